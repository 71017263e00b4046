// The coverage planner's cell grid drawn over the map: state (0 unknown, 1 free, 2 obstacle,
// 3 visited; core/coverage/knowledge_map.hpp) and visit counts, one pixel a cell in an ImageData
// that is scaled onto the map with the grid's own cell size. The grid's lower-left corner lies at
// `origin` in the map's local frame ([0, 0]: the map's own corner; a mission in an area plans on
// its planning window, whose origin the stream's snapshot gives); row 0 is the north row. Fed by the stream's binary frames (live_stream.js),
// or rebuilt from the rovers' paths for replay.
// On the map it is an OpenLayers image layer (issue 24, raster_overlay.js: one cell a block),
// drawn again by OL when the grid changed (sync, once a frame) or the view moved.

import { RasterOverlay } from './raster_overlay.js';
import { el } from './util.js';

// RGBA per state / visit count.
const FREE = [110, 170, 255, 70];
// Obstacles near-black violet: far from every visit colour (4+ visits is red), in hue and in
// lightness, so the two cannot be taken for each other (issue 27).
const OBSTACLE = [40, 24, 64, 230];
const VISITS = [
  [60, 205, 95, 170],   // 1 visit
  [245, 215, 55, 190],  // 2
  [250, 140, 40, 205],  // 3
  [235, 50, 60, 220],   // 4+
];
const LITTLE = new Uint8Array(new Uint32Array([0x01020304]).buffer)[0] === 4;
const pack = ([r, g, b, a]) => (LITTLE ? ((a << 24) | (b << 16) | (g << 8) | r) >>> 0 : ((r << 24) | (g << 16) | (b << 8) | a) >>> 0);
const FREE_PX = pack(FREE), OBSTACLE_PX = pack(OBSTACLE), VISIT_PX = VISITS.map(pack);

function colour(state, visits) {
  if (state === 1) return FREE_PX;
  if (state === 2) return OBSTACLE_PX;
  if (state === 3) return VISIT_PX[Math.min(Math.max(visits, 1), 4) - 1];
  return 0;
}

export class CoverageLayer {
  // view: the MapView whose OL map shows the grid, at zIndex among its layers.
  constructor(view, zIndex) {
    this.raster = new RasterOverlay(view, zIndex, 'coverage-grid',
      () => (this.ready ? { canvas: this.canvas, rect: [...this.origin, this.cols * this.cell, this.rows * this.cell] } : null));
    this.olLayer = this.raster.layer;
    this.rows = 0;
    this.cols = 0;
    this.cell = 1;
    this.origin = [0, 0];
    this.canvas = document.createElement('canvas');
    this.ctx = this.canvas.getContext('2d');
    this.image = null;
    this.pixels = null;
    this.state = null;
    this.visits = null;
    this.dirty = false;
    this.final = null;  // {state, visits} kept for replay
  }

  get ready() {
    return this.rows > 0;
  }

  reset(rows = 0, cols = 0, cell = 1, origin = [0, 0]) {
    this.rows = rows;
    this.cols = cols;
    this.cell = cell;
    this.origin = origin;
    this.final = null;
    if (!rows || !cols) {
      this.image = this.pixels = this.state = this.visits = null;
      return;
    }
    this.canvas.width = cols;
    this.canvas.height = rows;
    this.image = this.ctx.createImageData(cols, rows);
    this.pixels = new Uint32Array(this.image.data.buffer);
    this.state = new Uint8Array(rows * cols);
    this.visits = new Uint32Array(rows * cols);
    this.dirty = true;
  }

