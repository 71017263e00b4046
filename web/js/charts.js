// Small charts on <canvas>, no library: line charts with axes (several series, optional
// horizontal reference lines) and bar charts. Sized to the canvas' CSS box, sharp on HiDPI.

import { fmt, roverColour } from './util.js';

const AXIS = '#93a1b2';
const GRID = 'rgba(147,161,178,0.15)';
const FONT = '10px system-ui, sans-serif';

function prepare(canvas) {
  const r = canvas.getBoundingClientRect();
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(10, Math.round(r.width)), h = Math.max(10, Math.round(r.height));
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
  }
  const ctx = canvas.getContext('2d');
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.clearRect(0, 0, w, h);
  ctx.font = FONT;
  return { ctx, w, h };
}

// "Nice" tick values covering [lo, hi].
export function ticks(lo, hi, count = 4) {
  if (!(hi > lo)) return [lo];
  const raw = (hi - lo) / count;
  const pow = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * pow).find((s) => s >= raw) || raw;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Number(v.toPrecision(12)));
  return out;
}

function message(ctx, w, h, text) {
  ctx.fillStyle = AXIS;
  ctx.textAlign = 'center';
  ctx.fillText(text, w / 2, h / 2);
}

// series: [{x: [], y: [], colour, label, dash}]; opts: {xLabel, yMin, yMax, xMin, xMax (a fixed x
// range, e.g. the whole mission, so charts under one replay cursor line up), refLines: [{y, label}],
// empty, cursorX}. Leaves the x scale on the canvas for chartXAt (click to seek).
export function lineChart(canvas, series, opts = {}) {
  const { ctx, w, h } = prepare(canvas);
  canvas.chartScale = null;
  const pts = series.filter((s) => s.x && s.x.length > 0);
  if (pts.length === 0) return message(ctx, w, h, opts.empty || 'no data yet');
  let xMin = Infinity, xMax = -Infinity, yMin = Infinity, yMax = -Infinity;
  for (const s of pts) {
    for (let i = 0; i < s.x.length; i++) {
      const x = s.x[i], y = s.y[i];
      if (!Number.isFinite(x) || !Number.isFinite(y)) continue;
      if (x < xMin) xMin = x;
      if (x > xMax) xMax = x;
      if (y < yMin) yMin = y;
      if (y > yMax) yMax = y;
    }
  }
  for (const r of opts.refLines || []) {
    yMin = Math.min(yMin, r.y);
    yMax = Math.max(yMax, r.y);
  }
  if (opts.refLines && opts.refLines.length) {  // room for the reference lines' labels
    const pad = 0.1 * (yMax - yMin);
    yMin -= pad;
    yMax += pad;
  }
  if (opts.yMin !== undefined) yMin = opts.yMin;
  if (opts.yMax !== undefined) yMax = Math.max(opts.yMax, yMax);
  if (opts.xMin !== undefined) xMin = opts.xMin;
  if (opts.xMax !== undefined) xMax = opts.xMax;
  if (!(xMax > xMin)) xMax = xMin + 1;
  if (!(yMax > yMin)) yMax = yMin + 1;
  const L = 40, R = 8, T = 6, B = 18;
  const px = (x) => L + ((x - xMin) / (xMax - xMin)) * (w - L - R);
  const py = (y) => h - B - ((y - yMin) / (yMax - yMin)) * (h - T - B);
  canvas.chartScale = { left: L, right: w - R, xMin, xMax };

  ctx.strokeStyle = GRID;
  ctx.fillStyle = AXIS;
  ctx.lineWidth = 1;
  ctx.textAlign = 'right';
  ctx.textBaseline = 'middle';
  for (const v of ticks(yMin, yMax, Math.max(2, Math.floor((h - T - B) / 28)))) {
    const y = Math.round(py(v)) + 0.5;
    ctx.beginPath();
    ctx.moveTo(L, y);
    ctx.lineTo(w - R, y);
    ctx.stroke();
    ctx.fillText(fmt(v), L - 4, y);
  }
  ctx.textAlign = 'center';
  ctx.textBaseline = 'top';
  for (const v of ticks(xMin, xMax, Math.max(2, Math.floor((w - L - R) / 70)))) {
    const x = Math.round(px(v)) + 0.5;
    ctx.beginPath();
    ctx.moveTo(x, T);
    ctx.lineTo(x, h - B);
    ctx.stroke();
    ctx.fillText(fmt(v), x, h - B + 3);
  }
  ctx.strokeStyle = AXIS;
  ctx.strokeRect(L + 0.5, T + 0.5, w - L - R - 1, h - T - B - 1);

  for (const r of opts.refLines || []) {
    ctx.strokeStyle = r.colour || '#ff6b6b';
    ctx.setLineDash([4, 3]);
    const y = Math.round(py(r.y)) + 0.5;
    ctx.beginPath();
    ctx.moveTo(L, y);
    ctx.lineTo(w - R, y);
    ctx.stroke();
    ctx.setLineDash([]);
    if (r.label) {
      ctx.fillStyle = r.colour || '#ff6b6b';
      ctx.textAlign = 'left';
      ctx.textBaseline = 'bottom';
      ctx.fillText(r.label, L + 3, y - 1);
    }
  }

  ctx.save();
  ctx.beginPath();
  ctx.rect(L, T, w - L - R, h - T - B);
  ctx.clip();
  pts.forEach((s, k) => {
    ctx.strokeStyle = s.colour || roverColour(k);
    ctx.lineWidth = s.width || 1.5;
    ctx.setLineDash(s.dash || []);
    ctx.beginPath();
    // At most ~2 points per pixel column.
    const stride = Math.max(1, Math.floor(s.x.length / ((w - L - R) * 2)));
    let started = false;
    for (let i = 0; i < s.x.length; i += stride) {
      const x = s.x[i], y = s.y[i];
      if (!Number.isFinite(x) || !Number.isFinite(y)) continue;
      if (started) ctx.lineTo(px(x), py(y));
      else ctx.moveTo(px(x), py(y)), (started = true);
    }
    const n = s.x.length - 1;
    if (started && n % stride !== 0) ctx.lineTo(px(s.x[n]), py(s.y[n]));
    ctx.stroke();
  });
  ctx.restore();
  if (opts.cursorX !== undefined && opts.cursorX !== null) {
    ctx.strokeStyle = '#ffd166';
    const x = Math.round(px(opts.cursorX)) + 0.5;
    ctx.beginPath();
    ctx.moveTo(x, T);
    ctx.lineTo(x, h - B);
    ctx.stroke();
  }
  if (opts.legend) {
    ctx.textAlign = 'right';
    ctx.textBaseline = 'top';
    let y = T + 2;
    pts.forEach((s, k) => {
      if (!s.label) return;
      ctx.fillStyle = s.colour || roverColour(k);
      ctx.fillText(s.label, w - R - 3, y);
      y += 12;
    });
  }
}

