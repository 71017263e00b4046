// The route profile of one rover (issue 27; QGroundControl's and MMGIS's elevation profile): its
// elevation, the slope along its track, its roll and its pitch against the distance driven, from
// the run's result.json (the rover's path and its roll_deg_rover_k / pitch_deg_rover_k series) and
// the map's elevation raster (the cursor readout's float32 layer). The slope panel has the map's
// class bands (high risk from 10°, impassable from 15°, or the mission's own high_risk_deg /
// impassable_deg), the roll and pitch panels the mission's attitude limit (metrics
// attitude_limit_deg); samples past the limit are marked red. A click on a trail (pan tool) or the
// rover menu chooses the rover; hovering the chart moves a marker on the map and in the 3D view;
// CSV and PNG export.
//
// Samples: series point i (x = mission time in s for team missions, a move number for coverage)
// is path point round(x / Δx) — one path point a second (team) or a move (coverage), as the
// replay's clock assumes (mission_view.js missionClockTimes).

import { ticks } from './charts.js';
import { state } from './state.js';
import { $, el, fmt, roverColour } from './util.js';

const PANELS = [
  { key: 'elevation', title: 'elevation (m)' },
  { key: 'slope', title: 'slope along track (°)' },
  { key: 'roll', title: 'roll (°)' },
  { key: 'pitch', title: 'pitch (°)' },
];
const OVER = '#ff3b3b';
const HIT_PX = 6;  // a click this close to a trail picks its rover

export class RouteProfile {
  constructor({ view, layers, missionView }) {
    this.view = view;
    this.layers = layers;
    this.missionView = missionView;
    this.rover = -1;
    this.data = null;     // {rover, d[], x[], y[], elevation[], slope[], roll[], pitch[], over[], limit, classes}
    this.hover = -1;      // the sample under the chart's cursor
    this.onHover = () => {};  // set by the page: the 3D view's marker follows
    this.canvas = $('profile-chart');
    this.select = $('profile-rover');
    this.select.addEventListener('change', () => this.choose(Number(this.select.value)));
    $('profile-csv').addEventListener('click', () => this.exportCsv());
    $('profile-png').addEventListener('click', () => this.exportPng());
    this.canvas.addEventListener('mousemove', (e) => this.hoverAt(e));
    this.canvas.addEventListener('mouseleave', () => this.setHover(-1));
    view.addLayer({ id: 'profile-marker', order: 60, draw: (ctx, v) => this.drawMarker(ctx, v) });
    this.bindTrailClicks();
    new ResizeObserver(() => this.draw()).observe(this.canvas);
    state.on('elevation', () => this.choose(this.rover));  // elevations arrive after the result
  }

  // The mission view has a result (or none): the menu lists its rovers, 1-based.
  update() {
    const r = this.missionView.result;
    const n = r ? r.rovers.length : 0;
    this.select.replaceChildren(el('option', { value: '-1' }, n ? 'choose a rover (or click its trail)' : 'after the run'),
      ...Array.from({ length: n }, (_, k) => el('option', { value: String(k) }, `rover ${k + 1}`)));
    this.select.disabled = !n;
    this.choose(this.rover < n ? this.rover : -1);
  }

  choose(k) {
    this.rover = k;
    this.select.value = String(k);
    this.data = k >= 0 ? this.compute(k) : null;
    this.hover = -1;
    this.onHover(null);
    $('profile-csv').disabled = !this.data;
    $('profile-png').disabled = !this.data;
    this.renderSummary();
    this.draw();
    this.view.invalidate();
  }