  // Binary frame (little-endian): u32 type, rows, cols, count, then the body. Returns the type.
  applyFrame(buffer) {
    const dv = new DataView(buffer);
    if (buffer.byteLength < 16) return 0;
    const type = dv.getUint32(0, true), rows = dv.getUint32(4, true), cols = dv.getUint32(8, true);
    const count = dv.getUint32(12, true);
    if (rows !== this.rows || cols !== this.cols) this.reset(rows, cols, this.cell, this.origin);
    if (type === 2) {
      const n = rows * cols;
      if (buffer.byteLength < 16 + 5 * n) return 0;
      this.state.set(new Uint8Array(buffer, 16, n));
      if ((16 + n) % 4 === 0 && LITTLE) {
        this.visits.set(new Uint32Array(buffer, 16 + n, n));
      } else {
        for (let i = 0; i < n; i++) this.visits[i] = dv.getUint32(16 + n + 4 * i, true);
      }
      const { state, visits, pixels } = this;
      for (let i = 0; i < n; i++) pixels[i] = colour(state[i], visits[i]);
    } else if (type === 1) {
      if (buffer.byteLength < 16 + 12 * count) return 0;
      const n = rows * cols;
      for (let k = 0, at = 16; k < count; k++, at += 12) {
        const i = dv.getUint32(at, true);
        if (i >= n) continue;
        const s = dv.getUint8(at + 4), v = dv.getUint32(at + 8, true);
        this.state[i] = s;
        this.visits[i] = v;
        this.pixels[i] = colour(s, v);
      }
    } else {
      return 0;
    }
    this.dirty = true;
    return type;
  }

  // --- replay: visits rebuilt from the paths up to a step, obstacles from the final grid ---
  keepFinal() {
    if (!this.ready) return;
    this.final = { state: this.state.slice(), visits: this.visits.slice() };
  }

  replayTo(paths, step) {
    if (!this.ready) return;
    if (!this.final) this.keepFinal();
    const { state, visits, pixels, rows, cols, cell } = this;
    const [ox, oy] = this.origin;
    const fs = this.final.state;
    for (let i = 0; i < fs.length; i++) {
      state[i] = fs[i] === 3 ? 1 : fs[i];
      visits[i] = 0;
    }
    for (const path of paths) {
      const last = Math.min(step, path.length - 1);
      for (let t = 0; t <= last; t++) {
        const c = Math.floor((path[t][0] - ox) / cell), r = rows - 1 - Math.floor((path[t][1] - oy) / cell);
        if (c < 0 || r < 0 || c >= cols || r >= rows) continue;
        const i = r * cols + c;
        state[i] = 3;
        visits[i]++;
      }
    }
    for (let i = 0; i < fs.length; i++) pixels[i] = colour(state[i], visits[i]);
    this.dirty = true;
  }

  restoreFinal() {
    if (!this.final) return;
    this.state.set(this.final.state);
    this.visits.set(this.final.visits);
    for (let i = 0; i < this.state.length; i++) this.pixels[i] = colour(this.state[i], this.visits[i]);
    this.dirty = true;
  }

  cellAt(x, y) {
    if (!this.ready) return null;
    const c = Math.floor((x - this.origin[0]) / this.cell), r = this.rows - 1 - Math.floor((y - this.origin[1]) / this.cell);
    if (c < 0 || r < 0 || c >= this.cols || r >= this.rows) return null;
    const i = r * this.cols + c;
    return { state: this.state[i], visits: this.visits[i] };
  }

  counts() {
    const n = [0, 0, 0, 0];
    if (this.state) for (let i = 0; i < this.state.length; i++) n[this.state[i] & 3]++;
    return n;
  }

  // Per frame: the layer list's opacity and visibility; a changed grid is painted again.
  sync(opacity, visible) {
    this.olLayer.setOpacity(opacity);
    this.olLayer.setVisible(visible && this.ready);
    if (this.ready && this.dirty) {
      this.ctx.putImageData(this.image, 0, 0);
      this.dirty = false;
      this.raster.changed();
    }
  }

  static legend() {
    const css = ([r, g, b, a]) => `rgba(${r},${g},${b},${(a / 255).toFixed(2)})`;
    const item = (c, label) => el('span', { class: 'legend-class' }, el('span', { class: 'swatch', style: `background:${css(c)}` }), label);
    return el('div', { class: 'legend-classes' },
      item(FREE, 'sensed free'), item(OBSTACLE, 'obstacle'),
      item(VISITS[0], '1 visit'), item(VISITS[1], '2 visits'), item(VISITS[2], '3 visits'), item(VISITS[3], '4+ visits'));
  }
}

export const CELL_STATE_NAMES = ['unknown', 'free', 'obstacle', 'visited'];
