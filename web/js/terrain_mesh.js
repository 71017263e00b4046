// Terrain meshes of the 3D view from elevation value tiles (GET /api/maps/{id}/tiles/elevation/
// {z}/{x}/{y}.f32, the map's tile grid, maps/tile_grid.hpp): a TerrainLevel is a window of whole
// tiles of one zoom assembled into one array, meshed tile by tile.
//
// Why vertices at tile-pixel *corners* (257 × 257 a tile) rather than at pixel centres: a tile's
// corner row/column is the tile grid line it shares with its neighbour, and a corner's height is
// the mean of the (up to four) pixels around it read from the level's assembled window, so two
// tiles of one level compute the same heights on their shared edge — no cracks, no skirts, and
// no neighbour's edge row to stitch in. The corners also sit on the grid lines of every coarser
// zoom (a tile edge of zoom z is a pixel edge of every zoom < z), so a finer window cut out of a
// coarser level has its border on the coarser mesh's vertex lines, where a wall (borderWall)
// closes the gap between the two surfaces exactly. And a tile's texture (the layer's PNG tile)
// maps onto the quads pixel for pixel: each quad is one tile pixel.

export const TILE = 256;

const HYPSO = [[40, 80, 160], [60, 150, 110], [200, 190, 110], [170, 110, 70], [240, 240, 240]];

// Colours are given in sRGB; three.js shades in linear light.
const linear = (c) => Math.pow(c, 2.2);

export function ramp(t) {
  const u = Math.max(0, Math.min(1, t)) * (HYPSO.length - 1);
  const i = Math.min(HYPSO.length - 2, Math.floor(u)), f = u - i;
  return HYPSO[i].map((a, k) => linear((a + (HYPSO[i + 1][k] - a) * f) / 255));
}

// The ramp in 1024 steps (linear RGB triplets), for meshes of 66 k vertices a tile.
const RAMP_STEPS = 1024;
const RAMP = new Float32Array(RAMP_STEPS * 3);
for (let k = 0; k < RAMP_STEPS; k++) RAMP.set(ramp(k / (RAMP_STEPS - 1)), 3 * k);

// A window of tiles {z, x0, y0, nx, ny} of the map's grid (map.tiles), their values `tiles`
// (Float32Array of 256², row-major over the window, NaN: no data or beyond the map).
export class TerrainLevel {
  constructor(map, win, tiles) {
    const t = map.tiles;
    this.win = win;
    this.z = win.z;
    this.W = map.width_m;
    this.H = map.height_m;
    this.res = t.resolutions[win.z];
    this.resY = (t.resolutions_y || t.resolutions)[win.z];
    this.cols = win.nx * TILE;
    this.rows = win.ny * TILE;
    this.ox = win.x0 * TILE * this.res;             // local x of the window's left edge
    this.oy = this.H - win.y0 * TILE * this.resY;   // local y of its top edge
    this.data = new Float32Array(this.cols * this.rows);
    for (let b = 0; b < win.ny; b++) {
      for (let a = 0; a < win.nx; a++) {
        const src = tiles[b * win.nx + a];
        for (let r = 0; r < TILE; r++) this.data.set(src.subarray(r * TILE, (r + 1) * TILE), (b * TILE + r) * this.cols + a * TILE);
      }
    }
    this.corners = this.cornerHeights();
    // The window inside the map, in local metres: [x0, y0, x1, y1].
    this.rect = [this.ox, Math.max(0, this.oy - this.rows * this.resY), Math.min(this.W, this.ox + this.cols * this.res), this.oy];
  }

  // Heights at the (cols + 1) × (rows + 1) pixel corners: the mean of the finite pixels around
  // each (sums of pixel pairs along a row, then of two rows' pairs: one pass over the window).
  cornerHeights() {
    const { cols, rows, data } = this;
    const w = cols + 1;
    const out = new Float32Array(w * (rows + 1));
    let prevSum = new Float32Array(w), prevCnt = new Uint8Array(w);  // the pixel row above: 0s
    let sum = new Float32Array(w), cnt = new Uint8Array(w);
    for (let cj = 0; cj <= rows; cj++) {
      if (cj < rows) {
        const row = cj * cols;
        for (let ci = 0; ci < w; ci++) {
          const l = ci > 0 ? data[row + ci - 1] : NaN, r = ci < cols ? data[row + ci] : NaN;
          let s = 0, n = 0;
          if (l === l) { s += l; n++; }  // not NaN
          if (r === r) { s += r; n++; }
          sum[ci] = s;
          cnt[ci] = n;
        }
      } else {
        sum.fill(0);
        cnt.fill(0);
      }
      const o = cj * w;
      for (let ci = 0; ci < w; ci++) {
        const n = cnt[ci] + prevCnt[ci];
        out[o + ci] = n ? (sum[ci] + prevSum[ci]) / n : NaN;
      }
      [prevSum, sum] = [sum, prevSum];
      [prevCnt, cnt] = [cnt, prevCnt];
    }
    return out;
  }

