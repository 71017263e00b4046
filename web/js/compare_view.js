// Compare two runs (issue 13 "compare that compares"): a panel over the map area with every
// metric of both runs side by side with the difference B − A and the ratio B / A (where both are
// positive), the curves of both runs on the same axes (coverage vs moves, probability vs
// distance, pitch vs time…: A solid, B dashed), and the two runs' maps toggled with an A/B switch
// (the server's rendered map.png of each, with its legend and scale bar). The switch also shows
// that run on the main map and in the dock, so the dock never shows a third mission's charts.

import { api, request } from './api.js';
import { lineChart } from './charts.js';
import { $, el, fmt, report } from './util.js';

// Which metrics are better low or high (the better cell is marked); the rest are only listed.
const BETTER = {
  coverage: 'max', coverage_reachable: 'max', true_coverage: 'max', map_accuracy: 'max',
  accumulated_probability: 'max', single_rover_probability: 'max', route_score: 'max',
  targets_reached: 'max', min_separation_m: 'max',
  moves: 'min', makespan: 'min', path_length_ratio: 'min', makespan_ratio: 'min', distance_m: 'min',
  energy_j: 'min', max_pitch_deg: 'min', max_roll_deg: 'min', revisits: 'min', steps: 'min',
  mean_trajectory_m: 'min', mission_time_s: 'min', mission_time_min: 'min', exceedances: 'min',
  exceedance_fraction: 'min', collisions: 'min', targets_skipped: 'min', targets_short: 'min',
  targets_no_slot: 'min', replans: 'min', waits: 'min', warnings: 'min', bumps: 'min',
  localisation_mae_m: 'min', plan_wall_s: 'min', unreachable_cells: 'min',
};

// The curves drawn for both runs: [series key or key prefix, chart title]. A prefix
// (pitch_deg_rover_) draws every rover's series, titled with its own x axis (time or move).
const CURVES = [
  ['coverage_vs_moves', 'coverage vs moves'],
  ['true_coverage_vs_moves', 'true coverage vs moves'],
  ['probability_vs_distance_team', 'probability vs mean distance per rover (m)'],
  ['probability_vs_distance_route', 'probability vs route distance (m)'],
  ['pitch_deg_rover_', 'pitch (°)'],
  ['roll_deg_rover_', 'roll (°)'],
];

const A_COLOUR = '#3ad6ff';
const B_COLOUR = '#ff8a3d';

function difference(a, b) {
  if (typeof a !== 'number' || typeof b !== 'number') return '';
  const d = b - a;
  return `${d > 0 ? '+' : ''}${fmt(d)}`;
}

function ratio(a, b) {
  if (typeof a !== 'number' || typeof b !== 'number' || !(a > 0) || !(b >= 0)) return '';
  return `×${fmt(b / a)}`;
}

// The unit after a metric's name, unless the name already ends with it (max_pitch_deg, distance_m).
function unitNote(key, unit) {
  if (!unit) return null;
  const tail = unit.replace('²', '2').replace('/', '_').toLowerCase();
  if (key === tail || key.endsWith(`_${tail}`)) return null;
  return el('span', { class: 'unit' }, ` (${unit})`);
}

export class CompareView {
  constructor({ missionView }) {
    this.missionView = missionView;
    this.box = $('compare-view');
    this.runs = [];
    this.results = [];
    this.images = [null, null];
    this.shown = 0;
    window.addEventListener('resize', () => this.runs.length && this.drawCharts());
  }

  get open() {
    return !this.box.hidden;
  }

  // runs: two mission records (GET /api/missions entries).
  async show(runs) {
    this.runs = runs;
    this.results = await Promise.all(runs.map((m) => api.result(m.id)));
    this.images = [null, null];
    this.render();
    this.box.hidden = false;
    // Charts are sized to their boxes, which exist only once the panel is shown.
    requestAnimationFrame(() => this.drawCharts());
    await this.toggle(0);
  }

  close() {
    this.box.hidden = true;
    for (const u of this.images) if (u) URL.revokeObjectURL(u);
    this.images = [null, null];
    this.runs = [];
    this.results = [];
  }

