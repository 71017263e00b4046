// The map's layers: server PNG rasters (elevation, hillshade, slope, traversability, PDM) drawn
// into the map view's base, plus overlay layers other modules register (coverage, trails). Each
// layer has a visibility checkbox and an opacity slider; the legend panel shows the legend of each
// visible layer (the server PNGs carry theirs as a strip under the map: it is cropped off the
// drawing and shown here). Also loads the float32 rasters behind the cursor readout.

import { fetchF32, fetchImage, layerUrl } from './api.js';
import { counters, state } from './state.js';
import { $, el, fmt } from './util.js';

const OVERVIEW = 1024;               // PNG overview size for big maps
const LEGEND_SIZE = 200;             // legends come from a PNG this wide, shown 1:1 (readable)
const MAX_F32_CELLS = 25_000_000;    // larger maps: no per-cell readout (100 MB a layer)
const CLASS_NAMES = ['traversable', 'high risk', 'impassable', 'nodata'];

// The size of the map part of a server PNG (maps/render.cpp displaySize).
function displaySize(rows, cols, max) {
  if (max <= 0 || Math.max(rows, cols) <= max) return [rows, cols];
  if (cols >= rows) return [Math.min(max, Math.max(1, Math.round((rows * max) / cols))), max];
  return [max, Math.min(max, Math.max(1, Math.round((cols * max) / rows)))];
}

export class LayerStack {
  constructor(view) {
    this.view = view;
    this.layers = [];
    this.rasters = {};     // elevation, slope, traversability, pdm → {rows, cols, cellW, cellH, data}
    this.generation = 0;   // bumps per map so late loads of an old map are dropped
    this.aborter = new AbortController();  // cancels the old map's loads in flight
    const png = (id, label, visible, opacity, order) => ({
      id, label, kind: 'png', visible, opacity, order, image: null, loading: false, error: '', crop: null, legendCanvas: null,
    });
    for (const l of [
      png('elevation', 'elevation', true, 1, 10),
      png('hillshade', 'hillshade', false, 0.6, 11),
      png('slope', 'slope', false, 0.7, 12),
      png('traversability', 'traversability', false, 0.6, 13),
      png('pdm', 'PDM (saved)', false, 0.7, 14),
    ]) this.add(l);
    this.listNode = $('layer-list');
    this.legendNode = $('legend-list');
  }

  add(layer) {
    this.layers.push(layer);
    if (layer.kind === 'png') {
      this.view.addLayer({ id: layer.id, order: layer.order, base: true, draw: (ctx, v) => this.drawPng(ctx, v, layer) });
    }
    this.renderControls();
  }

  // An overlay layer drawn by another module: {id, label, visible, opacity, legend(): Node}.
  addOverlay(layer) {
    this.add({ kind: 'overlay', ...layer });
    return this.get(layer.id);
  }

  get(id) {
    return this.layers.find((l) => l.id === id);
  }

  isVisible(id) {
    const l = this.get(id);
    return Boolean(l && l.visible);
  }

  setVisible(id, visible) {
    const l = this.get(id);
    if (!l || l.visible === visible) return;
    l.visible = visible;
    if (visible && l.kind === 'png') this.loadPng(l);
    this.renderControls();
    this.view.invalidate(true);
  }

  // --- the selected map ---
  async setMap(map) {
    this.generation++;
    this.aborter.abort();
    this.aborter = new AbortController();
    for (const l of this.layers) {
      if (l.kind !== 'png') continue;
      if (l.image && l.image.close) l.image.close();
      l.image = null;
      l.error = '';
      l.loading = false;
      l.legendCanvas = null;
    }
    this.rasters = {};
    this.renderControls();
    if (!map) return;
    const loads = this.layers.filter((l) => l.kind === 'png' && l.visible).map((l) => this.loadPng(l));
    this.loadRasters(map);
    await Promise.all(loads);
  }

