// A team mission's plan over the map (server stream "overlay" frames, result.json "overlays"):
// the team route through the search cells (white, numbered targets) and each rover's planned
// RRT* path as it is accepted (thin, in the rover's colour, under its simulated trail).
// Target numbers are decluttered (issue 27: "596061626364"): a number is drawn only where it
// overlaps no number already drawn (route order first), and the target nearest the cursor always
// shows its number, boxed.

import { roverColour } from './util.js';

export class PlanLayer {
  constructor() {
    this.clear();
    this.hover = null;    // the cursor on the map {sx, sy}, or null
    this.labelled = [];   // the targets whose numbers the last frame drew (tests read it)
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
      ctx.textBaseline = 'alphabetic';
      const screen = this.route.map(([x, y]) => view.worldToScreen(x, y));
      for (const [i, [sx, sy]] of screen.entries()) {
        ctx.beginPath();
        ctx.arc(sx, sy, i === 0 ? 5 : 3, 0, 2 * Math.PI);
        ctx.fill();
      }
      // The hovered target: the nearest within 12 px of the cursor.
      let hovered = -1, best = 12;
      if (this.hover) {
        screen.forEach(([sx, sy], i) => {
          const d = Math.hypot(sx - this.hover.sx, sy - this.hover.sy);
          if (i > 0 && d < best) {
            best = d;
            hovered = i;
          }
        });
      }
      const boxes = [];
      const box = (i) => {
        const [sx, sy] = screen[i];
        const w = ctx.measureText(String(i)).width;
        return [sx + 4, sy - 13, w, 10];
      };
      const hit = (a, b) => a[0] < b[0] + b[2] + 2 && b[0] < a[0] + a[2] + 2 && a[1] < b[1] + b[3] + 1 && b[1] < a[1] + a[3] + 1;
      if (hovered > 0) boxes.push(box(hovered));
      this.labelled = [];
      for (let i = 1; i < screen.length; i++) {
        if (i === hovered) continue;
        const b = box(i);
        if (boxes.some((o) => hit(o, b))) continue;
        boxes.push(b);
        this.labelled.push(i);
        ctx.fillText(String(i), b[0], screen[i][1] - 4);
      }
      if (hovered > 0) {
        const b = box(hovered);
        ctx.fillStyle = 'rgba(0,0,0,0.8)';
        ctx.fillRect(b[0] - 2, b[1] - 1, b[2] + 4, b[3] + 3);
        ctx.fillStyle = '#ffd23f';
        ctx.fillText(String(hovered), b[0], screen[hovered][1] - 4);
        this.labelled.push(hovered);
      }
    }
    ctx.restore();
  }
}
