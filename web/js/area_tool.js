// The mission area drawn on the map (issue 24: "the operator draws a rectangle on a big map").
// The mission form's area field (x0, y0, x1, y1 in the map's local metres, sent as area.bbox) and
// the map's outline of it stay in step: "draw area" arms tool 'area', a drag on the map draws the
// rectangle and fills the field (rounded to the map's cells), typing in the field moves the
// outline, "clear" empties both, Escape drops a drawing in progress. A tool on the overlay canvas
// like the zone editor (zones.js): the canvas above the OpenLayers tiles takes the pointer.
// The area of the mission shown (GET /api/missions/{id} `area`, bbox or polygon) is outlined too.
// The note under the field says when the map is too big to plan whole (the server's 400
// missing_field area).

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
    this.drag = null;         // {x, y, x1, y1}: the rectangle being drawn
    view.addLayer({ id: 'mission-area', order: 48, draw: (ctx, v) => this.draw(ctx, v) });
    view.registerTool('area', {
      down: (p) => this.down(p),
      move: (p) => this.move(p),
      up: (p) => this.up(p),
    });
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
      if (tool !== 'area') this.drag = null;
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
    this.view.invalidate();
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
    this.drag = null;
    if (state.tool === 'area') state.setTool('pan');
    this.fromField();
    if (record) history.push(this, 'clear the area', before, this.snapshot());
  }

  // Escape: the drawing in progress is dropped, the field keeps what it had.
  cancel() {
    this.drag = null;
    state.setTool('pan');
    this.view.invalidate();
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
  snap(p) {
    const m = state.map;
    const cw = m.cell_size_m, ch = m.cell_height_m ?? m.cell_size_m;
    const x = Math.min(Math.max(p.x, 0), m.width_m), y = Math.min(Math.max(p.y, 0), m.height_m);
    // Rounded to whole cells, and not past the map's edge by the rounding.
    return [Math.min(Math.round(x / cw) * cw, m.width_m), Math.min(Math.round(y / ch) * ch, m.height_m)];
  }

  down(p) {
    const m = state.map;
    if (!m || p.x < 0 || p.y < 0 || p.x > m.width_m || p.y > m.height_m) return false;  // pans
    const [x, y] = this.snap(p);
    this.drag = { x, y, x1: x, y1: y };
    return true;
  }

  move(p) {
    if (!this.drag || !state.map) return;
    [this.drag.x1, this.drag.y1] = this.snap(p);
    this.view.invalidate();
  }

  up(p) {
    const d = this.drag;
    if (!d || !state.map) return;  // cancelled with Escape meanwhile
    this.move(p);
    this.drag = null;
    // A click without a drag draws nothing; the tool stays armed for the drag.
    if (d.x1 === d.x || d.y1 === d.y) return this.view.invalidate();
    const before = this.snapshot();
    this.setBbox([Math.min(d.x, d.x1), Math.min(d.y, d.y1), Math.max(d.x, d.x1), Math.max(d.y, d.y1)]);
    history.push(this, 'draw the area', before, this.snapshot());
    this.form.clearFieldError('area');
    state.setTool('pan');
  }

  // --- the overlay ---
  // The shown mission's area: GET /api/missions/{id} keeps the request as `spec` (result.json has
  // it as `area`); null for a mission on the whole map.
  missionArea() {
    const m = this.missionView.mission;
    return m ? m.area ?? m.spec?.area ?? null : null;
  }

  draw(ctx, view) {
    const area = this.missionArea();
    if (area && state.map && this.missionView.mission.map === state.map.id) {
      const ring = area.bbox ? corners(area.bbox) : area.polygon;
      if (ring) this.stroke(ctx, view, ring, MISSION_COLOUR, [2, 4], 'mission area');
    }
    if (this.drag) {
      this.stroke(ctx, view, corners([this.drag.x, this.drag.y, this.drag.x1, this.drag.y1]), FORM_COLOUR, [6, 4], null);
    } else if (this.outline && this.form.showStarts) {
      this.stroke(ctx, view, corners(this.outline), FORM_COLOUR, [6, 4], 'area');
    }
  }

  stroke(ctx, view, ring, colour, dash, label) {
    ctx.beginPath();
    ring.forEach(([x, y], i) => {
      const [sx, sy] = view.worldToScreen(x, y);
      if (i === 0) ctx.moveTo(sx, sy);
      else ctx.lineTo(sx, sy);
    });
    ctx.closePath();
    ctx.setLineDash([]);
    ctx.strokeStyle = 'rgba(0, 0, 0, 0.7)';
    ctx.lineWidth = 3.5;
    ctx.stroke();
    ctx.setLineDash(dash);
    ctx.strokeStyle = colour;
    ctx.lineWidth = 2;
    ctx.stroke();
    ctx.setLineDash([]);
    if (!label) return;
    // The label above the ring's top-left corner.
    let lx = Infinity, ly = -Infinity;
    for (const [x, y] of ring) {
      lx = Math.min(lx, x);
      ly = Math.max(ly, y);
    }
    const [sx, sy] = view.worldToScreen(lx, ly);
    ctx.font = '11px system-ui, sans-serif';
    ctx.textBaseline = 'bottom';
    ctx.fillStyle = 'rgba(0, 0, 0, 0.6)';
    ctx.fillText(label, sx + 3, sy - 2);
    ctx.fillStyle = colour;
    ctx.fillText(label, sx + 2, sy - 3);
  }
}

function corners([x0, y0, x1, y1]) {
  return [[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
}