  setPdm(pdmId) {
    const l = this.get('pdm');
    if (l.image && l.image.close) l.image.close();
    l.image = null;
    l.error = '';
    l.legendCanvas = null;
    delete this.rasters.pdm;
    if (pdmId && state.map) {
      l.visible = true;
      this.loadPng(l);
      this.loadRaster(state.map, 'pdm', pdmId);
    }
    this.renderControls();
    this.view.invalidate(true);
  }

  async loadPng(layer) {
    const map = state.map;
    if (!map || layer.image || layer.loading) return;
    if (layer.id === 'pdm' && !state.pdmId) {
      layer.error = 'no PDM selected';
      this.renderControls();
      return;
    }
    const gen = this.generation;
    const max = Math.max(map.rows, map.cols) > OVERVIEW ? OVERVIEW : 0;
    const pdm = layer.id === 'pdm' ? state.pdmId : '';
    layer.loading = true;
    this.renderControls();
    try {
      const image = await fetchImage(layerUrl(map.id, layer.id, 'png', { max, pdm }), this.aborter.signal);
      if (gen !== this.generation || (layer.id === 'pdm' && pdm !== state.pdmId)) {
        image.close();
        return;
      }
      const [outRows, outCols] = displaySize(map.rows, map.cols, max);
      layer.image = image;
      layer.crop = { rows: Math.min(outRows, image.height), cols: Math.min(outCols, image.width) };
      layer.error = '';
      counters.layersLoaded.push(layer.id);
      this.loadLegend(layer, map, pdm, image, gen);
    } catch (err) {
      if (gen === this.generation && err.code !== 'aborted') layer.error = err.message || String(err);
    } finally {
      layer.loading = false;
      if (gen === this.generation) {
        this.renderControls();
        this.view.invalidate(true);
      }
    }
  }

  // The legend strip the server draws under the map in its PNG. A strip as wide as a big map
  // would be unreadable once shrunk into the legend panel, so for wide images it is taken from
  // the server's small overview of the same layer, whose legend is laid out for ~200 px.
  async loadLegend(layer, map, pdm, image, gen) {
    try {
      let source = image, max = Math.max(map.rows, map.cols) > OVERVIEW ? OVERVIEW : 0;
      if (image.width > LEGEND_SIZE * 1.3) {
        max = LEGEND_SIZE;
        source = await fetchImage(layerUrl(map.id, layer.id, 'png', { max, pdm }), this.aborter.signal);
      }
      if (gen !== this.generation || layer.image !== image) return;
      const [mapRows] = displaySize(map.rows, map.cols, max);
      layer.legendCanvas = this.legendFromStrip(source, mapRows);
      if (source !== image) source.close();
      this.renderLegends();
    } catch (err) {
      if (err.code !== 'aborted') console.warn(`legend of ${layer.id}: ${err.message}`);
    }
  }

  legendFromStrip(image, mapRows) {
    const h = image.height - mapRows;
    if (h <= 0) return null;
    const c = document.createElement('canvas');
    c.width = image.width;
    c.height = h;
    c.getContext('2d').drawImage(image, 0, mapRows, image.width, h, 0, 0, image.width, h);
    c.style.width = `${Math.min(image.width, 220)}px`;
    return c;
  }

  drawPng(ctx, view, layer) {
    if (!layer.visible || !layer.image || !state.map) return;
    const map = state.map;
    const [sx, sy, sw, sh] = view.rectToScreen(0, 0, map.width_m, map.height_m);
    ctx.globalAlpha = layer.opacity;
    // Crisp cells when zoomed far in, smooth otherwise.
    ctx.imageSmoothingEnabled = sw / layer.crop.cols < 2;
    ctx.drawImage(layer.image, 0, 0, layer.crop.cols, layer.crop.rows, sx, sy, sw, sh);
  }

