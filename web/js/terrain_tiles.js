// The 3D view's terrain from the map's tiles (issue 24): a base mesh of the whole map from the
// elevation value tiles (GET /api/maps/{id}/tiles/elevation/{z}/{x}/{y}.f32) at the deepest zoom
// whose tiles of the whole map fit the vertex budget, and finer windows of 3 × 3 tiles around the
// orbit target when the camera comes close, nested every second zoom down to the native zoom (one
// DEM cell a vertex). A finer window cuts its area out of the next coarser level (clipping planes)
// and a wall along its border closes the seam (terrain_mesh.js). Coloured by the elevation ramp
// (vertex colours) or by the traversability classes (the layer's PNG tiles as textures, the same
// tiles the 2D map shows).
//
// Budget: the base ≤ 4 tiles (≤ 4 × 257² = 264 k vertices); a window 9 tiles (595 k vertices), at
// most ⌈(native − base) / 2⌉ windows (one on most maps); value tiles kept in memory ≤ 64 (256 KB
// each: 16 MB), PNG tiles ≤ 64.

import { fetchF32, fetchImage } from './api.js';
import { counters } from './state.js';
import { TILE, TerrainLevel, borderWall, clipPlanes, setClip, tileMesh } from './terrain_mesh.js';

export const BASE_TILES = 4;
export const PATCH = 3;
// A window spans at least 1.2 × the orbit distance, which puts its pixels at about 1.5–3 screen
// pixels at the target in a 45° view (the view there is ~1.3 × the distance wide in ~1300 px).
const SPAN = 1.2;
const LEVEL_STEP = 2;      // windows every second zoom: each 4× finer than the one under it
const CACHE_TILES = 64;
const SETTLE_MS = 120;     // the view rests this long before finer tiles are asked for

// The deepest zoom whose tiles of the whole map number at most BASE_TILES (z = 0 is one tile).
export function baseZoom(tiles) {
  let z = 0;
  for (let k = 0; k <= tiles.native_zoom; k++) {
    const [across, down] = tiles.tile_counts[k];
    if (across * down <= BASE_TILES) z = k;
  }
  return z;
}

// The PATCH × PATCH window of zoom z around local (x, y), moved inside the grid at its edges.
export function windowAround(map, z, x, y) {
  const t = map.tiles, [across, down] = t.tile_counts[z];
  const res = t.resolutions[z], resY = (t.resolutions_y || t.resolutions)[z];
  const clamp = (v, lo, hi) => Math.max(lo, Math.min(hi, v));
  const tx = clamp(Math.floor(x / (TILE * res)), 0, across - 1), ty = clamp(Math.floor((map.height_m - y) / (TILE * resY)), 0, down - 1);
  return {
    z, x0: clamp(tx - 1, 0, Math.max(0, across - PATCH)), y0: clamp(ty - 1, 0, Math.max(0, down - PATCH)),
    nx: Math.min(PATCH, across), ny: Math.min(PATCH, down),
  };
}

const winKey = (w) => `${w.z}/${w.x0}/${w.y0}/${w.nx}/${w.ny}`;
const styleKey = (s) => `${s.colourBy}:${s.exag}:${s.zMin}:${s.zMax}`;
const aborted = (err) => err && (err.code === 'aborted' || err.name === 'AbortError');

// A small map that forgets its oldest entry beyond `cap`.
class Lru {
  constructor(cap) {
    this.cap = cap;
    this.items = new Map();
  }
  get(key) {
    const v = this.items.get(key);
    if (v !== undefined) {
      this.items.delete(key);
      this.items.set(key, v);
    }
    return v;
  }
  set(key, v) {
    this.items.set(key, v);
    if (this.items.size > this.cap) this.items.delete(this.items.keys().next().value);
  }
  clear() {
    this.items.clear();
  }
}

export class TerrainTiles {
  // group: the scene group the meshes go into; onChange(): the levels shown changed.
  constructor(THREE, group, onChange) {
    this.THREE = THREE;
    this.group = group;
    this.onChange = onChange;
    this.map = null;
    this.base = null;       // the base TerrainLevel
    this.entries = [];      // shown, coarse to fine: {key, level, meshes, wall, textures}
    this.style = null;
    this.shownKey = '';
    this.pendingKey = '';
    this.values = new Lru(CACHE_TILES);
    this.images = new Lru(CACHE_TILES);
    this.aborters = { map: new AbortController(), style: new AbortController(), refine: new AbortController() };
    this.timer = 0;
    this.view = null;       // {x, y, dist}: the orbit target (local metres) and distance
    this.styling = false;   // setStyle is building meshes
    this.version = 0;       // bumps whenever the shown levels change
  }

