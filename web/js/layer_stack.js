// The map's layers: the server's raster layers (elevation, hillshade, slope, traversability, PDM)
// as OpenLayers tile layers under the map view (tiles of GET /api/maps/{id}/tiles/..., at the
// resolution the view shows: one DEM cell a tile pixel when zoomed in), plus overlay layers other
// modules register (coverage, trails). Each layer has a visibility checkbox and an opacity slider;
// the legend panel shows the legend of each visible layer, drawn by the page (legend.js: ramps
// with ticks, class swatches; the strip under the server's small PNG overview only for maps too
// big for the float32 layers). Also loads the float32 rasters behind the cursor readout.

import TileLayer from 'ol/layer/Tile.js';
import XYZ from 'ol/source/XYZ.js';
import TileGrid from 'ol/tilegrid/TileGrid.js';
import TileState from 'ol/TileState.js';
import { fetchF32, fetchImage, layerUrl, request } from './api.js';
import { counters, state } from './state.js';
import { $, el, fmt } from './util.js';
import { CLASSES, HYPSOMETRIC, PERCEPTUAL, SLOPE, classLegend, elevationRange, maxFinite, rampColour, rampLegend } from './legend.js';

const LEGEND_SIZE = 256;             // legends come from the 256-px overview, shown 1:1 (readable)
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
      id, label, kind: 'png', visible, opacity, order, source: null, loading: false, error: '', legendCanvas: null,
      ol: new TileLayer({ visible: false, opacity, zIndex: order }),
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
    if (layer.kind === 'png') this.view.olMap.addLayer(layer.ol);
    this.renderControls();
  }

  // An overlay layer drawn by another module: {id, label, visible, opacity, legend(): Node}, and
  // `ol` when it is an OL layer of its own (its visibility and opacity follow the controls).
  addOverlay(layer) {
    if (layer.ol) {
      layer.ol.setVisible(Boolean(layer.visible));
      layer.ol.setOpacity(layer.opacity ?? 1);
    }
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
    if (l.kind === 'png') {
      l.ol.setVisible(visible && Boolean(l.source));
      if (visible) this.loadPng(l);
    } else if (l.ol) {
      l.ol.setVisible(visible);  // an overlay drawn as an OL layer (zones.js)
    }
    this.renderControls();
    this.view.invalidate(true);
  }

  // --- the selected map ---
  async setMap(map) {
    this.generation++;
    this.aborter.abort();
    this.aborter = new AbortController();
    for (const l of this.layers) if (l.kind === 'png') this.dropSource(l);
    this.rasters = {};
    this.renderControls();
    if (!map) return;
    const loads = this.layers.filter((l) => l.kind === 'png' && l.visible).map((l) => this.loadPng(l));
    this.loadRasters(map);
    await Promise.all(loads);
  }

  setPdm(pdmId) {
    const l = this.get('pdm');
    this.dropSource(l);
    delete this.rasters.pdm;
    if (pdmId && state.map) {
      l.visible = true;
      this.loadPng(l);
      this.loadRaster(state.map, 'pdm', pdmId);
    }
    this.renderControls();
    this.view.invalidate(true);
  }

  dropSource(layer) {
    layer.ol.setVisible(false);
    layer.ol.setSource(null);
    layer.source = null;
    layer.tileShown = false;
    layer.error = '';
    layer.loading = false;
    layer.legendCanvas = null;
  }

  // The layer's tiles on the map's tile grid (the map's `tiles`), fetched with the token (so they
  // load behind --token too); the first tile that arrives counts the layer as loaded. A tile is
  // 256 × 256 pixels of `resolutions` × `resolutions_y` metres: on a map whose cells are not square
  // the grid's tiles are 256 view pixels wide and 256 × (cell height / cell width) tall, so OL
  // draws each tile over its true extent in metres (the tile size per axis; OL's tile renderer
  // draws an image into its tile's rectangle) and the view needs no stretching.
  loadPng(layer) {
    const map = state.map;
    if (!map || layer.source || layer.loading) return;
    if (layer.id === 'pdm' && !state.pdmId) {
      layer.error = 'no PDM selected';
      this.renderControls();
      return;
    }
    if (!map.tiles) {
      layer.error = 'the server gives no tiles for this map';
      this.renderControls();
      return;
    }
    const gen = this.generation, pdm = layer.id === 'pdm' ? state.pdmId : '';
    const t = map.tiles, top = t.extent[3];
    const aspect = t.resolutions_y ? t.resolutions_y[0] / t.resolutions[0] : 1;  // cell height / width
    const signal = this.aborter.signal;
    const q = pdm ? `?pdm=${encodeURIComponent(pdm)}` : '';
    const source = new XYZ({
      projection: this.view.projection,
      tileGrid: new TileGrid({ extent: [0, 0, t.extent[2], top], origin: [0, top], resolutions: t.resolutions, tileSize: [t.tile_size, t.tile_size * aspect] }),
      tileUrlFunction: ([z, x, y]) => `/api/maps/${map.id}/tiles/${layer.id}/${z}/${x}/${y}.png${q}`,
      tileLoadFunction: (tile, src) => loadTile(tile, src, signal),
      interpolate: false,  // magnified cells stay crisp squares
      transition: 0,
      wrapX: false,
    });
    layer.source = source;
    layer.loading = true;
    const settled = (error) => {
      if (layer.source !== source || !layer.loading) return;
      layer.loading = false;
      layer.error = error;
      if (!error) {
        layer.tileShown = true;
        counters.layersLoaded.push(layer.id);
      }
      this.renderControls();
      this.view.invalidate();
    };
    source.on('tileloadend', () => settled(''));
    source.on('tileloaderror', () => settled(`${layer.label}: tiles unavailable`));
    layer.ol.setSource(source);
    layer.ol.setOpacity(layer.opacity);
    layer.ol.setVisible(layer.visible);
    this.renderControls();
    this.loadLegend(layer, map, pdm, gen);
  }

  // The legend strip the server draws under the map in its small PNG overview.
  async loadLegend(layer, map, pdm, gen) {
    const source = layer.source;
    try {
      const max = Math.max(map.rows, map.cols) > LEGEND_SIZE ? LEGEND_SIZE : 0;
      const image = await fetchImage(layerUrl(map.id, layer.id, 'png', { max, pdm, version: state.pdms.find((p) => p.id === pdm)?.version }), this.aborter.signal);
      if (gen !== this.generation || layer.source !== source) {
        image.close();
        return;
      }
      const [mapRows] = displaySize(map.rows, map.cols, max);
      layer.legendCanvas = this.legendFromStrip(image, mapRows);
      image.close();
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

  // --- float32 rasters for the cursor readout ---
  loadRasters(map) {
    for (const name of ['elevation', 'slope', 'traversability']) this.loadRaster(map, name);
    if (state.pdmId) this.loadRaster(map, 'pdm', state.pdmId);
  }

  async loadRaster(map, name, pdm = '') {
    if (map.rows * map.cols > MAX_F32_CELLS) return;
    const gen = this.generation;
    try {
      const r = await fetchF32(layerUrl(map.id, name, 'f32', { pdm, version: state.pdms.find((p) => p.id === pdm)?.version }), this.aborter.signal);
      if (gen !== this.generation || (name === 'pdm' && pdm !== state.pdmId)) return;
      this.rasters[name] = r;
      if (name === 'elevation') state.emit('elevation', r);
      if (name === 'elevation' || name === 'pdm') this.renderLegends();  // their ramps' ranges
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
            if (l.ol) l.ol.setOpacity(l.opacity);
            else this.view.invalidate();
          },
        }));
      return row;
    }));
    this.renderLegends();
  }

  // The page's own legend of a server layer (legend.js), or null (then the server's strip).
  drawnLegend(l) {
    const map = state.map;
    if (!map) return null;
    if (l.id === 'elevation') {
      const r = this.rasters.elevation;
      if (!r) return null;
      const { lo, hi } = elevationRange(r);
      return el('div', {}, rampLegend({ lo, hi, unit: 'm', colourAt: (v) => rampColour(HYPSOMETRIC, (v - lo) / (hi - lo)) }),
        el('div', { class: 'muted small' }, `2–98 % of the heights; the map spans ${fmt(map.elevation.min)} … ${fmt(map.elevation.max)} m`));
    }
    if (l.id === 'slope') {
      return el('div', {}, rampLegend({
        lo: 0, hi: 45, unit: '°', colourAt: (v) => rampColour(SLOPE, v),
        marks: [{ v: 0, label: '0' }, { v: 10, label: '10' }, { v: 15, label: '15' }, { v: 30, label: '30' }, { v: 45, label: '45' }],
      }), el('div', { class: 'muted small' }, 'high risk from 10°, impassable from 15°'));
    }
    if (l.id === 'traversability') {
      return classLegend(CLASSES.map((c) => ({ colour: c.colour, name: c.name, note: map.classes && map.classes[c.key] !== undefined ? `${fmt(map.classes[c.key], 2)} %` : '' })));
    }
    if (l.id === 'hillshade') return el('div', { class: 'muted small' }, 'grey shaded relief (light: slopes facing the sun)');
    if (l.id === 'pdm') {
      const r = this.rasters.pdm;
      if (!r) return null;
      const hi = maxFinite(r);
      return el('div', {}, rampLegend({ lo: 0, hi, colourAt: (v) => rampColour(PERCEPTUAL, v / hi) }),
        el('div', { class: 'muted small' }, 'probability mass per cell'));
    }
    return null;
  }

  renderLegends() {
    if (!this.legendNode) return;
    const items = [];
    for (const l of this.layers) {
      if (!l.visible) continue;
      let body = null;
      if (l.kind === 'png') body = this.drawnLegend(l) || l.legendCanvas;
      else if (l.legend) body = l.legend();
      if (!body) continue;
      items.push(el('div', { class: 'legend-item', dataset: { layer: l.id } }, el('div', { class: 'legend-name' }, l.legendTitle || l.label), body));
    }
    this.legendNode.replaceChildren(...items);
    this.legendNode.parentElement.hidden = items.length === 0;
  }
}

// Loads a tile's PNG with the token into the tile's image (as a blob URL, released once decoded);
// a refused or failed fetch marks the tile failed, so OL neither waits on it nor asks again.
async function loadTile(tile, src, signal) {
  const image = tile.getImage();
  try {
    const blob = await (await request(src, { signal })).blob();
    const url = URL.createObjectURL(blob);
    const release = () => URL.revokeObjectURL(url);
    image.addEventListener('load', release, { once: true });
    image.addEventListener('error', release, { once: true });
    image.src = url;
  } catch {
    tile.setState(TileState.ERROR);
  }
}
