// The 3D view (three.js, loaded on first use): the map's elevation tiles as displaced meshes
// (terrain_tiles.js: the whole map at a zoom within the vertex budget, finer tiles around the
// orbit target when the camera comes close), coloured by elevation or traversability, with the
// mission's trails draped at terrain height plus a small offset, and the map's keep-out zones as
// red walls standing on their outlines. A small orbit control of our own: drag to orbit,
// right-drag or shift-drag to pan, wheel or the toolbar's +/− to zoom ("fit" frames the whole map
// again).

import { counters, state } from './state.js';
import { TerrainTiles } from './terrain_tiles.js';
import { roverColour } from './util.js';

function webglAvailable() {
  try {
    const c = document.createElement('canvas');
    return Boolean(c.getContext('webgl2') || c.getContext('webgl'));
  } catch {
    return false;
  }
}

export class View3D {
  constructor({ container, message, missionView }) {
    this.container = container;
    this.message = message;
    this.missionView = missionView;
    this.THREE = null;
    this.renderer = null;
    this.mapId = null;
    this.trailKey = '';
    this.orbit = { yaw: -0.6, pitch: 0.75, dist: 1, target: [0, 0, 0] };
    this.visible = false;
    $colour(this).addEventListener('change', () => this.rebuild());
    $exag(this).addEventListener('change', () => this.rebuild());
  }

  async show() {
    this.visible = true;
    if (!webglAvailable()) {
      this.say('The 3D view needs WebGL, which this browser does not offer (hardware acceleration off?). The 2D map has every layer.');
      return;
    }
    try {
      if (!this.THREE) this.THREE = await import('three');
      if (!this.renderer) this.setup();
      await this.rebuild();
      this.resize();
      this.frame();
    } catch (err) {
      this.say(`3D view unavailable: ${err.message}`);
    }
  }

  hide() {
    this.visible = false;
  }

  say(text) {
    this.message.textContent = text;
    this.message.hidden = !text;
  }

  // "loading terrain…" while the base tiles come, apart from the message (which says the view is
  // unavailable, and which the page's tests read so).
  loading(on) {
    if (!this.status) {
      this.status = Object.assign(document.createElement('div'), { className: 'view3d-message', textContent: 'loading terrain…' });
      this.status.setAttribute('role', 'status');
      this.status.style.pointerEvents = 'none';
      this.container.append(this.status);
    }
    this.status.hidden = !on;
  }