  compute(k) {
    const r = this.missionView.result;
    const rv = r?.rovers?.[k];
    if (!rv || !rv.path || rv.path.length === 0) return null;
    const path = rv.path;
    const cum = new Float64Array(path.length);
    for (let j = 1; j < path.length; j++) cum[j] = cum[j - 1] + Math.hypot(path[j][0] - path[j - 1][0], path[j][1] - path[j - 1][1]);
    const series = r.series || {};
    const pitchS = series[`pitch_deg_rover_${k}`], rollS = series[`roll_deg_rover_${k}`];
    const base = pitchS || rollS;
    // Without attitude series: every path point, elevation and slope only.
    const xs = base ? base.x : path.map((_, j) => j);
    const dx = xs.length > 1 ? xs[1] - xs[0] : 1;
    const n = xs.length;
    const out = { rover: k, unit: base ? base.x_label : 'point', t: [], index: [], d: [], x: [], y: [], elevation: [], slope: [], roll: [], pitch: [], over: [] };
    const params = r.spec?.params || {};
    out.limit = Number(r.metrics?.attitude_limit_deg ?? params.exceedance_limit ?? 15);
    out.classes = { highRisk: Number(params.high_risk_deg ?? 10), impassable: Number(params.impassable_deg ?? 15) };
    for (let i = 0; i < n; i++) {
      const j = Math.min(path.length - 1, Math.max(0, Math.round(xs[i] / (dx > 0 ? dx : 1))));
      const [x, y] = path[j];
      const z = this.layers.sample('elevation', x, y);
      out.t.push(xs[i]);
      out.index.push(j);
      out.d.push(cum[j]);
      out.x.push(x);
      out.y.push(y);
      out.elevation.push(z === undefined || Number.isNaN(z) ? null : z);
      out.roll.push(rollS ? rollS.y[i] : null);
      out.pitch.push(pitchS ? pitchS.y[i] : null);
      const worst = Math.max(Math.abs(rollS ? rollS.y[i] : 0), Math.abs(pitchS ? pitchS.y[i] : 0));
      out.over.push(worst > out.limit);
    }
    // Slope along the track: the rise over a run of at least two map cells back along the track
    // (a shorter run, e.g. a turn on the spot, would divide the elevation's noise by ~0).
    const m = state.map;
    const run = m ? 2 * Math.max(m.cell_size_m, m.cell_height_m ?? m.cell_size_m) : 0.5;
    out.run = run;
    for (let i = 0, b = 0; i < n; i++) {
      while (b + 1 < i && out.d[i] - out.d[b + 1] >= run) b++;
      const zi = out.elevation[i], zb = out.elevation[b];
      out.slope.push(out.d[i] - out.d[b] >= run && zi !== null && zb !== null
        ? (Math.atan2(zi - zb, out.d[i] - out.d[b]) * 180) / Math.PI : i > 0 ? out.slope[i - 1] : null);
    }
    return out;
  }

  renderSummary() {
    const d = this.data, box = $('profile-summary');
    if (!d) {
      box.textContent = this.missionView.result ? 'Choose a rover, or click its trail on the map.' : '';
      return;
    }
    const over = d.over.filter(Boolean).length;
    const last = d.d.length ? d.d[d.d.length - 1] : 0;
    box.textContent = `rover ${d.rover + 1}: ${fmt(last)} m, ${d.d.length} samples · attitude limit ${fmt(Number(d.limit.toPrecision(4)))}°: ` +
      (over ? `${over} sample${over === 1 ? '' : 's'} over (red)` : 'none over') +
      (d.roll.every((v) => v === null) ? ' · no roll series for this planner' : '');
  }

  // --- the chart: four panels side by side, distance along x ---
  layout() {
    const r = this.canvas.getBoundingClientRect();
    const w = Math.max(10, Math.round(r.width)), h = Math.max(10, Math.round(r.height));
    const gap = 8, pw = (w - gap * (PANELS.length - 1)) / PANELS.length;
    return { w, h, panels: PANELS.map((p, i) => ({ ...p, left: i * (pw + gap), width: pw })) };
  }

  draw() {
    const c = this.canvas;
    const { w, h, panels } = this.layout();
    const dpr = window.devicePixelRatio || 1;
    if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    const ctx = c.getContext('2d');
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    this.paint(ctx, w, h, panels);
  }