  abort(...names) {
    for (const n of names) {
      this.aborters[n].abort();
      this.aborters[n] = new AbortController();
    }
  }

  // Loads the base level of `map`; false when another map was chosen meanwhile.
  async setMap(map) {
    this.abort('map', 'style', 'refine');
    clearTimeout(this.timer);
    this.apply([]);
    this.values.clear();
    this.images.clear();
    this.map = map;
    this.base = null;
    this.style = null;
    this.styling = false;
    this.shownKey = this.pendingKey = '';
    const t = map.tiles, z = baseZoom(t);
    const signal = this.aborters.map.signal;
    const level = await this.loadLevel({ z, x0: 0, y0: 0, nx: t.tile_counts[z][0], ny: t.tile_counts[z][1] }, signal);
    if (signal.aborted || this.map !== map) return false;
    this.base = level;
    return true;
  }

  // Builds the meshes of the levels shown (the base at first) with style {zMin, zMax, exag,
  // colourBy}; false when superseded.
  async setStyle(style) {
    if (!this.base) return false;
    if (this.style && this.entries.length && !this.styling && styleKey(style) === styleKey(this.style)) return true;  // shown already
    this.abort('style', 'refine');
    this.pendingKey = '';
    const signal = this.aborters.style.signal;
    const levels = this.entries.length ? this.entries.map((e) => e.level) : [this.base];
    this.style = style;
    this.styling = true;  // no refinement meanwhile: it would pair new meshes with the old base's
    const built = [];
    try {
      for (const level of levels) built.push(await this.buildEntry(level, signal));
    } catch (err) {
      built.forEach((e) => this.dispose(e));
      if (aborted(err)) return false;
      throw err;
    } finally {
      if (this.aborters.style.signal === signal) this.styling = false;
    }
    if (signal.aborted) {
      built.forEach((e) => this.dispose(e));
      return false;
    }
    this.apply(built);
    this.shownKey = this.keyOf(levels.slice(1).map((l) => l.win));
    this.refineSoon();
    return true;
  }

  keyOf(wins) {
    return `${wins.map(winKey).join('|')}#${styleKey(this.style)}`;
  }

  // The orbit moved: target at local (x, y), camera `dist` metres from it.
  viewChanged(x, y, dist) {
    this.view = { x, y, dist };
    this.refineSoon();
  }