  setup() {
    const THREE = this.THREE;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.container.prepend(this.renderer.domElement);
    this.renderer.domElement.tabIndex = 0;
    this.renderer.domElement.setAttribute('aria-label', '3D terrain: drag to orbit, wheel to zoom');
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x0b0d10);
    this.camera = new THREE.PerspectiveCamera(45, 1, 0.1, 1e7);
    this.scene.add(new THREE.AmbientLight(0xffffff, 0.8));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(-1, 1.2, 0.6);
    this.scene.add(sun);
    this.group = new THREE.Group();
    this.scene.add(this.group);
    this.renderer.localClippingEnabled = true;  // finer tiles cut their area out of coarser ones
    this.terrain = new TerrainTiles(THREE, this.group, () => this.terrainChanged());
    new ResizeObserver(() => this.resize()).observe(this.container);
    this.bindOrbit(this.renderer.domElement);
    state.on('map', () => this.visible && this.rebuild());
    state.on('zones', () => this.updateZones());
    setInterval(() => this.visible && this.updateTrails(), 400);
  }

  resize() {
    if (!this.renderer) return;
    const r = this.container.getBoundingClientRect();
    if (r.width < 2 || r.height < 2) return;
    this.renderer.setSize(r.width, r.height, false);
    this.camera.aspect = r.width / r.height;
    this.camera.updateProjectionMatrix();
    this.frame();
  }

  // The terrain of the selected map with the colour and relief chosen: the base level's tiles
  // are fetched when the map changed, the meshes made again for a new colour or relief.
  async rebuild() {
    const map = state.map;
    if (!this.THREE || !this.renderer || !map) return;
    if (!map.tiles) {
      this.say('The server gives no tiles for this map: no 3D view.');
      return;
    }
    try {
      const newMap = this.terrain.map?.id !== map.id;
      if (newMap) {
        this.say('');
        this.loading(true);
        this.mapId = null;
        const loaded = await this.terrain.setMap(map).finally(() => this.loading(false));
        if (!loaded) return;  // another map chosen meanwhile
      }
      let zMin = map.elevation?.min, zMax = map.elevation?.max;
      if (!Number.isFinite(zMin) || !Number.isFinite(zMax)) [zMin, zMax] = finiteRange(this.terrain.base.data);
      if (this.mapId !== map.id) {
        // Relief exaggeration so that the relief is about a tenth of the map's width.
        const auto = zMax > zMin ? (0.1 * Math.max(map.width_m, map.height_m)) / (zMax - zMin) : 1;
        $exag(this).value = String(Math.max(1, Math.min(50, Number(auto.toPrecision(2)))));
      }
      const exag = Math.max(0.1, Number($exag(this).value) || 1);
      const W = map.width_m, H = map.height_m;
      this.extent = { W, H, zMin, zMax, exag };
      if (!(await this.terrain.setStyle({ zMin, zMax, exag, colourBy: $colour(this).value }))) return;
      this.say('');
      if (this.mapId !== map.id) {
        this.mapId = map.id;
        this.orbit = { yaw: -0.6, pitch: 0.75, dist: 1.75 * Math.max(W, H), target: [0, ((zMax - zMin) * exag) / 2, 0] };
      }
      counters.view3dReady = true;
      this.frame();
    } catch (err) {
      if (err.code !== 'aborted') this.say(`3D view unavailable: ${err.message}`);
    }
  }

  // The levels shown changed (a map, a colour, finer tiles): trails, zones and the marker are
  // draped on the new surface.
  terrainChanged() {
    this.trailKey = '';
    this.updateTrails();
    this.updateZones();
    this.setMarker(this.markerAt || null);
    this.frame();
  }

  // Terrain is shown (so trails, zones and the marker have a surface to stand on).
  get shown() {
    return Boolean(this.THREE && this.terrain && this.terrain.entries.length && this.extent);
  }

  heightAt(x, y) {
    const h = this.terrain.heightAt(x, y);
    return Number.isNaN(h) ? this.extent.zMin : h;
  }

  // The route profile's hovered sample (x, y in local metres), or null: a white ball on the
  // terrain. Made anew when a rebuild of the terrain removed (and disposed) the last one.
  setMarker(p) {
    this.markerAt = p;
    if (!this.shown) return;
    if (this.marker && this.marker.parent !== this.group) this.marker = null;
    if (!p) {
      if (this.marker) this.group.remove(this.marker);
      this.marker = null;
      return this.frame();
    }
    const THREE = this.THREE;
    if (!this.marker) {
      this.marker = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0xffffff }));
      this.marker.name = 'profile-marker';
      this.group.add(this.marker);
    }
    const { W, H, zMin, exag } = this.extent;
    const r = Math.max(0.3, 0.008 * Math.max(W, H));
    this.marker.scale.setScalar(r);
    this.marker.position.set(p.x - W / 2, (this.heightAt(p.x, p.y) - zMin) * exag + r, H / 2 - p.y);
    this.frame();
  }

  // Zoom by `factor` (> 1: closer), as the toolbar's +/− do on the 2D map.
  zoom(factor) {
    this.orbit.dist = Math.max(1, this.orbit.dist / factor);
    this.frame();
  }

  // The whole map in view again, from the starting angle.
  fit() {
    if (!this.extent) return;
    const { W, H, zMin, zMax, exag } = this.extent;
    this.orbit = { yaw: -0.6, pitch: 0.75, dist: 1.75 * Math.max(W, H), target: [0, ((zMax - zMin) * exag) / 2, 0] };
    this.frame();
  }

  // The map's saved keep-out zones (state.zones, local frame): each outline draped on the terrain
  // (points every ~cell along its edges) and a translucent red wall standing on it, so a zone
  // reads from any angle.
  updateZones() {
    if (!this.shown) return;
    const THREE = this.THREE;
    for (const c of this.group.children.filter((o) => o.name === 'zone')) {
      this.group.remove(c);
      c.geometry.dispose();
      c.material.dispose();
    }
    const { W, H, zMin, exag } = this.extent;
    const wall = Math.max(0.5, 0.03 * Math.max(W, H));
    const lift = Math.max(0.15, 0.004 * Math.max(W, H));
    const step = Math.max(state.map.cell_size_m, state.map.cell_height_m || 0, Math.max(W, H) / 400);
    let n = 0;
    for (const f of state.zones?.features || []) {
      const rings = f.geometry?.type === 'Polygon' ? [f.geometry.coordinates[0]]
        : f.geometry?.type === 'MultiPolygon' ? f.geometry.coordinates.map((p) => p[0]) : [];
      for (const ring of rings) {
        const pts = [];
        for (let i = 0; i + 1 < ring.length; i++) {
          const [x0, y0] = ring[i], [x1, y1] = ring[i + 1];
          const k = Math.max(1, Math.ceil(Math.hypot(x1 - x0, y1 - y0) / step));
          for (let j = 0; j < k; j++) pts.push([x0 + ((x1 - x0) * j) / k, y0 + ((y1 - y0) * j) / k]);
        }
        if (pts.length < 2) continue;
        pts.push(pts[0]);
        const base = pts.map(([x, y]) => [x - W / 2, (this.heightAt(x, y) - zMin) * exag + lift, H / 2 - y]);
        const line = new THREE.Line(new THREE.BufferGeometry().setAttribute('position', new THREE.BufferAttribute(new Float32Array(base.flat()), 3)),
          new THREE.LineBasicMaterial({ color: 0xff4040 }));
        line.name = 'zone';
        this.group.add(line);
        const pos = new Float32Array(base.length * 2 * 3);
        base.forEach(([x, y, z], i) => pos.set([x, y, z, x, y + wall, z], 6 * i));
        const index = [];
        for (let i = 0; i + 1 < base.length; i++) index.push(2 * i, 2 * i + 2, 2 * i + 1, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        const geo = new THREE.BufferGeometry();
        geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
        geo.setIndex(index);
        const mesh = new THREE.Mesh(geo, new THREE.MeshBasicMaterial({ color: 0xff3030, transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false }));
        mesh.name = 'zone';
        this.group.add(mesh);
        n++;
      }
    }
    counters.view3dZones = n;
    this.frame();
  }

  // The shown mission's trails (and compared runs) as lines on the terrain.
  updateTrails() {
    if (!this.shown) return;
    const THREE = this.THREE;
    const sets = this.missionView.compareSets.length ? this.missionView.compareSets : [this.missionView.trails];
    const key = sets.map((s) => `${s.version}:${s.paths.map((p) => p.length).join('/')}:${s.limit}`).join('|') + `#${this.terrain.version}`;
    if (key === this.trailKey) return;
    this.trailKey = key;
    for (const c of this.group.children.filter((o) => o.name === 'trail')) {
      this.group.remove(c);
      c.geometry.dispose();
      c.material.dispose();
    }
    const { W, H, zMin, exag } = this.extent;
    const lift = Math.max(0.15, 0.004 * Math.max(W, H));
    for (const s of sets) {
      s.paths.forEach((path, k) => {
        const end = Math.min(path.length, s.limit + 1);
        if (end < 2) return;
        const stride = Math.max(1, Math.ceil(end / 20000));
        const pts = [];
        for (let i = 0; i < end; i += stride) pts.push(path[i]);
        if ((end - 1) % stride) pts.push(path[end - 1]);
        const arr = new Float32Array(pts.length * 3);
        pts.forEach(([x, y], i) => arr.set([x - W / 2, (this.heightAt(x, y) - zMin) * exag + lift, H / 2 - y], 3 * i));
        const geo = new THREE.BufferGeometry();
        geo.setAttribute('position', new THREE.BufferAttribute(arr, 3));
        const line = new THREE.Line(geo, new THREE.LineBasicMaterial({ color: roverColour(k + (s.style.colourOffset || 0)) }));
        line.name = 'trail';
        this.group.add(line);
      });
    }
    this.frame();
  }

  bindOrbit(canvas) {
    let drag = null;
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
    canvas.addEventListener('pointerdown', (e) => {
      drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
      canvas.setPointerCapture(e.pointerId);
    });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX;
      drag.y = e.clientY;
      const o = this.orbit;
      if (drag.pan) {
        const s = o.dist / 800;
        const cy = Math.cos(o.yaw), sy = Math.sin(o.yaw);
        o.target[0] -= (dx * cy + dy * sy) * s;
        o.target[2] -= (-dx * sy + dy * cy) * s;
      } else {
        o.yaw -= dx * 0.006;
        o.pitch = Math.max(0.05, Math.min(1.5, o.pitch + dy * 0.006));
      }
      this.frame();
    });
    const end = () => { drag = null; };
    canvas.addEventListener('pointerup', end);
    canvas.addEventListener('pointercancel', end);
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      this.orbit.dist = Math.max(1, this.orbit.dist * Math.exp(e.deltaY * 0.001));
      this.frame();
    }, { passive: false });
    canvas.addEventListener('keydown', (e) => {
      const o = this.orbit;
      const k = { ArrowLeft: () => (o.yaw += 0.1), ArrowRight: () => (o.yaw -= 0.1), ArrowUp: () => (o.pitch = Math.min(1.5, o.pitch + 0.05)),
        ArrowDown: () => (o.pitch = Math.max(0.05, o.pitch - 0.05)), '+': () => (o.dist *= 0.85), '-': () => (o.dist /= 0.85) }[e.key];
      if (k) {
        e.preventDefault();
        k();
        this.frame();
      }
    });
  }

  frame() {
    if (!this.renderer || !this.visible) return;
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      const o = this.orbit;
      const [tx, ty, tz] = o.target;
      this.camera.position.set(
        tx + o.dist * Math.cos(o.pitch) * Math.sin(o.yaw),
        ty + o.dist * Math.sin(o.pitch),
        tz + o.dist * Math.cos(o.pitch) * Math.cos(o.yaw));
      this.camera.near = o.dist / 1000;
      this.camera.far = o.dist * 20;
      this.camera.updateProjectionMatrix();
      this.camera.lookAt(tx, ty, tz);
      this.renderer.render(this.scene, this.camera);
      if (this.extent) {
        const { W, H } = this.extent;
        this.terrain.viewChanged(Math.max(0, Math.min(W, tx + W / 2)), Math.max(0, Math.min(H, H / 2 - tz)), o.dist);
      }
    });
  }

  toDataURL() {
    if (!this.renderer) return null;
    this.renderer.render(this.scene, this.camera);
    return this.renderer.domElement.toDataURL('image/png');
  }
}

function $colour() {
  return document.getElementById('view3d-colour');
}
function $exag() {
  return document.getElementById('view3d-exag');
}

// [min, max] of the finite values (both 0 when none).
function finiteRange(data) {
  let lo = Infinity, hi = -Infinity;
  for (const v of data) if (Number.isFinite(v)) { if (v < lo) lo = v; if (v > hi) hi = v; }
  return Number.isFinite(lo) ? [lo, hi] : [0, 0];
}