  // --- float32 rasters for the cursor readout ---
  loadRasters(map) {
    for (const name of ['elevation', 'slope', 'traversability']) this.loadRaster(map, name);
    if (state.pdmId) this.loadRaster(map, 'pdm', state.pdmId);
  }

  async loadRaster(map, name, pdm = '') {
    if (map.rows * map.cols > MAX_F32_CELLS) return;
    const gen = this.generation;
    try {
      const r = await fetchF32(layerUrl(map.id, name, 'f32', { pdm }), this.aborter.signal);
      if (gen !== this.generation || (name === 'pdm' && pdm !== state.pdmId)) return;
      this.rasters[name] = r;
      if (name === 'elevation') state.emit('elevation', r);
    } catch (err) {
      if (err.code !== 'aborted') console.warn(`readout layer ${name}: ${err.message}`);
    }
  }

  sample(name, x, y) {
    const r = this.rasters[name];
    if (!r) return undefined;
    const col = Math.floor(x / r.cellW), row = r.rows - 1 - Math.floor(y / r.cellH);
    if (col < 0 || row < 0 || col >= r.cols || row >= r.rows) return undefined;
    return r.data[row * r.cols + col];
  }

  // "x … y … | elevation … | slope … | class … | PDM …"
  readout(x, y) {
    const map = state.map;
    const parts = [`x ${x.toFixed(2)} m`, `y ${y.toFixed(2)} m`];
    if (!map || x < 0 || y < 0 || x > map.width_m || y > map.height_m) {
      parts.push('outside the map');
      return parts.join('   ');
    }
    const z = this.sample('elevation', x, y);
    if (z !== undefined) parts.push(`elevation ${Number.isNaN(z) ? 'nodata' : `${z.toFixed(2)} m`}`);
    const s = this.sample('slope', x, y);
    if (s !== undefined) parts.push(`slope ${Number.isNaN(s) ? 'nodata' : `${s.toFixed(1)}°`}`);
    const c = this.sample('traversability', x, y);
    if (c !== undefined) parts.push(`class ${Number.isNaN(c) ? 'nodata' : CLASS_NAMES[Math.round(c)] || c}`);
    const p = this.sample('pdm', x, y);
    if (p !== undefined) parts.push(`PDM ${Number.isNaN(p) ? 'nodata' : fmt(p)}`);
    return parts.join('   ');
  }

  // --- controls and legends ---
  renderControls() {
    if (!this.listNode) return;
    this.listNode.replaceChildren(...this.layers.map((l) => {
      const id = `layer-${l.id}`;
      const status = l.loading ? ' …' : l.error ? ' (n/a)' : '';
      const row = el('div', { class: `layer-row${l.error ? ' unavailable' : ''}`, title: l.error || '' },
        el('input', {
          type: 'checkbox', id, checked: l.visible, 'aria-label': `show ${l.label}`,
          onchange: (e) => this.setVisible(l.id, e.target.checked),
        }),
        el('label', { for: id }, l.label + status),
        el('input', {
          type: 'range', min: '0', max: '1', step: '0.05', value: String(l.opacity),
          'aria-label': `${l.label} opacity`, id: `${id}-opacity`,
          oninput: (e) => {
            l.opacity = Number(e.target.value);
            this.view.invalidate(l.kind === 'png');
          },
        }));
      return row;
    }));
    this.renderLegends();
  }

  renderLegends() {
    if (!this.legendNode) return;
    const items = [];
    for (const l of this.layers) {
      if (!l.visible) continue;
      let body = null;
      if (l.kind === 'png') body = l.legendCanvas;
      else if (l.legend) body = l.legend();
      if (!body) continue;
      items.push(el('div', { class: 'legend-item', dataset: { layer: l.id } }, el('div', { class: 'legend-name' }, l.legendTitle || l.label), body));
    }
    this.legendNode.replaceChildren(...items);
    this.legendNode.parentElement.hidden = items.length === 0;
  }
}
