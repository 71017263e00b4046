// The mission area drawn on the map (issue 24: "the operator draws a rectangle on a big map").
// The mission form's area field (x0, y0, x1, y1 in the map's local metres, sent as area.bbox) and
// the map's outline of it stay in step: "draw area" arms tool 'area', a drag on the map draws the
// rectangle and fills the field (rounded to the map's cells), typing in the field moves the
// outline, "clear" empties both, Escape drops a drawing in progress. The drag is OpenLayers' Draw
// (a freehand box whose corners snap to the map's cells), the outlines are features of an OL vector
// layer over the tiles (issue 24), updated when what they show changes.
// The area of the mission shown (GET /api/missions/{id} `area`, bbox or polygon) is outlined too.
// The note under the field says when the map is too big to plan whole (the server's 400
// missing_field area).

import Draw from 'ol/interaction/Draw.js';
import Feature from 'ol/Feature.js';
import Polygon from 'ol/geom/Polygon.js';
import Point from 'ol/geom/Point.js';
import { Fill, Stroke, Style, Text } from 'ol/style.js';
import { state } from './state.js';
import { history } from './undo_stack.js';
import { $ } from './util.js';

const FORM_COLOUR = '#ffd34d';
const MISSION_COLOUR = '#7fdbff';
// The server plans a map whole up to this many cells (mission_service's wholeMapCells).
const WHOLE_MAP_CELLS = 4096 * 4096;

// "x0, y0, x1, y1" → [x0, y0, x1, y1] ordered, or null when it is not four finite numbers.
export function parseBbox(text) {
  const v = text.trim().split(/[\s,]+/).filter(Boolean).map(Number);
  if (v.length !== 4 || !v.every(Number.isFinite)) return null;
  return [Math.min(v[0], v[2]), Math.min(v[1], v[3]), Math.max(v[0], v[2]), Math.max(v[1], v[3])];
}

export class AreaTool {
  constructor({ view, missionView, form }) {
    this.view = view;
    this.missionView = missionView;
    this.form = form;         // the MissionForm: its showStarts says the Mission tab is open
    this.outline = null;      // the field's rectangle [x0, y0, x1, y1], or null
    this.olLayer = view.addVectorLayer(48, { style: (f) => outlineStyle(f.get('colour'), f.get('dash'), f.get('label')) });
    this.shown = '';          // what the outlines show now (they are rebuilt when it changes)
    view.onRender(() => this.render());
    this.draw = null;         // OL's Draw while the tool is armed (see arm)
    // A press is the drag of a rectangle: freehand Draw takes it before the map's DragPan sees it;
    // one that starts off the map draws from the map's edge.
    view.registerTool('area', {});
    $('m-area').addEventListener('input', () => this.fromField());
    // Typing: one undo step per committed change of the field.
    this.committed = '';
    $('m-area').addEventListener('change', () => {
      history.push(this, 'type the area', { text: this.committed }, this.snapshot());
      this.committed = $('m-area').value;
    });
    $('m-area-draw').addEventListener('click', () => state.setTool(state.tool === 'area' ? 'pan' : 'area'));
    $('m-area-clear').addEventListener('click', () => this.clear(true));
    // Escape wherever the focus is (the canvas after a press, the button after arming it).
    window.addEventListener('keydown', (e) => {
      if (e.key !== 'Escape' || state.tool !== 'area') return;
      this.cancel();
      e.preventDefault();
    });
    state.on('tool', (tool) => {
      $('m-area-draw').setAttribute('aria-pressed', String(tool === 'area'));
      $('m-area-draw').textContent = tool === 'area' ? 'drawing… (drag on map)' : 'draw area';
      this.arm(tool === 'area');
      view.invalidate();
    });
    // Another map: the field's rectangle belonged to the last one.
    state.on('map', (map) => {
      this.clear();
      this.renderNote(map);
    });
    this.renderNote(null);
  }

  // --- the field and the outline ---
  fromField() {
    this.outline = parseBbox($('m-area').value);
    $('m-area').classList.remove('invalid');
    this.render();
  }

  setBbox(b) {
    // Not fmt(): its thousands separators are commas. Micrometres hide the float noise of k × cell.
    $('m-area').value = b.map((v) => String(Number(v.toFixed(6)))).join(', ');
    this.committed = $('m-area').value;
    this.fromField();
  }

  // --- undo (undo_stack.js): the area field's text ---
  snapshot() {
    return { text: $('m-area').value };
  }

  restore(s) {
    $('m-area').value = s.text;
    this.committed = s.text;
    this.fromField();
  }

  // `record`: the "clear" button (a step of the undo history); a new map clears without one.
  clear(record = false) {
    const before = this.snapshot();
    $('m-area').value = '';
    this.committed = '';
    if (state.tool === 'area') state.setTool('pan');
    this.fromField();
    if (record) history.push(this, 'clear the area', before, this.snapshot());
  }

  // Escape: the drawing in progress is dropped, the field keeps what it had.
  cancel() {
    state.setTool('pan');
  }

  // A fresh Draw each time the tool is armed, removed when it is not: one turned off in the middle
  // of a drag (Escape) would still count that press as under way at the next one.
  arm(on) {
    if (this.draw) {
      this.draw.abortDrawing();
      this.view.olMap.removeInteraction(this.draw);
      this.draw = null;
    }
    if (!on) return;
    this.draw = new Draw({
      type: 'Circle', freehand: true,
      geometryFunction: (coords, geometry) => this.box(coords, geometry),
      style: outlineStyle(FORM_COLOUR, [6, 4], null),
    });
    this.draw.on('drawend', (e) => this.drawn(e.feature.getGeometry()));
    this.view.olMap.addInteraction(this.draw);
  }

