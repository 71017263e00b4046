// The 2D map view in the local frame (x east, y north, metres from the map's lower-left corner).
// Two stacked surfaces:
// - an OpenLayers map underneath (issue 24): the raster layers as tiles of the server's tile API
//   (layer_stack.js adds them) in a custom projection of the map's local metres, the overlays
//   that are OL layers, a ScaleLine — and the pointer: pan and zoom are OL's own interactions
//   (DragPan with its inertia, MouseWheelZoom, PinchZoom, DoubleClickZoom in the pan tool only,
//   KeyboardPan and KeyboardZoom on the focused map), the view's resolutions bounded by the
//   map's tile grid (see setProjection).
// - a <canvas> on top, transparent to the pointer, for the overlays that are not OL layers: the
//   PDM editor's brush, a conflict's two versions, a zone set's history, the route profile's
//   marker; drawn when something asked for it; "base" overlay layers are composed into a cached
//   canvas only when the view changes.
// The view's state is mirrored here as cx, cy (the centre, metres) and scale (CSS pixels per
// metre), read by the canvas overlays and the tools; code that moves the view sets them and calls
// viewChanged(), which hands them to OL's view (its constraints apply).
// Tools (the mission form's rover placing, the PDM editor, zones, the mission area) get the
// pointer through ToolInput, an OL interaction under the tools' own Draw/Modify (which see a
// press first and keep it from DragPan when they take it) and over DragPan: a press a tool takes
// (its down() says true) is a drag of the tool's, not a pan; a press it leaves and releases
// without moving (OL's move tolerance, 1 px) is its click. DragPan pans from its first drag event
// on: the pixel or two before it are not panned (OL's way).
// Maps whose cells are not square (geographic grids: a cell's metres along y differ from x) need
// no stretching: the projection is in metres both ways and the tile grid's tiles are as tall as
// their cells make them (layer_stack.js), so features keep their shapes.

import OlMap from 'ol/Map.js';
import View from 'ol/View.js';
import ScaleLine from 'ol/control/ScaleLine.js';
import Projection from 'ol/proj/Projection.js';
import VectorLayer from 'ol/layer/Vector.js';
import VectorSource from 'ol/source/Vector.js';
import Interaction, { zoomByDelta } from 'ol/interaction/Interaction.js';
import { defaults as defaultInteractions } from 'ol/interaction/defaults.js';
import KeyboardPan from 'ol/interaction/KeyboardPan.js';
import KeyboardZoom from 'ol/interaction/KeyboardZoom.js';
import { primaryAction } from 'ol/events/condition.js';

let projections = 0;  // OL keeps projections by code: one code per map shown

// How far the view zooms: out to a quarter of the tile grid's coarsest zoom (the whole map in one
// tile), in to three zooms past its finest (itself two past one DEM cell a tile pixel: there a
// cell covers 32 CSS pixels, enough to read rover-scale ground on a 1 m map; issue 24 asks for at
// least 8; OL magnifies the finest tiles).
const ZOOMS_OUT = 2;
const ZOOMS_IN_PAST_GRID = 3;
const VIEW_EVENTS = ['change:center', 'change:resolution'];

// The tools' share of the pointer (see the header): one OL interaction, added right after the
// pan/zoom ones so that every interaction added later (Draw, Modify, Snap) sees a press first.
class ToolInput extends Interaction {
  constructor(view) {
    super();
    this.view = view;
    this.press = null;      // the press under way: {tool, consumed, moved}
    this.clickable = null;  // the press just released, when its click is the tool's
    this.toolsPressed = ['', ''];  // the tool (name) of the last two presses
  }

  handleEvent(e) {
    const v = this.view, oe = e.originalEvent;
    switch (e.type) {
      case 'pointerdown': {
        if (!primaryAction(e)) return true;
        const tool = v.tools[v.tool];
        this.toolsPressed = [this.toolsPressed[1], v.tool];
        const consumed = Boolean(tool && tool.down && tool.down(v.eventPoint(oe), oe) === true);
        this.press = { tool, consumed, moved: false };
        v.box.classList.toggle('dragging', !consumed);
        return !consumed;  // a press the tool took is no pan
      }
      case 'pointerdrag': {
        const d = this.press;
        if (!d) return true;
        d.moved = true;
        if (!d.consumed) return true;
        if (d.tool.move) d.tool.move(v.eventPoint(oe), oe);
        return false;
      }
      case 'pointerup': {
        const d = this.press;
        this.press = null;
        v.box.classList.remove('dragging');
        if (d && d.consumed && d.tool.up) d.tool.up(v.eventPoint(oe), oe, d.moved);
        // OL's click follows at once (when the pointer stayed within the move tolerance): the
        // tool's for a press that came here (not one a Draw or Modify took) and that it left.
        this.clickable = d && !d.consumed && d.tool && d.tool.click ? d.tool : null;
        return true;
      }
      case 'click': {
        const tool = this.clickable;
        this.clickable = null;
        if (tool) tool.click(v.eventPoint(oe), oe);
        return true;
      }
      case 'dblclick':
        // DoubleClickZoom (under this) zooms only where clicks mean nothing else: two quick
        // clicks placing rovers or PDM components are no zoom, the last of them neither when it
        // ended the tool (the last rover placed).
        return this.toolsPressed.every((t) => t === 'pan');
      default:
        return true;
    }
  }
}