  refineSoon() {
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.refine(), SETTLE_MS);
  }

  // The finer windows the view wants, coarse to fine: the deepest zoom (≤ native) whose 3 × 3
  // tiles span SPAN × the distance, and every second zoom above it down to the base's.
  wanted() {
    if (!this.view || !this.base) return [];
    const t = this.map.tiles, zb = this.base.z, { x, y, dist } = this.view;
    let zr = -1;
    for (let z = zb + 1; z <= t.native_zoom; z++) {
      const res = Math.min(t.resolutions[z], (t.resolutions_y || t.resolutions)[z]);
      if (PATCH * TILE * res >= SPAN * dist) zr = z;
    }
    const wins = [];
    for (let z = zr; zr > zb && z > zb; z -= LEVEL_STEP) wins.unshift(windowAround(this.map, z, x, y));
    return wins;
  }

  // Shows the windows the view wants (fetching what is not shown yet), or drops them all.
  async refine() {
    if (!this.base || !this.style || !this.entries.length || this.styling) return;
    const wins = this.wanted();
    const key = this.keyOf(wins);
    if (key === this.shownKey || key === this.pendingKey) return;
    this.abort('refine');  // the view moved on: stale tiles are not waited for
    this.pendingKey = key;
    const signal = this.aborters.refine.signal;
    const fresh = [];
    try {
      const levels = await Promise.all(wins.map((w) => this.entries.find((e) => e.key === winKey(w))?.level || this.loadLevel(w, signal)));
      const entries = [this.entries[0]];
      for (const level of levels) {
        let e = this.entries.find((x) => x.key === winKey(level.win));
        if (!e) fresh.push((e = await this.buildEntry(level, signal)));
        entries.push(e);
      }
      if (signal.aborted || this.entries[0] !== entries[0]) throw Object.assign(new Error('superseded'), { code: 'aborted' });
      this.apply(entries);
      this.shownKey = key;
    } catch (err) {
      fresh.forEach((e) => this.dispose(e));
      if (!aborted(err)) console.warn(`3D terrain tiles: ${err.message}`);
    } finally {
      if (this.pendingKey === key) this.pendingKey = '';
    }
  }

  async loadLevel(win, signal) {
    const jobs = [];
    for (let b = 0; b < win.ny; b++) for (let a = 0; a < win.nx; a++) jobs.push(this.tileValues(win.z, win.x0 + a, win.y0 + b, signal));
    return new TerrainLevel(this.map, win, await Promise.all(jobs));
  }

  async tileValues(z, x, y, signal) {
    const key = `${z}/${x}/${y}`;
    const hit = this.values.get(key);
    if (hit) return hit;
    const r = await fetchF32(`/api/maps/${encodeURIComponent(this.map.id)}/tiles/elevation/${key}.f32`, signal);
    if (r.rows !== TILE || r.cols !== TILE) throw new Error(`tile ${key}: ${r.rows}×${r.cols}, not ${TILE}²`);
    this.values.set(key, r.data);
    return r.data;
  }

  // The traversability PNG tile as a texture; null when it cannot be had (vertex colours then).
  async tileTexture(z, x, y, signal) {
    const THREE = this.THREE, key = `${z}/${x}/${y}`;
    let image = this.images.get(key);
    if (!image) {
      try {
        image = await fetchImage(`/api/maps/${encodeURIComponent(this.map.id)}/tiles/traversability/${key}.png`, signal);
      } catch (err) {
        if (aborted(err)) throw err;
        console.warn(`3D traversability tile ${key}: ${err.message}`);
        return null;
      }
      this.images.set(key, image);
    }
    const texture = new THREE.Texture(image);
    texture.flipY = false;                        // an ImageBitmap is not flipped: v = 0 is the tile's top row
    texture.magFilter = THREE.NearestFilter;      // class pixels stay crisp squares
    texture.minFilter = THREE.LinearFilter;
    texture.generateMipmaps = false;
    texture.colorSpace = THREE.SRGBColorSpace;
    texture.needsUpdate = true;
    return texture;
  }

  async buildEntry(level, signal) {
    const { win } = level;
    let textures = [];
    if (this.style.colourBy === 'traversability') {
      const jobs = [];
      for (let b = 0; b < win.ny; b++) for (let a = 0; a < win.nx; a++) jobs.push(this.tileTexture(win.z, win.x0 + a, win.y0 + b, signal));
      textures = await Promise.all(jobs);
    }
    const entry = { key: winKey(win), level, meshes: [], wall: null, textures: textures.filter(Boolean) };
    try {
      for (let b = 0; b < win.ny; b++) {
        for (let a = 0; a < win.nx; a++) {
          // A tile's mesh at a time, the page answering in between; a build the view has left
          // behind stops here.
          if (a + b) await new Promise((r) => setTimeout(r, 0));
          if (signal.aborted) throw Object.assign(new Error('superseded'), { code: 'aborted' });
          const m = tileMesh(this.THREE, level, a, b, { ...this.style, texture: textures[b * win.nx + a] || null });
          if (m) entry.meshes.push(m);
        }
      }
    } catch (err) {
      this.dispose(entry);
      throw err;
    }
    return entry;
  }

  // Shows `entries` (coarse to fine): each cut out under the next, a wall on each finer border.
  apply(entries) {
    const keep = new Set(entries);
    for (const e of this.entries) if (!keep.has(e)) this.dispose(e);
    for (const o of this.group.children.filter((c) => c.name.startsWith('terrain'))) this.group.remove(o);
    entries.forEach((e, i) => {
      if (e.wall) this.disposeObject(e.wall);
      e.wall = i ? borderWall(this.THREE, e.level, entries[i - 1].level, { ...this.style, texture: this.style.colourBy === 'traversability' }) : null;
      const planes = i + 1 < entries.length ? clipPlanes(this.THREE, entries[i + 1].level) : null;
      for (const m of e.wall ? [...e.meshes, e.wall] : e.meshes) {
        setClip(m, planes);
        this.group.add(m);
      }
    });
    this.entries = entries;
    this.version++;
    counters.view3dLevels = entries.map((e) => e.level.z);
    if (entries.length) this.onChange();
  }

  dispose(e) {
    for (const m of e.meshes) this.disposeObject(m);
    if (e.wall) this.disposeObject(e.wall);
    for (const t of e.textures) t.dispose();
    e.meshes = [];
    e.wall = null;
    e.textures = [];
  }

  disposeObject(o) {
    this.group.remove(o);
    o.geometry.dispose();
    o.material.dispose();
  }

  // The terrain's height at local (x, y) as the finest level shown draws it; NaN where none does.
  heightAt(x, y) {
    for (let i = this.entries.length - 1; i >= 0; i--) {
      const l = this.entries[i].level;
      if (!l.contains(x, y)) continue;
      const h = l.surfaceAt(x, y);
      if (!Number.isNaN(h)) return h;
    }
    return NaN;
  }
}