  cornerX(ci) {
    return Math.min(this.W, this.ox + ci * this.res);  // the last partial block ends at the map's edge
  }

  cornerY(cj) {
    return Math.max(0, this.oy - cj * this.resY);
  }

  contains(x, y) {
    const [x0, y0, x1, y1] = this.rect;
    return x >= x0 && x <= x1 && y >= y0 && y <= y1;
  }

  // The mesh's height at local (x, y): the triangle of the pixel's quad that holds the point
  // (the split the meshes use), NaN outside the window or on a pixel without data.
  surfaceAt(x, y) {
    const u = (x - this.ox) / this.res, v = (this.oy - y) / this.resY;
    const i = Math.min(this.cols - 1, Math.floor(u)), j = Math.min(this.rows - 1, Math.floor(v));
    if (i < 0 || j < 0 || u > this.cols || v > this.rows) return NaN;
    if (Number.isNaN(this.data[j * this.cols + i])) return NaN;
    const w = this.cols + 1, k = j * w + i;
    const a = this.corners[k], b = this.corners[k + 1], c = this.corners[k + w], d = this.corners[k + w + 1];
    const fu = u - i, fv = v - j;
    return fu + fv <= 1 ? a + fu * (b - a) + fv * (c - a) : d + (1 - fu) * (c - d) + (1 - fv) * (b - d);
  }
}

// The mesh of tile (a, b) of the level's window (257² vertices at the pixel corners, one quad per
// pixel with data). style: {zMin, zMax, exag, texture (a THREE.Texture of the tile, or null:
// vertex colours from the elevation ramp)}.
export function tileMesh(THREE, level, a, b, style) {
  const n = TILE + 1, w = level.cols + 1;
  const { zMin, zMax, exag } = style;
  const span = Math.max(1e-9, zMax - zMin);
  const pos = new Float32Array(n * n * 3), nor = new Float32Array(n * n * 3);
  const col = style.texture ? null : new Float32Array(n * n * 3);
  const uv = style.texture ? new Float32Array(n * n * 2) : null;
  const H = level.corners;
  const at = (ci, cj) => (ci < 0 || cj < 0 || ci >= w || cj > level.rows ? NaN : H[cj * w + ci]);
  for (let j = 0; j < n; j++) {
    const cj = b * TILE + j;
    for (let i = 0; i < n; i++) {
      const ci = a * TILE + i, k = j * n + i;
      const h = at(ci, cj);
      const y = ((Number.isNaN(h) ? zMin : h) - zMin) * exag;
      pos[3 * k] = level.cornerX(ci) - level.W / 2;
      pos[3 * k + 1] = y;
      pos[3 * k + 2] = level.H / 2 - level.cornerY(cj);  // north is −z
      // The normal from central differences over the level's corners, so tiles of a level shade
      // alike on their shared edge.
      const dx = slope(at(ci - 1, cj), h, at(ci + 1, cj), level.res) * exag;
      const dz = slope(at(ci, cj - 1), h, at(ci, cj + 1), level.resY) * exag;  // a row down is +z
      const len = Math.sqrt(dx * dx + 1 + dz * dz);
      nor[3 * k] = -dx / len;
      nor[3 * k + 1] = 1 / len;
      nor[3 * k + 2] = -dz / len;
      if (col) {
        const q = Number.isNaN(h) ? -1 : 3 * Math.round(Math.max(0, Math.min(1, (h - zMin) / span)) * (RAMP_STEPS - 1));
        col[3 * k] = q < 0 ? 0.2 : RAMP[q];
        col[3 * k + 1] = q < 0 ? 0.2 : RAMP[q + 1];
        col[3 * k + 2] = q < 0 ? 0.2 : RAMP[q + 2];
      }
      if (uv) {
        uv[2 * k] = i / TILE;
        uv[2 * k + 1] = j / TILE;
      }
    }
  }
  const index = new Uint32Array(TILE * TILE * 6);
  let m = 0;
  for (let j = 0; j < TILE; j++) {
    const row = (b * TILE + j) * level.cols + a * TILE;
    for (let i = 0; i < TILE; i++) {
      if (Number.isNaN(level.data[row + i])) continue;
      const p = j * n + i, q = p + 1, r = p + n, s = r + 1;
      // Counter-clockwise seen from above.
      index[m++] = p; index[m++] = r; index[m++] = q;
      index[m++] = q; index[m++] = r; index[m++] = s;
    }
  }
  if (!m) return null;
  const geo = new THREE.BufferGeometry();
  geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  geo.setAttribute('normal', new THREE.BufferAttribute(nor, 3));
  if (col) geo.setAttribute('color', new THREE.BufferAttribute(col, 3));
  if (uv) geo.setAttribute('uv', new THREE.BufferAttribute(uv, 2));
  geo.setIndex(new THREE.BufferAttribute(index.slice(0, m), 1));
  const material = new THREE.MeshLambertMaterial(style.texture ? { map: style.texture } : { vertexColors: true });
  material.side = THREE.DoubleSide;
  const mesh = new THREE.Mesh(geo, material);
  mesh.name = 'terrain';
  mesh.userData.tile = [level.z, level.win.x0 + a, level.win.y0 + b];
  return mesh;
}

