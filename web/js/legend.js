// Legends the page draws itself (issue 27: the old ones were strips cut from the server's PNG,
// cropped at 1366×768): a colour ramp with ticks and a title, and class swatches with names. The
// ramps repeat the server's stops (maps/render.cpp kHypsometric, kSlope, kPerceptual) and its
// ranges (elevation: 2nd–98th percentile of the heights, nearest rank, from at most ~1M cells;
// PDM: 0 to the largest cell), computed from the float32 layers the page already loads for the
// cursor readout. Without those layers (maps over 25 M cells) the server's strip is used.

import { ticks } from './charts.js';
import { el, fmt } from './util.js';

export const HYPSOMETRIC = [[0, 38, 115, 77], [0.25, 134, 166, 84], [0.5, 224, 204, 128], [0.75, 168, 112, 66], [1, 245, 240, 232]];
export const SLOPE = [[0, 46, 158, 74], [10, 245, 222, 60], [15, 242, 140, 40], [30, 208, 38, 34], [45, 110, 12, 22]];
export const PERCEPTUAL = [[0, 48, 18, 74], [0.25, 45, 90, 145], [0.5, 30, 150, 135], [0.75, 110, 200, 90], [1, 245, 230, 50]];
// terrain::TerrainClass order, as maps/render.cpp kClassColours.
export const CLASSES = [
  { name: 'traversable', colour: 'rgb(50,170,80)', key: 'traversable_pct' },
  { name: 'high risk', colour: 'rgb(255,176,0)', key: 'high_risk_pct' },
  { name: 'impassable', colour: 'rgb(215,35,35)', key: 'impassable_pct' },
  { name: 'nodata', colour: 'rgba(40,40,40,0.63)', key: 'nodata_pct' },
];

const WIDTH = 224;  // the legend panel's inner width

export function rampColour(stops, v) {
  if (!(v > stops[0][0])) return stops[0].slice(1);
  let i = 1;
  while (i < stops.length - 1 && v > stops[i][0]) i++;
  const a = stops[i - 1], b = stops[i];
  const t = Math.min(1, Math.max(0, (v - a[0]) / (b[0] - a[0])));
  return [1, 2, 3].map((k) => Math.round(a[k] + (b[k] - a[k]) * t));
}

// The server's elevation ramp range (maps/render.cpp elevationRange), cached on the raster.
export function elevationRange(raster) {
  if (raster.range) return raster.range;
  const v = raster.data, n = v.length, stride = Math.max(1, Math.floor(n / 2 ** 20));
  const h = [];
  for (let i = 0; i < n; i += stride) if (Number.isFinite(v[i])) h.push(v[i]);
  if (!h.length && stride > 1) for (let i = 0; i < n; i++) if (Number.isFinite(v[i])) h.push(v[i]);
  const sorted = Float32Array.from(h).sort();
  let lo = 0, hi = 0;
  if (sorted.length) {
    const pct = (q) => sorted[Math.round(q * (sorted.length - 1))];
    lo = pct(0.02);
    hi = pct(0.98);
  }
  if (!(hi > lo)) {
    lo -= 0.5;
    hi += 0.5;
  }
  raster.range = { lo, hi };
  return raster.range;
}

export function maxFinite(raster) {
  if (raster.max !== undefined) return raster.max;
  let mx = 0;
  for (const x of raster.data) if (Number.isFinite(x) && x > mx) mx = x;
  raster.max = mx > 0 ? mx : 1;
  return raster.max;
}

// A horizontal ramp from lo to hi: `colourAt(v)` → [r, g, b]; ticks at nice values (or `marks`:
// [{v, label}]), every label kept inside the canvas and apart from its neighbours.
export function rampLegend({ lo, hi, colourAt, marks = null, unit = '' }) {
  const dpr = window.devicePixelRatio || 1;
  const h = 32, x0 = 6, x1 = WIDTH - 6, barH = 12;
  const c = el('canvas', { class: 'legend-drawn', width: WIDTH * dpr, height: h * dpr, style: `width:${WIDTH}px;height:${h}px` });
  const ctx = c.getContext('2d');
  ctx.scale(dpr, dpr);
  for (let x = x0; x < x1; x++) {
    const [r, g, b] = colourAt(lo + ((x - x0 + 0.5) / (x1 - x0)) * (hi - lo));
    ctx.fillStyle = `rgb(${r},${g},${b})`;
    ctx.fillRect(x, 2, 1, barH);
  }
  ctx.strokeStyle = 'rgba(255,255,255,0.5)';
  ctx.strokeRect(x0 - 0.5, 1.5, x1 - x0 + 1, barH + 1);
  // Default marks: both ends (the ramp's exact range), then the nice values between them; a nice
  // value too close to an end loses its label (below).
  const list = marks || [{ v: lo, label: fmt(lo) }, { v: hi, label: fmt(hi) },
    ...ticks(lo, hi, 5).filter((v) => v > lo && v < hi).map((v) => ({ v, label: fmt(v) }))];
  ctx.font = '10px system-ui, sans-serif';
  ctx.textBaseline = 'top';
  ctx.fillStyle = '#c9d3df';
  ctx.strokeStyle = '#c9d3df';
  // Labels in list order (ends first): one that would overlap a label already drawn is left out
  // (its tick stays). The unit goes after the highest value.
  const drawn = [];
  const top = list.reduce((a, m) => (m.v > a ? m.v : a), -Infinity);
  for (const m of list) {
    const x = x0 + ((m.v - lo) / (hi - lo)) * (x1 - x0);
    const text = m.v === top && unit ? `${m.label} ${unit}` : m.label;
    const w = ctx.measureText(text).width;
    const left = Math.min(Math.max(x - w / 2, 0), WIDTH - w);
    ctx.beginPath();
    ctx.moveTo(Math.round(x) + 0.5, 3 + barH);
    ctx.lineTo(Math.round(x) + 0.5, 6 + barH);
    ctx.stroke();
    if (drawn.some(([a, b]) => left < b + 4 && a < left + w + 4)) continue;
    ctx.fillText(text, left, 7 + barH);
    drawn.push([left, left + w]);
  }
  return c;
}

// Class swatches: [{colour, name, note}] in a two-column grid (one column when they have notes).
export function classLegend(items) {
  return el('div', { class: `legend-classes${items.some((it) => it.note) ? ' one-column' : ''}` }, items.map((it) => el('span', { class: 'legend-class' },
    el('span', { class: 'swatch', style: `background:${it.colour}` }), it.name, it.note ? el('span', { class: 'muted' }, ` ${it.note}`) : null)));
}
