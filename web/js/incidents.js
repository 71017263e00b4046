// A finished mission's incidents (result.json `incidents`: short and skipped legs, slot-less
// targets, attitude exceedances, collisions, coverage bumps): a list in the dock (kind, rover,
// time, place), marks on the replay clock's strip and markers on the map (a toggleable layer).
// Choosing one anywhere selects it everywhere: the clock seeks to its time, the map centres on it
// and rings it, its row is highlighted.

import { clockText } from './mission_clock.js';
import { IncidentKind } from './outcomes.js';
import { el, fmt } from './util.js';

// Colour and marker shape per kind; unknown kinds get the last one.
export const INCIDENT_KINDS = {
  [IncidentKind.Collision]: { colour: '#ff3b3b', shape: 'cross', label: 'collision (rovers too close)' },
  [IncidentKind.Exceedance]: { colour: '#ff9f1a', shape: 'triangle', label: 'roll/pitch over the limit' },
  [IncidentKind.Short]: { colour: '#ffe14d', shape: 'circle', label: 'short leg (ended away from its target)' },
  [IncidentKind.Skipped]: { colour: '#e056fd', shape: 'square', label: 'skipped leg' },
  [IncidentKind.NoSlot]: { colour: '#b0b8c4', shape: 'diamond', label: 'target without ground for its slot' },
  [IncidentKind.Bump]: { colour: '#ff6b6b', shape: 'triangle', label: 'bump (move into an unmapped obstacle)' },
  other: { colour: '#ffffff', shape: 'circle', label: 'other' },
};
const MIN_SCALE = 8;  // px/m the map zooms in to, at least, to show a chosen incident
const kindOf = (k) => INCIDENT_KINDS[k] || INCIDENT_KINDS.other;

function marker(ctx, shape, x, y, r) {
  ctx.beginPath();
  if (shape === 'circle') ctx.arc(x, y, r, 0, 2 * Math.PI);
  else if (shape === 'square') ctx.rect(x - r, y - r, 2 * r, 2 * r);
  else if (shape === 'diamond') ctx.moveTo(x, y - r), ctx.lineTo(x + r, y), ctx.lineTo(x, y + r), ctx.lineTo(x - r, y), ctx.closePath();
  else if (shape === 'triangle') ctx.moveTo(x, y - r * 1.2), ctx.lineTo(x + r, y + r * 0.8), ctx.lineTo(x - r, y + r * 0.8), ctx.closePath();
  else {  // cross
    const a = r * 0.45;
    for (const [dx, dy] of [[1, 1], [1, -1], [-1, -1], [-1, 1]]) {
      ctx.lineTo(x + dx * a, y);
      ctx.lineTo(x + dx * r, y + dy * (r - a));
      ctx.lineTo(x + dx * (r - a), y + dy * r);
      ctx.lineTo(x, y + dy * a);
    }
    ctx.closePath();
  }
  ctx.fill();
  ctx.stroke();
}

export class Incidents {
  // onSelect(item): seek the replay to item.at.
  constructor({ view, list, summary, count, onSelect }) {
    this.view = view;
    this.list = list;
    this.summary = summary;
    this.count = count;
    this.onSelect = onSelect;
    this.items = [];
    this.selected = -1;
    this.unit = 's';
    this.rows = [];
    this.render();
  }

  // result: result.json; unit 's' (team: time_s) or 'step' (coverage: the incident's step).
  set(result, unit) {
    this.unit = unit;
    this.selected = -1;
    this.items = (result?.incidents || []).map((inc, i) => ({
      ...inc, index: i, at: unit === 's' ? Number(inc.time_s) || 0 : Number(inc.step ?? 0),
    }));
    this.render();
  }

  clear() {
    this.set(null, 's');
  }

  when(item) {
    return this.unit === 's' ? clockText(item.at) : `step ${fmt(item.at)}`;
  }

