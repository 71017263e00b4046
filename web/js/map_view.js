// The 2D map view in the local frame (x east, y north, metres from the map's lower-left corner),
// pan by dragging, zoom with the wheel or +/- keys. Two stacked surfaces:
// - an OpenLayers map underneath (issue 24): the raster layers as tiles of the server's tile API
//   (layer_stack.js adds them) in a custom projection of the map's local metres, and a ScaleLine.
//   This view owns pan and zoom and sets the OL view's centre and resolution; OL's interactions
//   get the pointer only for the tools that ask for it (below).
// - a <canvas> on top for the overlays that are not OL layers: the PDM editor's handles and
//   brush, a conflict's two versions, a zone set's history, the route profile's marker;
//   drawn every frame; "base" overlay layers are composed into a cached canvas only when the view
//   changes. Frames are drawn on requestAnimationFrame only when something asked for it.
// Maps whose cells are not square (geographic grids: metres along y differ from x) get a tile
// projection whose y is stretched to x-metres, and the OL surface is scaled back by CSS.
// Pointer input: the map box (the canvas's parent) listens, so a tool registered with `ol: true`
// (zones, mission area: OL's Draw/Modify/Snap) lets the pointer through the canvas to the OL
// viewport, whose interactions see it first; the same events then bubble here for pan and zoom.

import OlMap from 'ol/Map.js';
import View from 'ol/View.js';
import ScaleLine from 'ol/control/ScaleLine.js';
import Projection from 'ol/proj/Projection.js';
import VectorLayer from 'ol/layer/Vector.js';
import VectorSource from 'ol/source/Vector.js';
import { clamp } from './util.js';