  render() {
    const [a, b] = this.results;
    const keys = [...new Set([...Object.keys(a.metrics), ...Object.keys(b.metrics)])];
    const units = { ...(a.metric_units || {}), ...(b.metric_units || {}) };
    const rows = keys.map((k) => {
      const va = a.metrics[k], vb = b.metrics[k];
      const better = BETTER[k];
      const best = better && typeof va === 'number' && typeof vb === 'number' && va !== vb
        ? (better === 'min' ? Math.min(va, vb) : Math.max(va, vb)) : null;
      const cell = (v) => el('td', { class: best !== null && v === best ? 'better' : '', title: String(v ?? '') }, fmt(v));
      return el('tr', { dataset: { metric: k } },
        el('th', { scope: 'row' }, k.replace(/_/g, ' '), unitNote(k, units[k])),
        cell(va), cell(vb), el('td', { class: 'diff' }, difference(va, vb)), el('td', { class: 'ratio' }, ratio(va, vb)));
    });
    const name = (m) => m.label || `${m.planner} · ${m.id}`;
    const switcher = el('div', { class: 'segmented', role: 'tablist', 'aria-label': 'map of run A or B' },
      ...['A', 'B'].map((label, i) => el('button', {
        id: `compare-show-${label.toLowerCase()}`, role: 'tab', 'aria-selected': 'false',
        title: `show run ${label} (${name(this.runs[i])}) on the map and in the dock`,
        onclick: () => this.toggle(i).catch(report),
      }, `map ${label}`)));
    this.charts = CURVES.map(([key, title]) => {
      const has = (r) => Object.keys(r.series || {}).some((s) => (key.endsWith('_') ? s.startsWith(key) : s === key));
      if (!has(a) && !has(b)) return null;
      const canvas = el('canvas', { dataset: { curve: key } });
      const first = [a, b].flatMap((r) => Object.entries(r.series || {})).find(([s]) => s.startsWith(key))?.[1];
      const caption = key.endsWith('_') && first?.x_label ? `${title} vs ${first.x_label}` : title;
      return { key, canvas, node: el('figure', {}, el('figcaption', {}, caption), canvas) };
    }).filter(Boolean);
    this.box.replaceChildren(
      el('div', { class: 'compare-head' },
        el('h2', {}, 'Compare ',
          el('span', { class: 'run-a' }, `A ${name(this.runs[0])}`), ' vs ',
          el('span', { class: 'run-b' }, `B ${name(this.runs[1])}`)),
        switcher,
        el('button', { id: 'compare-close', onclick: () => this.onClose?.() }, 'close')),
      el('div', { class: 'compare-body' },
        el('div', { class: 'compare-table' },
          el('table', { id: 'compare-metrics' },
            el('thead', {}, el('tr', {}, el('th', {}, 'metric'), el('th', { class: 'run-a' }, 'A'), el('th', { class: 'run-b' }, 'B'), el('th', {}, 'B − A'), el('th', {}, 'B / A'))),
            el('tbody', {}, ...rows))),
        el('figure', { class: 'compare-map' },
          el('figcaption', { id: 'compare-map-caption' }, ''),
          el('img', { id: 'compare-map-img', alt: 'map of the shown run' })),
        el('div', { class: 'compare-side' },
          el('div', { class: 'compare-charts' }, ...this.charts.map((c) => c.node)),
          this.charts.length ? el('div', { class: 'muted small' }, 'A solid (blue), B dashed (orange); one line per rover where the curve is per rover') : null)));
  }

  drawCharts() {
    for (const c of this.charts || []) {
      const series = [];
      this.results.forEach((r, i) => {
        for (const [k, s] of Object.entries(r.series || {})) {
          if (c.key.endsWith('_') ? !k.startsWith(c.key) : k !== c.key) continue;
          const rover = c.key.endsWith('_') ? ` rover ${Number(k.slice(c.key.length)) + 1}` : '';  // 1-based for people
          series.push({ x: s.x, y: s.y, colour: i === 0 ? A_COLOUR : B_COLOUR, dash: i === 0 ? null : [5, 3], label: `${i === 0 ? 'A' : 'B'}${rover}` });
        }
      });
      lineChart(c.canvas, series, { empty: 'no such curve' });
    }
  }

  // Shows run i: its rendered map in the panel, and the run itself on the main map and the dock.
  async toggle(i) {
    this.shown = i;
    for (const [j, label] of [[0, 'a'], [1, 'b']]) {
      const b = $(`compare-show-${label}`);
      b.classList.toggle('active', j === i);
      b.setAttribute('aria-selected', String(j === i));
    }
    const run = this.runs[i];
    $('compare-map-caption').textContent = `${i === 0 ? 'A' : 'B'}: ${run.label || run.id} · ${run.planner} · ${run.map_name ?? run.map}`;
    const img = $('compare-map-img');
    img.dataset.run = run.id;
    if (!this.images[i]) {
      // The server's picture (legend, scale bar), fetched with the token; a blob URL for <img>.
      const blob = await (await request(`/api/missions/${run.id}/map.png`)).blob();
      this.images[i] = URL.createObjectURL(blob);
    }
    if (this.shown === i) img.src = this.images[i];
    await this.missionView.show(run);
  }
}
