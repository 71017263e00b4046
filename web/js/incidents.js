// A mission's incidents (result.json `incidents`: short and skipped legs, slot-less targets,
// attitude exceedances, collisions, coverage bumps), live as the stream reports them (issue 27:
// {"type":"incidents", from, complete, incidents}) and then the stored result's list: a list in
// the dock grouped by kind and cause with counts (163 short legs of one cause are one row that
// opens), marks on the replay clock's strip and markers on the map (a toggleable layer, an OL
// vector layer: incidents_layer.js).
// Choosing one anywhere selects it everywhere: the clock seeks to its time, the map centres on it
// and rings it, its row is highlighted (its group opened).

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
// The cause (result.json `cause`) in words, beside the kind.
const CAUSES = {
  exceedance_limit: '|roll| or |pitch| over exceedance_limit',
  safety_distance: 'closer than safety_distance',
  steep: 'every try tilts past attitude_check',
  no_path: 'no path to the target',
  conflict: 'blocked by a rover with priority',
  pieces_exhausted: 'max_pieces RRT* pieces used up',
  keep_out: 'every try enters a keep-out zone',
  invalid_goal: 'target not on ground a rover may stop on',
  no_ground: 'no valid ground for the slot',
  off_field: 'the move would leave the field',
  unmapped_obstacle: 'an obstacle its map held free',
};
// An incident's group: its kind and cause (an older result without `cause`: its note with the
// numbers taken out).
const causeOf = (it) => it.cause || (it.note || '').replace(/^target \d+: /, '').replace(/-?\d+(\.\d+)?/g, '#');
const causeText = (c) => CAUSES[c] || c || '';
const MIN_SCALE = 8;  // px/m the map zooms in to, at least, to show a chosen incident
export const kindOf = (k) => INCIDENT_KINDS[k] || INCIDENT_KINDS.other;

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
    this.complete = true;  // a stored result, or nothing shown
    this.setItems(result?.incidents || []);
  }

  // A live stream's incident frame: keep the first `from`, append these (the result's list
  // replaces them at the end). Rendering waits for a quiet moment: a run may report hundreds.
  live(msg) {
    const keep = this.items.slice(0, Math.min(Number(msg.from) || 0, this.items.length));
    this.complete = Boolean(msg.complete);
    if ((msg.incidents || []).some((inc) => inc.step !== undefined)) this.unit = 'step';  // coverage: no clock
    this.setItems([...keep, ...(msg.incidents || [])], { later: true });
  }

  setItems(list, { later = false } = {}) {
    this.items = list.map((inc, i) => ({
      ...inc, index: i,
      at: this.unit === 'step' ? Number(inc.step ?? 0) : Number(inc.time_s) || 0,
    }));
    if (this.selected >= this.items.length) this.selected = -1;
    if (!later) return this.render();
    if (this.renderPending) return;
    this.renderPending = true;
    setTimeout(() => {
      this.renderPending = false;
      this.render();
      this.view.invalidate();
    }, 150);
  }

  clear() {
    this.open = new Set();
    this.set(null, 's');
  }

  when(item) {
    return this.unit === 's' ? clockText(item.at) : `step ${fmt(item.at)}`;
  }

  // The groups, in order of their first incident: {key, kind, cause, items}.
  groups() {
    const byKey = new Map();
    for (const it of this.items) {
      const key = `${it.kind}|${causeOf(it)}`;
      if (!byKey.has(key)) byKey.set(key, { key, kind: it.kind, cause: causeOf(it), items: [] });
      byKey.get(key).items.push(it);
    }
    return [...byKey.values()];
  }

  render() {
    this.open ||= new Set();
    const n = this.items.length;
    this.count.textContent = String(n);
    this.count.dataset.count = String(n);
    const byKind = new Map();
    for (const it of this.items) byKind.set(it.kind, (byKind.get(it.kind) || 0) + 1);
    const groups = this.groups();
    this.summary.replaceChildren(n === 0
      ? (this.complete ? 'no incidents' : 'no incidents so far')
      : el('span', { class: 'swatches' }, [...byKind].map(([k, c]) =>
        el('span', { title: kindOf(k).label }, el('span', { class: 'swatch', style: `background:${kindOf(k).colour}` }), `${k.replace(/_/g, ' ')} ${fmt(c)}`)),
      ` · ${fmt(groups.length)} group${groups.length === 1 ? '' : 's'}${this.complete ? '' : ' · live'}`));
    this.rows = [];
    this.groupRows = new Map();
    const out = [];
    for (const g of groups) {
      const single = g.items.length === 1;
      const open = single || this.open.has(g.key);
      if (!single) {
        const rovers = [...new Set(g.items.map((it) => it.rover + 1))].sort((a, b) => a - b);
        const first = g.items.reduce((a, b) => (b.at < a.at ? b : a)), last = g.items.reduce((a, b) => (b.at > a.at ? b : a));
        const toggle = () => this.toggle(g.key);
        const head = el('tr', {
          class: 'incident-group', tabindex: '0', dataset: { group: g.key, count: String(g.items.length) },
          'aria-expanded': String(open), title: g.items[0].note || '',
          onclick: toggle, onkeydown: (e) => { if (e.key === 'Enter' || e.key === ' ') e.preventDefault(), toggle(); },
        },
        el('td', {}, el('span', { class: 'fold' }, open ? '▾' : '▸'), el('span', { class: 'swatch', style: `background:${kindOf(g.kind).colour}` }),
          `${g.kind.replace(/_/g, ' ')} ×${fmt(g.items.length)}`),
        el('td', {}, rovers.length > 4 ? `${rovers.length} rovers` : `rover${rovers.length > 1 ? 's' : ''} ${rovers.join(', ')}`),
        el('td', { class: 'num' }, first === last ? this.when(first) : `${this.when(first)}–${this.when(last)}`),
        el('td', { class: 'num' }, ''),
        el('td', { class: 'note' }, el('b', {}, causeText(g.cause)), g.items[0].note ? ` — e.g. ${g.items[0].note}` : ''));
        this.groupRows.set(g.key, head);
        out.push(head);
      }
      for (const it of g.items) {
        const row = el('tr', {
          class: single ? '' : 'incident-member', hidden: !open,
          tabindex: '0', dataset: { incident: String(it.index), group: g.key }, title: it.note || '',
          onclick: () => this.select(it.index), onkeydown: (e) => { if (e.key === 'Enter') this.select(it.index); },
        },
        el('td', {}, el('span', { class: 'swatch', style: `background:${kindOf(it.kind).colour}` }), it.kind.replace(/_/g, ' ')),
        el('td', {}, `rover ${it.rover + 1}${it.other !== undefined ? ` · ${it.other + 1}` : ''}`),
        el('td', { class: 'num' }, this.when(it)),
        el('td', { class: 'num' }, `${it.x.toFixed(1)}, ${it.y.toFixed(1)} m`),
        el('td', { class: 'note' }, it.note || ''));
        if (it.index === this.selected) row.classList.add('selected');
        this.rows[it.index] = row;
        out.push(row);
      }
    }
    this.list.replaceChildren(...out);
  }

  // Opens or closes a group of incidents of one kind and cause.
  toggle(key, open = !this.open.has(key)) {
    if (open) this.open.add(key);
    else this.open.delete(key);
    const head = this.groupRows.get(key);
    if (!head) return;
    head.setAttribute('aria-expanded', String(open));
    head.querySelector('.fold').textContent = open ? '▾' : '▸';
    for (const row of this.list.querySelectorAll('tr.incident-member')) if (row.dataset.group === key) row.hidden = !open;
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
    if (row.hidden) this.toggle(row.dataset.group, true);  // its group opens to show it
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