  render() {
    const n = this.items.length;
    this.count.textContent = String(n);
    this.count.dataset.count = String(n);
    const byKind = new Map();
    for (const it of this.items) byKind.set(it.kind, (byKind.get(it.kind) || 0) + 1);
    this.summary.replaceChildren(n === 0
      ? 'no incidents'
      : el('span', { class: 'swatches' }, [...byKind].map(([k, c]) =>
        el('span', { title: kindOf(k).label }, el('span', { class: 'swatch', style: `background:${kindOf(k).colour}` }), `${k.replace(/_/g, ' ')} ${fmt(c)}`))));
    this.rows = this.items.map((it) => el('tr', {
      tabindex: '0', dataset: { incident: String(it.index) }, title: it.note || '',
      onclick: () => this.select(it.index), onkeydown: (e) => { if (e.key === 'Enter') this.select(it.index); },
    },
    el('td', {}, el('span', { class: 'swatch', style: `background:${kindOf(it.kind).colour}` }), it.kind.replace(/_/g, ' ')),
    el('td', {}, `rover ${it.rover + 1}${it.other !== undefined ? ` · ${it.other + 1}` : ''}`),
    el('td', { class: 'num' }, this.when(it)),
    el('td', { class: 'num' }, `${it.x.toFixed(1)}, ${it.y.toFixed(1)} m`),
    el('td', { class: 'note' }, it.note || '')));
    this.list.replaceChildren(...this.rows);
  }

  // Select item i (or none with -1): highlight its row, ring it on the map, centre the map on it
  // and let the replay seek to it.
  select(i, { seek = true, centre = true } = {}) {
    const prev = this.rows[this.selected];
    if (prev) prev.classList.remove('selected');
    this.selected = i;
    const it = this.items[i];
    if (!it) return this.view.invalidate();
    const row = this.rows[i];
    row.classList.add('selected');
    row.scrollIntoView({ block: 'nearest' });
    if (centre) {
      // Close enough to tell neighbouring markers apart (a 150 m map fits at ~3 px/m).
      const v = this.view;
      if (v.scale < MIN_SCALE) v.scale = MIN_SCALE;
      v.cx = it.x;
      v.cy = it.y;
      v.viewChanged();
    }
    if (seek) this.onSelect(it);
    this.view.invalidate();
  }

  // Marks for the clock's strip, in item order.
  marks() {
    return this.items.map((it, i) => ({ at: it.at, colour: kindOf(it.kind).colour, selected: i === this.selected }));
  }

  // The map layer: a marker per incident, the selected one ringed and drawn last.
  draw(ctx, view, opacity) {
    if (!this.items.length) return;
    ctx.save();
    ctx.globalAlpha = opacity;
    ctx.lineWidth = 1;
    ctx.strokeStyle = '#000000b0';
    const r = 5;
    for (const it of this.items) {
      if (it.index === this.selected) continue;
      const [sx, sy] = view.worldToScreen(it.x, it.y);
      if (sx < -r || sy < -r || sx > view.cssW + r || sy > view.cssH + r) continue;
      ctx.fillStyle = kindOf(it.kind).colour;
      marker(ctx, kindOf(it.kind).shape, sx, sy, r);
    }
    const sel = this.items[this.selected];
    if (sel) {
      const [sx, sy] = view.worldToScreen(sel.x, sel.y);
      ctx.globalAlpha = 1;
      ctx.fillStyle = kindOf(sel.kind).colour;
      marker(ctx, kindOf(sel.kind).shape, sx, sy, r + 2);
      ctx.strokeStyle = '#ffffff';
      ctx.lineWidth = 2;
      ctx.beginPath();
      ctx.arc(sx, sy, 13, 0, 2 * Math.PI);
      ctx.stroke();
    }
    ctx.restore();
  }

  // The incident under a screen point (within 8 px), or -1.
  hit(sx, sy) {
    let best = -1, bestD = 8;
    for (const it of this.items) {
      const [x, y] = this.view.worldToScreen(it.x, it.y);
      const d = Math.hypot(x - sx, y - sy);
      if (d < bestD) (best = it.index), (bestD = d);
    }
    return best;
  }

  legend() {
    if (!this.items.length) return null;
    const kinds = [...new Set(this.items.map((it) => it.kind))];
    return el('div', { class: 'swatches' }, kinds.map((k) =>
      el('span', {}, el('span', { class: 'swatch', style: `background:${kindOf(k).colour}` }), kindOf(k).label)));
  }
}