  paint(ctx, w, h, panels) {
    ctx.fillStyle = '#161b21';
    ctx.fillRect(0, 0, w, h);
    ctx.font = '10px system-ui, sans-serif';
    const d = this.data;
    if (!d) {
      ctx.fillStyle = '#93a1b2';
      ctx.textAlign = 'center';
      ctx.textBaseline = 'middle';
      ctx.fillText(this.missionView.result ? 'choose a rover, or click its trail on the map' : 'route profile: after the run', w / 2, h / 2);
      return;
    }
    const dMax = d.d[d.d.length - 1] || 1;
    this.scales = [];
    for (const p of panels) {
      const values = d[p.key];
      const L = p.left + 34, R = p.left + p.width - 4, T = 14, B = h - 16;
      const finite = values.filter((v) => v !== null && Number.isFinite(v));
      const refs = [];
      if (p.key === 'slope') refs.push(d.classes.highRisk, -d.classes.highRisk, d.classes.impassable, -d.classes.impassable);
      if (p.key === 'roll' || p.key === 'pitch') refs.push(d.limit, -d.limit);
      let lo = Math.min(...finite, ...refs), hi = Math.max(...finite, ...refs);
      if (!Number.isFinite(lo)) [lo, hi] = [0, 1];
      if (!(hi > lo)) hi = lo + 1;
      const pad = (hi - lo) * 0.05;
      lo -= pad;
      hi += pad;
      const px = (v) => L + (v / dMax) * (R - L), py = (v) => B - ((v - lo) / (hi - lo)) * (B - T);
      this.scales.push({ L, R, dMax });
      ctx.fillStyle = '#c9d3df';
      ctx.textAlign = 'left';
      ctx.textBaseline = 'top';
      ctx.fillText(p.title, p.left + 4, 1);
      // Class bands of the slope: high risk (amber) and impassable (red), both signs.
      if (p.key === 'slope') {
        const band = (a, b, colour) => {
          const y0 = py(Math.min(b, hi)), y1 = py(Math.max(a, lo));
          if (y1 > y0) {
            ctx.fillStyle = colour;
            ctx.fillRect(L, y0, R - L, y1 - y0);
          }
        };
        band(d.classes.highRisk, d.classes.impassable, 'rgba(240,180,76,0.18)');
        band(-d.classes.impassable, -d.classes.highRisk, 'rgba(240,180,76,0.18)');
        band(d.classes.impassable, Math.max(hi, d.classes.impassable), 'rgba(255,59,59,0.18)');
        band(Math.min(lo, -d.classes.impassable), -d.classes.impassable, 'rgba(255,59,59,0.18)');
      }
      // Axes and ticks.
      ctx.strokeStyle = 'rgba(147,161,178,0.15)';
      ctx.fillStyle = '#93a1b2';
      ctx.lineWidth = 1;
      ctx.textAlign = 'right';
      ctx.textBaseline = 'middle';
      for (const t of ticks(lo, hi, 4)) {
        ctx.beginPath();
        ctx.moveTo(L, py(t));
        ctx.lineTo(R, py(t));
        ctx.stroke();
        ctx.fillText(fmt(t), L - 3, py(t));
      }
      ctx.textAlign = 'center';
      ctx.textBaseline = 'top';
      for (const t of ticks(0, dMax, 3)) ctx.fillText(`${fmt(t)} m`, px(t), B + 3);
      // Reference lines: class limits (dashed amber/red), attitude limit (red).
      const refLine = (v, colour, dash, label, left = false) => {
        if (v < lo || v > hi) return;
        ctx.strokeStyle = colour;
        ctx.setLineDash(dash);
        ctx.beginPath();
        ctx.moveTo(L, py(v));
        ctx.lineTo(R, py(v));
        ctx.stroke();
        ctx.setLineDash([]);
        if (label) {
          ctx.fillStyle = colour;
          ctx.textAlign = left ? 'left' : 'right';
          ctx.textBaseline = v >= 0 ? 'bottom' : 'top';
          ctx.fillText(label, left ? L + 2 : R - 2, py(v) + (v >= 0 ? -1 : 1));
        }
      };
      const deg = (v) => `${fmt(Number(v.toPrecision(4)))}°`;
      if (p.key === 'slope') {
        for (const s of [1, -1]) {
          refLine(s * d.classes.highRisk, '#f0b44c', [4, 3], s > 0 ? `high risk ${deg(d.classes.highRisk)}` : '', true);
          refLine(s * d.classes.impassable, OVER, [4, 3], s > 0 ? `impassable ${deg(d.classes.impassable)}` : '');
        }
      }
      if (p.key === 'roll' || p.key === 'pitch') for (const s of [1, -1]) refLine(s * d.limit, OVER, [], s > 0 ? `limit ±${deg(d.limit)}` : '');
      if (!finite.length) {
        ctx.fillStyle = '#93a1b2';
        ctx.textAlign = 'center';
        ctx.textBaseline = 'middle';
        ctx.fillText('no series', (L + R) / 2, (T + B) / 2);
        continue;
      }
      // The line.
      ctx.strokeStyle = roverColour(d.rover);
      ctx.lineWidth = 1.25;
      ctx.beginPath();
      let pen = false;
      values.forEach((v, i) => {
        if (v === null || !Number.isFinite(v)) {
          pen = false;
          return;
        }
        if (pen) ctx.lineTo(px(d.d[i]), py(v));
        else ctx.moveTo(px(d.d[i]), py(v));
        pen = true;
      });
      ctx.stroke();
      // Samples over the attitude limit: red dots on roll/pitch, red ticks under every panel.
      ctx.fillStyle = OVER;
      d.over.forEach((o, i) => {
        if (!o) return;
        const x = px(d.d[i]);
        ctx.fillRect(x - 0.5, B - 3, 1.5, 3);
        const v = values[i];
        if ((p.key === 'roll' || p.key === 'pitch') && v !== null && Math.abs(v) > d.limit) {
          ctx.beginPath();
          ctx.arc(x, py(v), 2, 0, 2 * Math.PI);
          ctx.fill();
        }
      });
      // The hover cursor.
      if (this.hover >= 0) {
        const x = px(d.d[this.hover]);
        ctx.strokeStyle = '#ffffff';
        ctx.beginPath();
        ctx.moveTo(x, T);
        ctx.lineTo(x, B);
        ctx.stroke();
        const v = values[this.hover];
        ctx.fillStyle = '#ffffff';
        ctx.textAlign = x > (L + R) / 2 ? 'right' : 'left';
        ctx.textBaseline = 'top';
        ctx.fillText(v === null ? '—' : fmt(v), x + (x > (L + R) / 2 ? -3 : 3), T);
      }
    }
  }