export class MapView {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.base = document.createElement('canvas');
    this.baseCtx = this.base.getContext('2d');
    this.widthM = 100;
    this.heightM = 100;
    this.cx = 50;
    this.cy = 50;
    this.scale = 1;          // CSS pixels per metre
    this.padLeft = 0;        // CSS pixels covered by floating panels on the left
    this.padRight = 0;       // and on the right (the legend)
    this.padTop = 0;         // and on top (a conflict's panel, conflict_view.js)
    this.dpr = 1;
    this.cssW = 1;
    this.cssH = 1;
    this.layers = [];        // {id, order, base, draw(ctx, view)}
    this.viewVersion = 0;    // bumps on every pan/zoom/resize (screen-space caches key on it)
    this.baseDirty = true;
    this.pending = false;
    this.renderListeners = [];
    this.tools = {};         // name → {down, move, up, click, hover}
    this.tool = 'pan';
    this.panClicks = [];     // fn(p): a click (not a drag) in the pan tool (onPanClick)
    this.registerTool('pan', { click: (p) => this.panClicks.forEach((fn) => fn(p)) });
    this.hoverListeners = [];
    this.pushing = false;    // viewChanged() is setting OL's view: its change events are ours

    this.box = canvas.parentNode;
    this.olBox = document.createElement('div');
    this.olBox.className = 'map-ol';
    canvas.before(this.olBox);
    this.scaleBox = document.createElement('div');
    this.scaleBox.className = 'map-scale';
    canvas.after(this.scaleBox);
    // Pan and zoom: OL's, without rotation; the keys on the focused canvas (the map's keyboard
    // target), zooming at once (the tests and the +/- buttons read the new scale straight away).
    const interactions = defaultInteractions({ altShiftDragRotate: false, pinchRotate: false, shiftDragZoom: false, keyboard: false });
    for (const i of [new KeyboardPan(), new KeyboardZoom({ duration: 0 })]) interactions.push(i);
    this.input = new ToolInput(this);
    interactions.push(this.input);
    this.olMap = new OlMap({
      target: this.olBox, controls: [new ScaleLine({ target: this.scaleBox })], interactions, layers: [],
      keyboardEventTarget: canvas,
    });
    this.setProjection(100, 100);

    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
    this.bindPointer();
    this.bindKeys();
  }

  // --- geometry ---
  // A map of widthM × heightM metres with its tile grid (`tiles` of GET /api/maps/{id}): its
  // projection and view (setProjection), fitted in the window when `fit`.
  setExtent(widthM, heightM, fit = true, tiles = null) {
    this.widthM = widthM;
    this.heightM = heightM;
    this.setProjection(widthM, heightM, tiles);
    if (fit) this.fit();
    else this.invalidate(true);
  }

  // A new map: a projection in its local metres (the tile sources of that map take it), and a
  // view whose resolutions are those of the map's tile grid (`tiles`, GET /api/maps/{id}), ZOOMS_OUT
  // coarser and ZOOMS_IN_PAST_GRID finer; zooming between them is smooth.
  setProjection(widthM, heightM, tiles = null) {
    this.projection = new Projection({ code: `roverplan-local-${++projections}`, units: 'm', extent: [0, 0, widthM, heightM] });
    const grid = tiles && tiles.resolutions && tiles.resolutions.length ? tiles.resolutions : [Math.max(widthM, heightM) / 256];
    const resolutions = [];
    for (let k = ZOOMS_OUT; k > 0; k--) resolutions.push(grid[0] * 2 ** k);
    resolutions.push(...grid);
    for (let k = 1; k <= ZOOMS_IN_PAST_GRID; k++) resolutions.push(grid[grid.length - 1] / 2 ** k);
    if (this.olView) this.olView.un(VIEW_EVENTS, this.onOlChange);
    this.olView = new View({
      projection: this.projection, center: [this.cx, this.cy], resolution: 1 / this.scale, resolutions,
      constrainResolution: false, smoothResolutionConstraint: false, enableRotation: false,
    });
    this.onOlChange = () => this.pull();
    this.olView.on(VIEW_EVENTS, this.onOlChange);
    this.olMap.setView(this.olView);
    this.pull();
  }

  // The OL view moved (an interaction, an animation, a constraint): the mirror follows.
  pull() {
    const c = this.olView.getCenter(), r = this.olView.getResolution();
    if (!c || !r) return;
    this.cx = c[0];
    this.cy = c[1];
    this.scale = 1 / r;
    if (this.pushing) return;
    this.viewVersion++;
    this.invalidate(true);
  }

  // The mirror was set (cx, cy, scale): OL's view takes it, within its constraints.
  push() {
    const centre = [this.cx, this.cy], resolution = 1 / this.scale;  // the change events rewrite them
    this.pushing = true;
    try {
      this.olView.cancelAnimations();
      this.olView.setCenter(centre);
      this.olView.setResolution(resolution);
    } finally {
      this.pushing = false;
    }
    this.pull();
  }

  // An OL vector layer over the tiles (zIndex above theirs), for an overlay drawn as features.
  addVectorLayer(zIndex, options = {}) {
    const layer = new VectorLayer({ source: new VectorSource(), zIndex, updateWhileAnimating: true, updateWhileInteracting: true, ...options });
    this.olMap.addLayer(layer);
    return layer;
  }

  fit() {
    // Leave the floating panels (layers left, legend right) free when there is room for it.
    const pad = 16, left = this.cssW - this.padLeft > 400 ? this.padLeft : 0;
    // The legend's side is kept free whenever 300 px are left for the map: a smaller map beats
    // one whose east part lies under the legend (clicks there would land on the panel).
    const right = this.cssW - left - this.padRight >= 300 ? this.padRight : 0;
    const top = this.cssH - this.padTop > 200 ? this.padTop : 0;
    const w = this.cssW - 2 * pad - left - right, h = this.cssH - 2 * pad - top;
    this.scale = Math.max(1e-6, Math.min(w / this.widthM, h / this.heightM));
    this.cx = this.widthM / 2 - (left - right) / 2 / this.scale;
    this.cy = this.heightM / 2 + top / 2 / this.scale;
    this.viewChanged();
  }

  worldToScreen(x, y) {
    return [(x - this.cx) * this.scale + this.cssW / 2, (this.cy - y) * this.scale + this.cssH / 2];
  }

  screenToWorld(sx, sy) {
    return [(sx - this.cssW / 2) / this.scale + this.cx, this.cy - (sy - this.cssH / 2) / this.scale];
  }

  // Screen rectangle of a world rectangle [x0, x0+w] × [y0, y0+h].
  rectToScreen(x0, y0, w, h) {
    const [sx, sy] = this.worldToScreen(x0, y0 + h);
    return [sx, sy, w * this.scale, h * this.scale];
  }

  // One zoom step of the view (delta ±1: twice or half the scale), as OL's KeyboardZoom does it.
  zoomStep(delta) {
    zoomByDelta(this.olView, delta, undefined, 0);
  }

  viewChanged() {
    this.push();
    this.viewVersion++;
    this.invalidate(true);
  }

  resize() {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(r.width)), h = Math.max(1, Math.round(r.height));
    if (w === this.cssW && h === this.cssH && dpr === this.dpr) return;
    const first = this.cssW <= 1;
    this.cssW = w;
    this.cssH = h;
    this.dpr = dpr;
    for (const c of [this.canvas, this.base]) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    this.olMap.updateSize();
    if (first) this.fit();
    else this.viewChanged();
  }

  // --- layers and drawing ---
  addLayer(layer) {
    this.layers.push(layer);
    this.layers.sort((a, b) => a.order - b.order);
    this.invalidate(Boolean(layer.base));
  }

  invalidate(base = false) {
    if (base) this.baseDirty = true;
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame((t) => {
      this.pending = false;
      this.render(t);
    });
  }

  onRender(fn) {
    this.renderListeners.push(fn);
  }

  render(t = performance.now()) {
    const { ctx, dpr } = this;
    if (this.baseDirty) {
      this.baseDirty = false;
      const b = this.baseCtx;
      b.setTransform(1, 0, 0, 1, 0, 0);
      b.clearRect(0, 0, this.base.width, this.base.height);  // the tiles show through
      b.setTransform(dpr, 0, 0, dpr, 0, 0);
      // The map's outline, so an area without data still shows where the map is.
      const [fx, fy, fw, fh] = this.rectToScreen(0, 0, this.widthM, this.heightM);
      for (const l of this.layers) if (l.base) this.drawLayer(b, l);
      b.strokeStyle = '#56657a';
      b.lineWidth = 1;
      b.strokeRect(Math.round(fx) + 0.5, Math.round(fy) + 0.5, Math.round(fw), Math.round(fh));
    }
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.drawImage(this.base, 0, 0);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    for (const l of this.layers) if (!l.base) this.drawLayer(ctx, l);
    for (const fn of this.renderListeners) fn(t);
  }

  drawLayer(ctx, layer) {
    ctx.save();
    try {
      layer.draw(ctx, this);
    } catch (err) {
      console.warn(`layer ${layer.id}:`, err);
    }
    ctx.restore();
  }

  // The view as one picture (PNG export): the OL layers' canvases, then the overlays.
  snapshot() {
    this.olMap.renderSync();
    this.render();
    const out = document.createElement('canvas');
    out.width = this.canvas.width;
    out.height = this.canvas.height;
    const ctx = out.getContext('2d');
    ctx.fillStyle = '#0b0d10';
    ctx.fillRect(0, 0, out.width, out.height);
    const box = this.canvas.getBoundingClientRect();
    for (const c of this.olBox.querySelectorAll('.ol-layer canvas')) {
      if (!c.width || !c.height) continue;
      const r = c.getBoundingClientRect();
      const opacity = Number(c.parentNode.style.opacity || 1);
      ctx.globalAlpha = Number.isFinite(opacity) ? opacity : 1;
      ctx.drawImage(c, (r.left - box.left) * this.dpr, (r.top - box.top) * this.dpr, r.width * this.dpr, r.height * this.dpr);
    }
    ctx.globalAlpha = 1;
    ctx.drawImage(this.canvas, 0, 0);
    return out;
  }

  // --- interaction ---
  registerTool(name, handler) {
    this.tools[name] = handler;
  }

  setTool(name) {
    this.tool = name;
    for (const t of ['pdm', 'rovers', 'zones', 'area']) this.box.classList.toggle(`tool-${t}`, name === t);
  }

  // fn(p) on a click of the map in the pan tool: a press released within the move tolerance,
  // p = {sx, sy, x, y} (incident markers, a rover's trail).
  onPanClick(fn) {
    this.panClicks.push(fn);
  }

  onHover(fn) {
    this.hoverListeners.push(fn);
  }

  eventPoint(e) {
    const r = this.canvas.getBoundingClientRect();
    const sx = e.clientX - r.left, sy = e.clientY - r.top;
    const [x, y] = this.screenToWorld(sx, sy);
    return { sx, sy, x, y };
  }

  // What OL's interactions leave to the page: the focus (the map's keys), the pointer read-out and
  // the tools' hover.
  bindPointer() {
    const c = this.canvas, box = this.box;
    // The box holds the floating panels too: only the OL surface is the map.
    const onMap = (e) => this.olBox.contains(e.target);
    // A press on the OL viewport (not focusable) would take the focus from the canvas, whose keys
    // OL and the tools listen to: the canvas keeps it, and takes it on a press on the map.
    box.addEventListener('mousedown', (e) => {
      if (e.button === 0 && onMap(e)) e.preventDefault();
    });
    box.addEventListener('pointerdown', (e) => {
      if (e.button === 0 && onMap(e)) c.focus({ preventScroll: true });
    }, true);
    box.addEventListener('pointermove', (e) => {
      const pressed = this.input.press;
      if (!pressed && !onMap(e)) {
        for (const fn of this.hoverListeners) fn(null);  // over a panel: as if the pointer left
        return;
      }
      const p = this.eventPoint(e);
      for (const fn of this.hoverListeners) fn(p);
      if (pressed) return;
      const tool = this.tools[this.tool];
      if (tool && tool.hover) tool.hover(p);
    });
    box.addEventListener('pointerleave', () => {
      if (!this.input.press) for (const fn of this.hoverListeners) fn(null);
    });
  }

  // The keys OL's KeyboardPan/KeyboardZoom do not take: '0' fits the map; '=' and '_' (+ and −
  // without Shift) zoom too, and + and − work anywhere on the page that is not a text field.
  bindKeys() {
    const handle = (e) => {
      if (e.ctrlKey || e.metaKey || e.altKey) return false;
      switch (e.key) {
        case '+': case '=': this.zoomStep(1); return true;
        case '-': case '_': this.zoomStep(-1); return true;
        case '0': this.fit(); return true;
        default: return false;
      }
    };
    this.canvas.addEventListener('keydown', (e) => {
      if (e.defaultPrevented || e.key === '+' || e.key === '-') return;  // OL's KeyboardZoom has them
      if (handle(e)) e.preventDefault();
    });
    window.addEventListener('keydown', (e) => {
      if (e.target === this.canvas || e.defaultPrevented) return;
      const t = e.target;
      if (t && (t.tagName === 'INPUT' || t.tagName === 'SELECT' || t.tagName === 'TEXTAREA' || t.isContentEditable)) return;
      if (this.canvas.offsetParent === null) return;  // the 3D view is showing
      if (['+', '=', '-', '_'].includes(e.key) && handle(e)) e.preventDefault();
    });
  }
}
