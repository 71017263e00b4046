// The Runs tab: every mission with its parameters (GET /api/missions); open one (live or
// finished: its stream replays the stored final state), or tick two and compare them side by
// side — metrics table and both runs' trails on the map.

import { api } from './api.js';
import { $, el, fmt, report } from './util.js';

const COMPARED = [
  ['coverage', 'coverage', 'max'],
  ['coverage_reachable', 'coverage of reachable', 'max'],
  ['moves', 'moves', 'min'],
  ['makespan', 'makespan', 'min'],
  ['path_length_ratio', 'path length ratio', 'min'],
  ['makespan_ratio', 'makespan ratio', 'min'],
  ['distance_m', 'distance (m)', 'min'],
  ['energy_j', 'energy (J)', 'min'],
  ['max_pitch_deg', 'max pitch (°)', 'min'],
  ['revisits', 'revisits', 'min'],
  ['unreachable_cells', 'unreachable cells', ''],
  ['steps', 'steps', 'min'],
];

function paramsLine(m) {
  const spec = m.spec || {};
  const rovers = (spec.rovers || []).map((r) => `(${fmt(r.x)}, ${fmt(r.y)}${r.heading ? `, ${fmt(r.heading)}°` : ''})`).join(' ');
  const params = Object.entries(spec.params || {}).map(([k, v]) => `${k}=${Array.isArray(v) ? `[${v.join(',')}]` : v}`).join(' ');
  return `${(spec.rovers || []).length} rover(s) ${rovers}; ${params || 'default parameters'}${spec.pace !== undefined ? `; pace ${spec.pace}` : ''}${m.pdm ? `; PDM ${m.pdm}` : ''}`;
}

export class RunsPanel {
  constructor({ missionView }) {
    this.missionView = missionView;
    this.missions = [];
    this.selected = new Set();
    $('runs-refresh').addEventListener('click', () => this.reload());
    $('runs-compare').addEventListener('click', () => this.compare());
  }

  async reload() {
    try {
      this.missions = await api.missions();
    } catch (err) {
      report(err);
      return;
    }
    for (const id of [...this.selected]) if (!this.missions.some((m) => m.id === id)) this.selected.delete(id);
    this.render();
  }

  render() {
    const list = $('run-list');
    if (!this.missions.length) {
      list.replaceChildren(el('li', { class: 'muted small' }, 'No mission yet: launch one in the Mission tab.'));
    } else {
      list.replaceChildren(...this.missions.map((m) => el('li', { dataset: { mission: m.id }, class: this.missionView.mission?.id === m.id ? 'selected' : '' },
        el('input', {
          type: 'checkbox', checked: this.selected.has(m.id), 'aria-label': `select run ${m.id} for comparison`,
          onchange: (e) => {
            if (e.target.checked) this.selected.add(m.id);
            else this.selected.delete(m.id);
            this.updateCompareButton();
          },
        }),
        el('button', { class: 'name', title: `open run ${m.id}`, onclick: () => this.open(m) }, `${m.planner} · ${m.id}`),
        el('span', { class: `badge ${m.status}`, title: m.message || '' }, m.status.replace(/_/g, ' ')),
        el('span', { class: 'meta' }, m.metrics?.coverage !== undefined ? `${(m.metrics.coverage * 100).toFixed(1)} %` : ''),
        el('div', { class: 'params-line' }, `${m.created_at.replace('T', ' ').slice(0, 19)} · ${paramsLine(m)}`))));
    }
    this.updateCompareButton();
  }

  updateCompareButton() {
    const b = $('runs-compare');
    b.disabled = this.selected.size !== 2;
    b.textContent = this.selected.size === 2 ? 'compare the 2 selected' : `compare (tick 2; ${this.selected.size} ticked)`;
  }

  async open(m) {
    try {
      this.missionView.setCompare([]);
      $('compare').hidden = true;
      await this.missionView.show(m);
      this.render();
    } catch (err) {
      report(err);
    }
  }

  async compare() {
    const ids = [...this.selected];
    const runs = ids.map((id) => this.missions.find((m) => m.id === id));
    const box = $('compare');
    try {
      const results = await Promise.all(ids.map((id) => api.result(id)));
      if (runs[0].map !== runs[1].map) report('the two runs are on different maps: trails are drawn on the current map');
      else if (this.missionView.mission?.map !== runs[0].map) await this.missionView.selectMap(runs[0].map);
      this.missionView.setCompare(results.map((r, i) => ({ label: i === 0 ? 'A' : 'B', paths: r.rovers.map((rv) => rv.path) })));
      const head = el('tr', {}, el('th', {}, 'metric'), el('th', {}, `A ${ids[0]}`), el('th', {}, `B ${ids[1]}`));
      const rows = COMPARED.filter(([k]) => results.some((r) => r.metrics[k] !== undefined)).map(([k, label, better]) => {
        const a = results[0].metrics[k], b = results[1].metrics[k];
        const best = better === 'min' ? Math.min(a, b) : better === 'max' ? Math.max(a, b) : null;
        const cell = (v) => el('td', { class: best !== null && a !== b && v === best ? 'better' : '' }, fmt(v));
        return el('tr', {}, el('td', {}, label), cell(a), cell(b));
      });
      const params = el('tr', {}, el('td', {}, 'parameters'), ...runs.map((m) => el('td', { style: 'text-align:left;font-size:11px' }, paramsLine(m))));
      box.replaceChildren(
        el('h2', {}, 'A (solid) vs B (dashed)'),
        el('table', {}, head, ...rows, params),
        el('div', { class: 'form-row' }, el('button', { onclick: () => this.clearCompare() }, 'clear comparison')));
      box.hidden = false;
    } catch (err) {
      report(err);
    }
  }

  clearCompare() {
    this.missionView.setCompare([]);
    $('compare').hidden = true;
  }
}