let projections = 0;  // OL keeps projections by code: one code per map shown

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
    this.tools = {};         // name → {down, move, up, cursor}
    this.tool = 'pan';
    this.drag = null;
    this.hoverListeners = [];

    this.box = canvas.parentNode;  // takes the pointer (see the header)
    this.olBox = document.createElement('div');
    this.olBox.className = 'map-ol';
    canvas.before(this.olBox);
    this.scaleBox = document.createElement('div');
    this.scaleBox.className = 'map-scale';
    canvas.after(this.scaleBox);
    this.yStretch = 1;  // tile-projection units per metre along y (1: square cells)
    this.olMap = new OlMap({ target: this.olBox, controls: [new ScaleLine({ target: this.scaleBox })], interactions: [], layers: [] });
    this.setProjection(100, 100, 1);

    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
    this.bindPointer();
    this.bindKeys();
  }

  // --- geometry ---
  setExtent(widthM, heightM, fit = true) {
    this.widthM = widthM;
    this.heightM = heightM;
    if (fit) this.fit();
    else this.invalidate(true);
  }

  // A new map: a projection in its local metres (`yStretch` = cell width / cell height, 1 for
  // square cells), returned for the tile sources of that map.
  setProjection(widthM, heightM, yStretch = 1) {
    this.yStretch = yStretch > 0 && Number.isFinite(yStretch) ? yStretch : 1;
    this.projection = new Projection({
      code: `roverplan-local-${++projections}`, units: 'm', extent: [0, 0, widthM, heightM * this.yStretch],
    });
    this.olView = new View({
      projection: this.projection, center: [this.cx, this.cy * this.yStretch], resolution: 1 / this.scale,
      minResolution: 1e-6, maxResolution: 1e7, constrainResolution: false, smoothResolutionConstraint: false,
      enableRotation: false,
    });
    this.olMap.setView(this.olView);
    this.syncOl();
    return this.projection;
  }

  // The OL view follows this one: same centre, metres per CSS pixel along x.
  syncOl() {
    if (!this.olView) return;
    const k = this.yStretch;
    // The OL surface is k times as tall and squeezed back by CSS, so its y units land on metres.
    this.olBox.style.height = `${this.cssH * k}px`;
    this.olBox.style.top = `${(this.cssH - this.cssH * k) / 2}px`;
    this.olBox.style.transform = k === 1 ? '' : `scaleY(${1 / k})`;
    this.olMap.updateSize();
    this.olView.setCenter([this.cx, this.cy * k]);
    this.olView.setResolution(1 / this.scale);
  }

  // Local metres ↔ the OL projection's coordinates (y stretched on maps with non-square cells).
  toOl([x, y]) {
    return [x, y * this.yStretch];
  }

  fromOl([x, y]) {
    return [x, y / this.yStretch];
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

  zoomAt(factor, sx = this.cssW / 2, sy = this.cssH / 2) {
    const [wx, wy] = this.screenToWorld(sx, sy);
    const fitScale = Math.min(this.cssW / this.widthM, this.cssH / this.heightM);
    this.scale = clamp(this.scale * factor, fitScale / 8, fitScale * 400);
    // Keep the world point under the cursor where it was.
    this.cx = wx - (sx - this.cssW / 2) / this.scale;
    this.cy = wy + (sy - this.cssH / 2) / this.scale;
    this.viewChanged();
  }

  panBy(dx, dy) {
    this.cx -= dx / this.scale;
    this.cy += dy / this.scale;
    this.viewChanged();
  }

  viewChanged() {
    this.viewVersion++;
    this.syncOl();
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
    this.olBox.style.width = `${w}px`;
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
      const r = c.getBoundingClientRect();  // CSS transforms included (the y stretch too)
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
    // An OL tool: the canvas lets the pointer through to the OL viewport (app.css .ol-input).
    this.box.classList.toggle('ol-input', Boolean(this.tools[name]?.ol));
    this.canvas.classList.toggle('tool-pdm', name === 'pdm');
    this.canvas.classList.toggle('tool-rovers', name === 'rovers');
    this.canvas.classList.toggle('tool-zones', name === 'zones');
    this.canvas.classList.toggle('tool-area', name === 'area');
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

  bindPointer() {
    const c = this.canvas, box = this.box;
    // The box holds the floating panels too: only the canvas and the OL surface are the map.
    const onMap = (e) => e.target === c || this.olBox.contains(e.target);
    // A press on the OL viewport (not focusable) would take the focus from the canvas, whose keys
    // the tools listen to: the canvas keeps it.
    box.addEventListener('mousedown', (e) => {
      if (e.button === 0 && this.olBox.contains(e.target)) e.preventDefault();
    });
    box.addEventListener('pointerdown', (e) => {
      if (e.button !== 0 || !onMap(e)) return;
      c.focus({ preventScroll: true });
      const p = this.eventPoint(e);
      const tool = this.tools[this.tool];
      let consumed = false;
      if (tool && tool.down) consumed = tool.down(p, e) === true;
      this.drag = { consumed, tool, lastX: p.sx, lastY: p.sy, startX: p.sx, startY: p.sy, moved: false };
      e.target.setPointerCapture(e.pointerId);
      if (!consumed) c.classList.add('dragging');
    });
    box.addEventListener('pointermove', (e) => {
      if (!this.drag && !onMap(e)) {
        for (const fn of this.hoverListeners) fn(null);  // over a panel: as if the pointer left
        return;
      }
      const p = this.eventPoint(e);
      for (const fn of this.hoverListeners) fn(p);
      const d = this.drag;
      if (!d) {
        const tool = this.tools[this.tool];
        if (tool && tool.hover) tool.hover(p);
        return;
      }
      if (Math.hypot(p.sx - d.startX, p.sy - d.startY) > 3) d.moved = true;
      if (d.consumed) {
        if (d.tool.move) d.tool.move(p, e);
      } else if (d.moved) {
        this.panBy(p.sx - d.lastX, p.sy - d.lastY);
      }
      d.lastX = p.sx;
      d.lastY = p.sy;
    });
    const end = (e) => {
      const d = this.drag;
      if (!d) return;
      this.drag = null;
      c.classList.remove('dragging');
      const p = this.eventPoint(e);
      if (d.consumed) {
        if (d.tool.up) d.tool.up(p, e, d.moved);
      } else if (!d.moved && d.tool && d.tool.click && e.type === 'pointerup') {
        d.tool.click(p, e);
      }
    };
    box.addEventListener('pointerup', end);
    box.addEventListener('pointercancel', end);
    box.addEventListener('pointerleave', () => {
      if (!this.drag) for (const fn of this.hoverListeners) fn(null);
    });
    box.addEventListener('wheel', (e) => {
      if (!onMap(e)) return;
      e.preventDefault();
      const p = this.eventPoint(e);
      const delta = e.deltaMode === 1 ? e.deltaY * 16 : e.deltaY;
      this.zoomAt(Math.exp(-delta * 0.0015), p.sx, p.sy);
    }, { passive: false });
  }

  bindKeys() {
    const handle = (e) => {
      if (e.ctrlKey || e.metaKey || e.altKey) return false;
      const step = 60;
      switch (e.key) {
        case '+': case '=': this.zoomAt(1.25); return true;
        case '-': case '_': this.zoomAt(0.8); return true;
        case '0': this.fit(); return true;
        case 'ArrowLeft': this.panBy(step, 0); return true;
        case 'ArrowRight': this.panBy(-step, 0); return true;
        case 'ArrowUp': this.panBy(0, step); return true;
        case 'ArrowDown': this.panBy(0, -step); return true;
        default: return false;
      }
    };
    this.canvas.addEventListener('keydown', (e) => {
      if (handle(e)) e.preventDefault();
    });
    // +/- also work anywhere on the page that is not a text field.
    window.addEventListener('keydown', (e) => {
      if (e.target === this.canvas || e.defaultPrevented) return;
      const t = e.target;
      if (t && (t.tagName === 'INPUT' || t.tagName === 'SELECT' || t.tagName === 'TEXTAREA' || t.isContentEditable)) return;
      if (this.canvas.offsetParent === null) return;  // the 3D view is showing
      if (['+', '=', '-', '_'].includes(e.key) && handle(e)) e.preventDefault();
    });
  }
}
