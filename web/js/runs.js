// The Runs tab: every mission with its label, map, PDM, key metrics and parameters
// (GET /api/missions); open one (live or finished: its stream replays the stored final state),
// rename it (PATCH), delete an ended one, or tick two and compare them (compare_view.js).

import { api, downloadWithToken } from './api.js';
import { CompareView } from './compare_view.js';
import { isFinal, statusText } from './outcomes.js';
import { $, el, fmt, report } from './util.js';


// The figures a run is judged by, per planner family: coverage runs by coverage and moves, team
// runs by probability found, targets and collisions.
function keyMetrics(m) {
  const x = m.metrics || {};
  const parts = [];
  if (x.accumulated_probability !== undefined) {
    parts.push(`p ${x.accumulated_probability.toFixed(3)}`);
    if (x.targets_reached !== undefined) parts.push(`${fmt(x.targets_reached)} targets`);
    if (x.collisions !== undefined) parts.push(`${fmt(x.collisions)} collisions`);
    if (x.mission_time_min !== undefined) parts.push(`${x.mission_time_min.toFixed(1)} min`);
  } else if (x.coverage !== undefined) {
    parts.push(`${(x.coverage * 100).toFixed(1)} %`);
    if (x.moves !== undefined) parts.push(`${fmt(x.moves)} moves`);
    if (x.makespan !== undefined && x.makespan !== x.moves) parts.push(`makespan ${fmt(x.makespan)}`);
  }
  return parts.join(' · ');
}

function paramsLine(m) {
  const spec = m.spec || {};
  const rovers = (spec.rovers || []).map((r) => `(${fmt(r.x)}, ${fmt(r.y)}${r.heading ? `, ${fmt(r.heading)}°` : ''})`).join(' ');
  const params = Object.entries(spec.params || {}).map(([k, v]) => `${k}=${Array.isArray(v) ? `[${v.join(',')}]` : v}`).join(' ');
  return `${(spec.rovers || []).length} rover(s) ${rovers}; ${params || 'default parameters'}${spec.pace !== undefined ? `; pace ${spec.pace}` : ''}`;
}

export class RunsPanel {
  constructor({ missionView, onDuplicate }) {
    this.missionView = missionView;
    this.onDuplicate = onDuplicate;
    this.missions = [];
    this.selected = new Set();
    this.compareView = new CompareView({ missionView });
    this.compareView.onClose = () => this.clearCompare();
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
        el('button', { class: 'name', title: `open run ${m.id}`, onclick: () => this.open(m) }, m.label || `${m.planner} · ${m.id}`),
        el('button', { class: 'small', title: 'rename this run', 'aria-label': `rename run ${m.id}`, onclick: (e) => this.rename(m, e.currentTarget.closest('li')) }, '✎'),
        el('span', { class: `badge ${m.status}`, title: m.message || '' }, statusText(m.status)),
        el('button', { class: 'small', title: 'duplicate and edit: this run in the Mission form', 'aria-label': `duplicate run ${m.id}`, onclick: () => this.duplicate(m) }, '⧉'),
        el('button', { class: 'small', title: 'download its mission file (open it in the Mission tab to run it again)', 'aria-label': `mission file of run ${m.id}`, onclick: () => downloadWithToken(`/api/missions/${m.id}/mission.json`, `mission-${m.id}.json`).catch(report) }, '⤓'),
        isFinal(m.status)
          ? el('button', { class: 'small', title: 'delete this run and its results', 'aria-label': `delete run ${m.id}`, onclick: () => this.remove(m) }, '✕')
          : null,
        el('div', { class: 'run-where' },
          `${m.map_name ?? 'deleted map'}${m.pdm ? ` · PDM ${m.pdm_name ?? 'deleted'}` : ''} · ${m.label ? `${m.planner} · ` : ''}${m.created_at.replace('T', ' ').slice(0, 16)}`,
          el('span', { class: 'run-metrics', dataset: { keyMetrics: m.id } }, keyMetrics(m))),
        el('div', { class: 'params-line' }, paramsLine(m)))));
    }
    this.updateCompareButton();
  }

  // The label becomes an input: Enter saves it (PATCH), Escape or leaving it keeps the old one.
  rename(m, row) {
    const name = row.querySelector('button.name');
    const input = el('input', { type: 'text', value: m.label || '', maxlength: '200', placeholder: `${m.planner} · ${m.id}`, 'aria-label': `label of run ${m.id}`, class: 'run-label' });
    let done = false;
    const finish = async (save) => {
      if (done) return;
      done = true;
      if (save && input.value.trim() !== (m.label || '')) {
        try {
          Object.assign(m, await api.labelMission(m.id, input.value.trim(), m.version));
        } catch (err) {
          report(err);
        }
      }
      this.render();
    };
    input.addEventListener('keydown', (e) => {
      if (e.key === 'Enter') finish(true);
      else if (e.key === 'Escape') finish(false);
    });
    input.addEventListener('blur', () => finish(false));
    name.replaceWith(input);
    input.focus();
    input.select();
  }

  async duplicate(m) {
    try {
      await this.onDuplicate(await api.missionFile(m.id));
    } catch (err) {
      report(err);
    }
  }

  async remove(m) {
    if (!window.confirm(`Delete the run “${m.label || m.id}” and its results?`)) return;
    try {
      await api.deleteMission(m.id);
      if (this.missionView.mission?.id === m.id) this.missionView.clear();
      this.selected.delete(m.id);
      await this.reload();
    } catch (err) {
      report(err);
    }
  }

  updateCompareButton() {
    const b = $('runs-compare');
    b.disabled = this.selected.size !== 2;
    b.textContent = this.selected.size === 2 ? 'compare the 2 selected' : `compare (tick 2; ${this.selected.size} ticked)`;
  }

  async open(m) {
    try {
      this.clearCompare();
      await this.missionView.show(m);
      this.render();
    } catch (err) {
      report(err);
    }
  }

  // The comparison panel (compare_view.js): every metric side by side, curves on one chart, the
  // maps toggled A/B. Both runs on the same map are the usual case; on different maps the switch
  // selects each run's own map.
  async compare() {
    const runs = [...this.selected].map((id) => this.missions.find((m) => m.id === id));
    try {
      this.missionView.setCompare([]);
      $('compare').hidden = true;
      await this.compareView.show(runs);
    } catch (err) {
      report(err);
    }
  }

  clearCompare() {
    this.missionView.setCompare([]);
    $('compare').hidden = true;
    this.compareView.close();
  }
}