// Rise over run from the neighbours of h (one-sided at an edge or beside no data).
function slope(lo, h, hi, step) {
  const l = Number.isNaN(lo) ? h : lo, r = Number.isNaN(hi) ? h : hi;
  const d = (Number.isNaN(lo) ? 0 : 1) + (Number.isNaN(hi) ? 0 : 1);
  return d && !Number.isNaN(h) ? (r - l) / (d * step) : 0;
}

// A wall along the border of a finer level from its edge down (or up) to the coarser level's
// surface at the same points: the coarser mesh is clipped exactly at that border, which lies on
// its vertex lines, so the wall closes the seam between the two resolutions. Sides on the map's
// edge have nothing outside and get no wall.
export function borderWall(THREE, fine, coarse, style) {
  const { zMin, zMax, exag } = style;
  const span = Math.max(1e-9, zMax - zMin);
  const w = fine.cols + 1;
  const sides = [];
  const eps = 1e-6 * Math.max(fine.W, fine.H);
  if (fine.oy < fine.H - eps) sides.push(Array.from({ length: w }, (_, ci) => [ci, 0]));
  if (fine.oy - fine.rows * fine.resY > eps) sides.push(Array.from({ length: w }, (_, ci) => [ci, fine.rows]));
  if (fine.ox > eps) sides.push(Array.from({ length: fine.rows + 1 }, (_, cj) => [0, cj]));
  if (fine.ox + fine.cols * fine.res < fine.W - eps) sides.push(Array.from({ length: fine.rows + 1 }, (_, cj) => [fine.cols, cj]));
  const pos = [], col = [], index = [];
  for (const side of sides) {
    let prev = -1;
    for (const [ci, cj] of side) {
      const x = fine.cornerX(ci), y = fine.cornerY(cj);
      const top = fine.corners[cj * w + ci], bottom = coarse.surfaceAt(x, y);
      if (Number.isNaN(top) || Number.isNaN(bottom)) {
        prev = -1;
        continue;
      }
      const k = pos.length / 3;
      for (const h of [top, bottom]) {
        pos.push(x - fine.W / 2, (h - zMin) * exag, fine.H / 2 - y);
        col.push(...(style.texture ? [0.25, 0.22, 0.2] : ramp((h - zMin) / span)));
      }
      if (prev >= 0) index.push(prev, prev + 1, k, k, prev + 1, k + 1);
      prev = k;
    }
  }
  if (!index.length) return null;
  const geo = new THREE.BufferGeometry();
  geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(pos), 3));
  geo.setAttribute('color', new THREE.BufferAttribute(new Float32Array(col), 3));
  // Lit as level ground, so the wall shades like the terrain beside it rather than as a cliff.
  const nor = new Float32Array(pos.length);
  for (let i = 1; i < nor.length; i += 3) nor[i] = 1;
  geo.setAttribute('normal', new THREE.BufferAttribute(nor, 3));
  geo.setIndex(index);
  const material = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide });
  const mesh = new THREE.Mesh(geo, material);
  mesh.name = 'terrain-wall';
  return mesh;
}

// Four planes whose intersection of negative sides is the level's window (local rect → scene):
// with clipIntersection, a coarser mesh is cut away where the finer one lies. The cut stops half a
// fine pixel inside the window: the coarse surface clipped per fragment and the wall's edge
// rasterised per triangle otherwise leave pixel-wide cracks along the seam where neither is
// drawn (the background showed through as a dotted line); the overlap hides under the finer
// surface, or shows the same ground a few centimetres higher over half a pixel.
export function clipPlanes(THREE, level) {
  const inset = 0.5 * Math.min(level.res, level.resY);
  const [x0, y0, x1, y1] = [level.rect[0] + inset, level.rect[1] + inset, level.rect[2] - inset, level.rect[3] - inset];
  const sx0 = x0 - level.W / 2, sx1 = x1 - level.W / 2, sz0 = level.H / 2 - y1, sz1 = level.H / 2 - y0;
  return [
    new THREE.Plane(new THREE.Vector3(-1, 0, 0), sx0),
    new THREE.Plane(new THREE.Vector3(1, 0, 0), -sx1),
    new THREE.Plane(new THREE.Vector3(0, 0, -1), sz0),
    new THREE.Plane(new THREE.Vector3(0, 0, 1), -sz1),
  ];
}

// Cuts the finer level's window out of a mesh of a coarser level (planes from clipPlanes), or
// nothing (null).
export function setClip(mesh, planes) {
  mesh.material.clippingPlanes = planes || null;
  mesh.material.clipIntersection = true;  // cut where inside all four planes, not outside any
  mesh.material.needsUpdate = true;
}