// The x value under a client x on a line chart drawn by lineChart, or null (no data drawn).
export function chartXAt(canvas, clientX) {
  const s = canvas.chartScale;
  if (!s) return null;
  const px = clientX - canvas.getBoundingClientRect().left;
  const f = Math.max(0, Math.min(1, (px - s.left) / (s.right - s.left)));
  return s.xMin + f * (s.xMax - s.xMin);
}

// bars: [{label, value, colour}]
export function barChart(canvas, bars, opts = {}) {
  const { ctx, w, h } = prepare(canvas);
  if (!bars.length) return message(ctx, w, h, opts.empty || 'no data yet');
  const max = Math.max(...bars.map((b) => b.value), 1e-12);
  const L = 40, R = 8, T = 14, B = 18;
  const py = (v) => h - B - (v / max) * (h - T - B);
  ctx.strokeStyle = GRID;
  ctx.fillStyle = AXIS;
  ctx.textAlign = 'right';
  ctx.textBaseline = 'middle';
  for (const v of ticks(0, max, Math.max(2, Math.floor((h - T - B) / 28)))) {
    const y = Math.round(py(v)) + 0.5;
    ctx.beginPath();
    ctx.moveTo(L, y);
    ctx.lineTo(w - R, y);
    ctx.stroke();
    ctx.fillText(fmt(v), L - 4, y);
  }
  const slot = (w - L - R) / bars.length;
  const bw = Math.min(48, slot * 0.7);
  bars.forEach((b, i) => {
    const x = L + slot * i + (slot - bw) / 2;
    ctx.fillStyle = b.colour || roverColour(i);
    ctx.fillRect(x, py(b.value), bw, h - B - py(b.value));
    ctx.fillStyle = AXIS;
    ctx.textAlign = 'center';
    ctx.textBaseline = 'top';
    ctx.fillText(b.label, x + bw / 2, h - B + 3);
    ctx.textBaseline = 'bottom';
    ctx.fillText(fmt(b.value), x + bw / 2, py(b.value) - 1);
  });
}