  renderNote(map) {
    const note = $('m-area-note');
    if (!map) return (note.textContent = '');
    const cells = map.rows * map.cols;
    const big = cells > WHOLE_MAP_CELLS;
    note.classList.toggle('warn', big);
    note.textContent = big
      ? `This map is ${map.cols} × ${map.rows} cells, more than a mission plans whole (4096 × 4096): draw or type an area (its window at most 4096 × 4096 cells).`
      : `Optional on this map (${map.cols} × ${map.rows} cells): without an area the whole map is planned.`;
  }

  // --- drawing: a point on the map, snapped to the cell corners ---
  onMap([x, y]) {
    const m = state.map;
    return Boolean(m) && x >= 0 && y >= 0 && x <= m.width_m && y <= m.height_m;
  }

  snap([px, py]) {
    const m = state.map;
    const cw = m.cell_size_m, ch = m.cell_height_m ?? m.cell_size_m;
    const x = Math.min(Math.max(px, 0), m.width_m), y = Math.min(Math.max(py, 0), m.height_m);
    // Rounded to whole cells, and not past the map's edge by the rounding.
    return [Math.min(Math.round(x / cw) * cw, m.width_m), Math.min(Math.round(y / ch) * ch, m.height_m)];
  }

  // Draw's geometry: the rectangle between the press and the pointer, corners on the cells.
  box(coords, geometry) {
    const v = this.view;
    const a = state.map ? this.snap(coords[0]) : [0, 0];
    const b = state.map ? this.snap(coords[coords.length - 1]) : a;
    const ring = [corners([Math.min(a[0], b[0]), Math.min(a[1], b[1]), Math.max(a[0], b[0]), Math.max(a[1], b[1])])];
    ring[0].push(ring[0][0]);
    if (!geometry) return new Polygon(ring);
    geometry.setCoordinates(ring);
    return geometry;
  }

  // Draw let go of a rectangle: the field gets it (a click without a drag draws nothing and the
  // tool stays armed for the drag).
  drawn(geometry) {
    if (!state.map) return;
    const [x0, y0, x1, y1] = geometry.getExtent();
    const bbox = [this.snap([x0, y0]), this.snap([x1, y1])].flat();
    if (bbox[2] <= bbox[0] || bbox[3] <= bbox[1]) return;
    const before = this.snapshot();
    this.setBbox([bbox[0], bbox[1], bbox[2], bbox[3]]);
    history.push(this, 'draw the area', before, this.snapshot());
    this.form.clearFieldError('area');
    state.setTool('pan');  // Draw has dropped its sketch already: turning it off loses nothing
  }

  // --- the outlines ---
  // The shown mission's area: GET /api/missions/{id} keeps the request as `spec` (result.json has
  // it as `area`); null for a mission on the whole map.
  missionArea() {
    const m = this.missionView.mission;
    return m ? m.area ?? m.spec?.area ?? null : null;
  }

  // The outlines as features, rebuilt only when what they show changed (checked per frame).
  render() {
    const area = this.missionArea();
    const mission = area && state.map && this.missionView.mission.map === state.map.id ? (area.bbox ? corners(area.bbox) : area.polygon) : null;
    const form = this.outline && this.form.showStarts ? corners(this.outline) : null;
    const key = JSON.stringify([mission, form, state.map?.id]);
    if (key === this.shown) return;
    this.shown = key;
    const source = this.olLayer.getSource();
    source.clear();
    const feature = (ring, colour, dash, label) => {
      const coords = [[...ring, ring[0]]];
      source.addFeature(new Feature({ geometry: new Polygon(coords), colour, dash, label }));
    };
    if (mission) feature(mission, MISSION_COLOUR, [2, 4], 'mission area');
    if (form) feature(form, FORM_COLOUR, [6, 4], 'area');
  }
}

// An outline: a dark halo under a dashed line in `colour`, and `label` at its top-left corner —
// above it for the form's area, below it (inside) for the mission's, so both read when they meet.
const styles = new Map();
function outlineStyle(colour, dash, label) {
  const key = `${colour} ${dash} ${label}`;
  if (styles.has(key)) return styles.get(key);
  const out = [
    new Style({ stroke: new Stroke({ color: 'rgba(0, 0, 0, 0.7)', width: 3.5 }) }),
    new Style({ stroke: new Stroke({ color: colour, width: 2, lineDash: dash }) }),
  ];
  if (label) {
    out.push(new Style({
      geometry: (f) => {
        const [x0, , , y1] = f.getGeometry().getExtent();
        return new Point([x0, y1]);
      },
      text: new Text({
        text: label, font: '11px system-ui, sans-serif', textAlign: 'left',
        textBaseline: label === 'area' ? 'bottom' : 'top', offsetX: 3, offsetY: label === 'area' ? -3 : 4,
        fill: new Fill({ color: colour }), stroke: new Stroke({ color: 'rgba(0, 0, 0, 0.6)', width: 2 }),
      }),
    }));
  }
  styles.set(key, out);
  return out;
}
function corners([x0, y0, x1, y1]) {
  return [[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
}
