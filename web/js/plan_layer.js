// A team mission's plan over the map (server stream "overlay" frames, result.json "overlays"):
// the team route through the search cells (white, numbered targets) and each rover's planned
// RRT* path as it is accepted (thin, in the rover's colour, under its simulated trail).

import { roverColour } from './util.js';

export class PlanLayer {
  constructor() {
    this.clear();
  }

  clear() {
    this.route = [];  // [[x, y]...]: the start cell's centre, then the targets
    this.paths = [];  // per rover: [[x, y]...]
  }

  get empty() {
    return this.route.length === 0 && this.paths.every((p) => p.length === 0);
  }

  // A snapshot's or an overlay frame's {route?, paths?}; snapshot paths are whole, frame paths append.
  apply(msg, whole = false) {
    if (Array.isArray(msg.route)) this.route = msg.route.map((p) => [p[0], p[1]]);
    if (whole && Array.isArray(msg.paths)) {
      this.paths = msg.paths.map((p) => p.map((q) => [q[0], q[1]]));
      return;
    }
    for (const p of msg.paths || []) {
      while (this.paths.length <= p.rover) this.paths.push([]);
      for (const q of p.append) this.paths[p.rover].push([q[0], q[1]]);
    }
  }

  // result.json's overlays: [{key, rover, points}].
  setFromResult(overlays) {
    this.clear();
    for (const o of overlays || []) {
      if (o.key === 'route') this.route = o.points;
      else if (o.key === 'path') {
        while (this.paths.length <= o.rover) this.paths.push([]);
        this.paths[o.rover] = o.points;
      }
    }
  }

  draw(ctx, view, opacity) {
    if (this.empty) return;
    ctx.save();
    ctx.globalAlpha = opacity;
    ctx.lineJoin = 'round';
    this.paths.forEach((path, k) => {
      if (path.length < 2) return;
      ctx.strokeStyle = roverColour(k);
      ctx.lineWidth = 1;
      ctx.setLineDash([3, 3]);
      ctx.beginPath();
      path.forEach(([x, y], i) => {
        const [sx, sy] = view.worldToScreen(x, y);
        if (i === 0) ctx.moveTo(sx, sy);
        else ctx.lineTo(sx, sy);
      });
      ctx.stroke();
    });
    ctx.setLineDash([]);
    if (this.route.length > 0) {
      ctx.strokeStyle = 'rgba(255,255,255,0.85)';
      ctx.lineWidth = 2;
      ctx.beginPath();
      this.route.forEach(([x, y], i) => {
        const [sx, sy] = view.worldToScreen(x, y);
        if (i === 0) ctx.moveTo(sx, sy);
        else ctx.lineTo(sx, sy);
      });
      ctx.stroke();
      ctx.fillStyle = '#fff';
      ctx.font = '10px sans-serif';
      this.route.forEach(([x, y], i) => {
        const [sx, sy] = view.worldToScreen(x, y);
        ctx.beginPath();
        ctx.arc(sx, sy, i === 0 ? 5 : 3, 0, 2 * Math.PI);
        ctx.fill();
        if (i > 0 && this.route.length <= 100) ctx.fillText(String(i), sx + 4, sy - 4);
      });
    }
    ctx.restore();
  }
}
