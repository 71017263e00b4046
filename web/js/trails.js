// Rover trails and poses on the map. Trails are drawn into a screen-space cache that only gets
// the new segments while the view stays put, and is redrawn whole after a pan/zoom, a replay
// seek or a reset — so a live mission with long trails stays cheap per frame.

import { roverColour } from './util.js';

export class TrailSet {
  constructor(style = {}) {
    this.paths = [];       // per rover: array of [x, y]
    this.headings = [];    // per rover: last heading (deg) or null
    this.limit = Infinity; // replay: points 0..limit are shown
    this.style = { width: 2, dash: null, alpha: 1, label: '', ...style };
    this.version = 0;      // bumps when drawn points may shrink/change (full redraw needed)
  }

  clear(rovers = 0) {
    this.paths = Array.from({ length: rovers }, () => []);
    this.headings = Array.from({ length: rovers }, () => null);
    this.limit = Infinity;
    this.version++;
  }

  ensure(k) {
    while (this.paths.length <= k) {
      this.paths.push([]);
      this.headings.push(null);
    }
  }

  append(k, points, pose) {
    this.ensure(k);
    const p = this.paths[k];
    for (const q of points) p.push(q);
    if (pose) this.headings[k] = pose.heading_deg;
  }

  setPaths(paths) {
    this.paths = paths.map((p) => p.slice());
    this.headings = paths.map(() => null);
    this.version++;
  }

  setLimit(limit) {
    if (limit === this.limit) return;
    this.limit = limit;
    this.version++;
  }

  get longest() {
    return this.paths.reduce((m, p) => Math.max(m, p.length), 0);
  }

  // Position and heading (deg) of rover k at the shown end of its trail.
  poseOf(k) {
    const p = this.paths[k];
    if (!p || p.length === 0) return null;
    const i = Math.min(p.length - 1, this.limit);
    let heading = this.limit >= p.length - 1 && this.headings[k] !== null ? this.headings[k] : null;
    if (heading === null) {
      // From the last move that changed the position.
      for (let j = i; j > 0; j--) {
        const dx = p[j][0] - p[j - 1][0], dy = p[j][1] - p[j - 1][1];
        if (dx || dy) {
          heading = (Math.atan2(dy, dx) * 180) / Math.PI;
          break;
        }
      }
    }
    return { x: p[i][0], y: p[i][1], heading: heading ?? 0 };
  }
}

export class TrailLayer {
  constructor(view) {
    this.view = view;
    this.sets = [];
    this.cache = document.createElement('canvas');
    this.cctx = this.cache.getContext('2d');
    this.key = '';
    this.drawn = new Map();  // set → per-rover count of points already in the cache
  }

  add(set) {
    this.sets.push(set);
    this.key = '';
    return set;
  }

  remove(set) {
    this.sets = this.sets.filter((s) => s !== set);
    this.key = '';
  }

  draw(ctx, view, opacity, showTrails) {
    const { cache, cctx } = this;
    const dpr = view.dpr;
    if (cache.width !== view.canvas.width || cache.height !== view.canvas.height) {
      cache.width = view.canvas.width;
      cache.height = view.canvas.height;
      this.key = '';
    }
    if (showTrails) {
      const key = `${view.viewVersion}|${this.sets.map((s) => s.version).join(',')}|${this.sets.length}`;
      if (key !== this.key) {
        this.key = key;
        cctx.setTransform(1, 0, 0, 1, 0, 0);
        cctx.clearRect(0, 0, cache.width, cache.height);
        this.drawn = new Map();
      }
      cctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      for (const set of this.sets) this.drawNew(set, view);
      ctx.save();
      ctx.setTransform(1, 0, 0, 1, 0, 0);
      ctx.globalAlpha = opacity;
      ctx.drawImage(cache, 0, 0);
      ctx.restore();
    }
    for (const set of this.sets) this.drawRovers(ctx, view, set);
  }

  drawNew(set, view) {
    const ctx = this.cctx;
    let counts = this.drawn.get(set);
    if (!counts) {
      counts = [];
      this.drawn.set(set, counts);
    }
    ctx.lineJoin = 'round';
    ctx.lineCap = 'round';
    ctx.lineWidth = set.style.width;
    ctx.globalAlpha = set.style.alpha;
    ctx.setLineDash(set.style.dash || []);
    set.paths.forEach((path, k) => {
      const end = Math.min(path.length, set.limit + 1);
      const from = Math.max(0, (counts[k] || 0) - 1);
      if (end - from < 2) {
        counts[k] = Math.max(counts[k] || 0, end);
        return;
      }
      ctx.strokeStyle = roverColour(k + (set.style.colourOffset || 0));
      ctx.beginPath();
      let [lx, ly] = view.worldToScreen(path[from][0], path[from][1]);
      ctx.moveTo(lx, ly);
      for (let i = from + 1; i < end; i++) {
        const [sx, sy] = view.worldToScreen(path[i][0], path[i][1]);
        // Skip sub-pixel steps (long trails zoomed out), but always end on the last point.
        if (i < end - 1 && Math.abs(sx - lx) < 0.75 && Math.abs(sy - ly) < 0.75) continue;
        ctx.lineTo(sx, sy);
        lx = sx;
        ly = sy;
      }
      ctx.stroke();
      counts[k] = end;
    });
  }

  drawRovers(ctx, view, set) {
    ctx.save();
    set.paths.forEach((path, k) => {
      const pose = set.poseOf(k);
      if (!pose) return;
      const [sx, sy] = view.worldToScreen(pose.x, pose.y);
      const a = (-pose.heading * Math.PI) / 180;  // screen y points down
      ctx.translate(sx, sy);
      ctx.rotate(a);
      ctx.beginPath();
      ctx.moveTo(9, 0);
      ctx.lineTo(-6, 6);
      ctx.lineTo(-3, 0);
      ctx.lineTo(-6, -6);
      ctx.closePath();
      const colour = roverColour(k + (set.style.colourOffset || 0));
      ctx.globalAlpha = 1;
      if (set.style.hollow) {
        // The believed pose (localisation error): an outline in the rover's colour.
        ctx.strokeStyle = colour;
        ctx.lineWidth = 2;
        ctx.stroke();
      } else {
        ctx.fillStyle = colour;
        ctx.strokeStyle = '#000';
        ctx.lineWidth = 1.5;
        ctx.fill();
        ctx.stroke();
      }
      ctx.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    });
    ctx.restore();
  }
}