  hoverAt(e) {
    const d = this.data;
    if (!d || !this.scales) return;
    const r = this.canvas.getBoundingClientRect();
    const mx = e.clientX - r.left;
    const s = this.scales.find((q) => mx >= q.L - 4 && mx <= q.R + 4);
    if (!s) return this.setHover(-1);
    const dist = Math.min(Math.max(((mx - s.L) / (s.R - s.L)) * s.dMax, 0), s.dMax);
    // The sample nearest that distance (d is non-decreasing: binary search).
    let lo = 0, hi = d.d.length - 1;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (d.d[mid] < dist) lo = mid + 1;
      else hi = mid;
    }
    if (lo > 0 && dist - d.d[lo - 1] < d.d[lo] - dist) lo--;
    this.setHover(lo);
  }

  setHover(i) {
    if (i === this.hover) return;
    this.hover = i;
    const d = this.data;
    $('profile-readout').textContent = d && i >= 0
      ? `${fmt(d.d[i])} m · x ${d.x[i].toFixed(1)} y ${d.y[i].toFixed(1)} · elevation ${d.elevation[i] === null ? '—' : `${d.elevation[i].toFixed(2)} m`} · slope ${fmt(d.slope[i])}° · roll ${fmt(d.roll[i])}° · pitch ${fmt(d.pitch[i])}°${d.over[i] ? ' · over the limit' : ''}`
      : '';
    this.draw();
    this.view.invalidate();
    this.onHover(d && i >= 0 ? { x: d.x[i], y: d.y[i] } : null);
  }

  drawMarker(ctx, view) {
    const d = this.data;
    if (!d || this.hover < 0) return;
    const [sx, sy] = view.worldToScreen(d.x[this.hover], d.y[this.hover]);
    ctx.beginPath();
    ctx.arc(sx, sy, 7, 0, 2 * Math.PI);
    ctx.lineWidth = 3;
    ctx.strokeStyle = '#000';
    ctx.stroke();
    ctx.lineWidth = 2;
    ctx.strokeStyle = d.over[this.hover] ? OVER : '#ffffff';
    ctx.stroke();
  }

  // --- choosing a rover by clicking its trail (pan tool, a click not a drag) ---
  bindTrailClicks() {
    this.view.onPanClick((p) => {
      const k = this.trailAt(p.sx, p.sy);
      if (k < 0) return;
      this.choose(k);
      $('dock-tab-profile').click();
    });
  }

  // The rover whose trail passes within HIT_PX of a screen point, or -1.
  trailAt(sx, sy) {
    const r = this.missionView.result;
    if (!r) return -1;
    let best = -1, bestD = HIT_PX;
    r.rovers.forEach((rv, k) => {
      const p = rv.path || [];
      let [ax, ay] = this.view.worldToScreen(p[0]?.[0] ?? 0, p[0]?.[1] ?? 0);
      for (let j = 1; j < p.length; j++) {
        const [bx, by] = this.view.worldToScreen(p[j][0], p[j][1]);
        const vx = bx - ax, vy = by - ay, len2 = vx * vx + vy * vy;
        const t = len2 > 0 ? Math.min(1, Math.max(0, ((sx - ax) * vx + (sy - ay) * vy) / len2)) : 0;
        const dd = Math.hypot(sx - (ax + t * vx), sy - (ay + t * vy));
        if (dd < bestD) {
          bestD = dd;
          best = k;
        }
        ax = bx;
        ay = by;
      }
    });
    return best;
  }

  // --- exports ---
  csv() {
    const d = this.data;
    const num = (v, digits) => (v === null || v === undefined || !Number.isFinite(v) ? '' : Number(v.toFixed(digits)).toString());
    const head = `rover,${d.unit === 'time (s)' ? 'time_s' : d.unit === 'move' ? 'move' : 'point'},distance_m,x_m,y_m,elevation_m,slope_along_track_deg,roll_deg,pitch_deg,over_attitude_limit`;
    const rows = d.d.map((_, i) => [d.rover + 1, num(d.t[i], 3), num(d.d[i], 3), num(d.x[i], 3), num(d.y[i], 3), num(d.elevation[i], 3),
      num(d.slope[i], 3), num(d.roll[i], 4), num(d.pitch[i], 4), d.over[i] ? 1 : 0].join(','));
    return `${head}\n${rows.join('\n')}\n`;
  }

  download(href, name) {
    const a = el('a', { href, download: name });
    document.body.append(a);
    a.click();
    a.remove();
  }

  baseName() {
    return `roverplan-${this.missionView.mission?.id || 'mission'}-rover${this.data.rover + 1}-profile`;
  }

  exportCsv() {
    if (!this.data) return;
    const url = URL.createObjectURL(new Blob([this.csv()], { type: 'text/csv' }));
    this.download(url, `${this.baseName()}.csv`);
    setTimeout(() => URL.revokeObjectURL(url), 10000);
  }

  // The chart at twice its size, with a title line.
  exportPng() {
    if (!this.data) return;
    const { w, h, panels } = this.layout();
    const k = 2, title = 18;
    const c = document.createElement('canvas');
    c.width = w * k;
    c.height = (h + title) * k;
    const ctx = c.getContext('2d');
    ctx.scale(k, k);
    ctx.fillStyle = '#161b21';
    ctx.fillRect(0, 0, w, h + title);
    ctx.fillStyle = '#e6edf3';
    ctx.font = '11px system-ui, sans-serif';
    ctx.textBaseline = 'middle';
    ctx.fillText(`${this.missionView.mission?.label || this.missionView.mission?.id || ''} — ${$('profile-summary').textContent}`, 4, title / 2);
    ctx.translate(0, title);
    const hover = this.hover;
    this.hover = -1;
    this.paint(ctx, w, h, panels);
    this.hover = hover;
    this.download(c.toDataURL('image/png'), `${this.baseName()}.png`);
  }
}
