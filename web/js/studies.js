// The Studies tab (issue 12): launch a preset or a parameter grid of one planner, watch its
// progress and ETA over the study WebSocket (server/studies/study_manager.hpp), plot its runs with
// Observable Plot (UMD from node_modules: globals Plot and d3, see index.html) and open a run as a
// mission. Plots are computed here from runs.csv and the study's configurations:
//   paper 002 fig. 6: path length ratio vs coverage %, mean ± std per variant (line + band)
//   paper 002 fig. 8: makespan per team size, box plots per variant
//   paper 001: accumulated probability vs distance per route method, mean ± std
//   any metric × any grouping: box plots, from two selects
// Reference values (SPEC.md §1, paper 002) are drawn on the same axes where the paper gives them.

import { ApiError, api, downloadWithToken, getJson, request, sendJson } from './api.js';
import { editName } from './name_edit.js';
import { RunStatus, isActive } from './outcomes.js';
import { $, el, fmt, report } from './util.js';

const PRESET_HINTS = {
  'laine-fig6': 'paper 002 fig. 6: 4 single-rover variants × 5 coverage levels, 60×60 grids',
  'laine-fig8': 'paper 002 fig. 8: overlap vs Voronoi, 2/4/8 rovers, 3 grid sizes',
  frontier: 'ours: spiral vs spiral+frontier (memory), 60×60 grids',
  swinton: 'paper 001: route methods on the synthetic Mars map, random PDMs (slow: seconds per run)',
};
// What the papers give in numbers (their figures are lost; SPEC.md §1 "Reference results").
const REFERENCE = {
  fig6: [
    { level: 95, value: 1.2, label: 'paper 002 fig. 5 run: 1.2 at 95 %' },
    { level: 100, value: 1.75, label: 'paper 002 fig. 5 run: 1.75 at 100 %' },
  ],
  fig8: [
    { rovers: '4', value: 444, label: 'paper 002 fig. 7: overlap, 4 rovers, 99 %: 444 steps' },
    { rovers: '4', value: 449, label: 'paper 002 fig. 7: Voronoi, 4 rovers, 99 %: 449 steps' },
  ],
};

// Backoff between reconnects of a study's stream that closed before its end, then every 4 s.
const STREAM_RETRY_MS = [250, 500, 1000, 2000, 4000];

function wsUrl(path) {
  const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
  const token = localStorage.getItem('roverplan.token');
  return `${proto}//${location.host}${path}${token ? `?token=${encodeURIComponent(token)}` : ''}`;
}

function duration(s) {
  if (s === null || s === undefined || !Number.isFinite(s)) return '—';
  if (s < 60) return `${Math.round(s)} s`;
  if (s < 3600) return `${Math.floor(s / 60)} min ${Math.round(s % 60)} s`;
  return `${Math.floor(s / 3600)} h ${Math.round((s % 3600) / 60)} min`;
}

// runs.csv (StudyDb::runsCsv) as objects; numbers parsed, empty = NaN.
function parseCsv(text) {
  const lines = text.trim().split('\n');
  if (lines.length < 2) return [];
  const head = lines[0].split(',');
  const textCols = new Set(['config', 'status', 'host', 'version', 'seed']);
  return lines.slice(1).map((line) => {
    const cells = line.split(',');
    const row = {};
    head.forEach((h, i) => { row[h] = textCols.has(h) ? cells[i] : cells[i] === '' ? NaN : Number(cells[i]); });
    return row;
  });
}

// A read-out at a level or distance the run did not reach (p_at_600m when the team drove 424 m;
// path_length_ratio@99% of a run that stopped at 97 %) is empty in runs.csv: "not reached", not
// missing data (issue 27).
const isReadOut = (key) => /^p_at_[\d.]+m$/.test(key) || key.includes('@');
function cellText(key, v) {
  return !Number.isFinite(v) && isReadOut(key) ? 'not reached' : fmt(v);
}
function notReachedWhy(key) {
  return key.startsWith('p_at_') ? `the team's mean distance per rover stayed under ${key.slice(5, -1)} m` : 'the run ended below this level';
}

function meanStd(values) {
  const v = values.filter(Number.isFinite);
  if (!v.length) return null;
  const mean = v.reduce((a, b) => a + b, 0) / v.length;
  const std = v.length > 1 ? Math.sqrt(v.reduce((a, b) => a + (b - mean) ** 2, 0) / (v.length - 1)) : 0;
  return { mean, std, n: v.length };
}

function toCsv(rows) {
  if (!rows.length) return '';
  const keys = Object.keys(rows[0]);
  const cell = (v) => (typeof v === 'string' && /[",\n]/.test(v) ? `"${v.replace(/"/g, '""')}"` : String(v));
  return [keys.join(','), ...rows.map((r) => keys.map((k) => cell(r[k])).join(','))].join('\n') + '\n';
}

function saveBlob(blob, filename) {
  const href = URL.createObjectURL(blob);
  const a = el('a', { href, download: filename });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(href), 10000);
}

// The figure's <svg> (Plot returns a <figure> when it has a legend).
function svgOf(node) {
  return node.tagName.toLowerCase() === 'svg' ? node : node.querySelector('svg:not([class$="-swatch"])') || node.querySelector('svg');
}

function exportSvg(node, name) {
  const svg = svgOf(node).cloneNode(true);
  svg.setAttribute('xmlns', 'http://www.w3.org/2000/svg');
  saveBlob(new Blob([new XMLSerializer().serializeToString(svg)], { type: 'image/svg+xml' }), `${name}.svg`);
}

function exportPng(node, name) {
  const svg = svgOf(node).cloneNode(true);
  svg.setAttribute('xmlns', 'http://www.w3.org/2000/svg');
  const w = Number(svg.getAttribute('width')) || 640, h = Number(svg.getAttribute('height')) || 400;
  const img = new Image();
  img.onload = () => {
    const c = el('canvas', { width: w * 2, height: h * 2 });
    const g = c.getContext('2d');
    g.fillStyle = '#ffffff';
    g.fillRect(0, 0, c.width, c.height);
    g.drawImage(img, 0, 0, c.width, c.height);
    c.toBlob((b) => saveBlob(b, `${name}.png`), 'image/png');
  };
  img.src = `data:image/svg+xml;charset=utf-8,${encodeURIComponent(new XMLSerializer().serializeToString(svg))}`;
}

export class StudiesPanel {
  // onMission(mission): a run opened as a mission (the page shows it).
  constructor({ onMission }) {
    this.onMission = onMission;
    this.presets = [];
    this.planners = [];
    this.studies = [];
    this.current = null;   // the study shown (GET /api/studies/{id})
    this.runs = [];        // its runs.csv rows
    this.ws = null;
    this.lastPlotted = -1;
    $('st-source').addEventListener('change', () => this.renderSource());
    $('st-planner').addEventListener('change', () => this.renderGrid());
    $('st-form').addEventListener('submit', (e) => { e.preventDefault(); this.launch(); });
    $('st-refresh').addEventListener('click', () => this.reload());
    $('st-box-metric').addEventListener('change', () => this.drawPlots());
    $('st-box-group').addEventListener('change', () => this.drawPlots());
    $('st-cancel').addEventListener('click', () => this.cancel());
  }

  async activate(planners) {
    this.planners = planners || this.planners;
    if (!this.presets.length) {
      try {
        this.presets = await getJson('/api/studies/presets');
      } catch (err) {
        report(err);
      }
      const sel = $('st-source');
      sel.replaceChildren(...this.presets.map((p) => el('option', { value: p.name }, `preset: ${p.name}`)),
        el('option', { value: 'grid' }, 'grid of a planner\'s parameters'));
      $('st-planner').replaceChildren(...this.planners.map((p) => el('option', { value: p.name }, p.name)));
      this.renderSource();
    }
    await this.reload();
  }

  renderSource() {
    const src = $('st-source').value;
    const grid = src === 'grid';
    $('st-grid').hidden = !grid;
    $('st-hint').textContent = grid ? 'values separated by commas; several values make a grid axis' : PRESET_HINTS[src] || '';
    const preset = this.presets.find((p) => p.name === src);
    $('st-runs').value = preset ? Math.min(preset.spec.runs, src === 'swinton' ? 2 : 20) : 5;
    if (grid) this.renderGrid();
  }

  renderGrid() {
    const planner = this.planners.find((p) => p.name === $('st-planner').value);
    if (!planner) return;
    // Random obstacle grids only for a planner that plans on a coverage grid (GET /api/planners: ground).
    const grids = planner.ground === 'coverage_grid';
    $('st-world').replaceChildren(
      ...(grids ? [el('option', { value: 'grid60' }, 'random 60×60 grids, 5 % obstacles (a new one per run)')] : []),
      el('option', { value: 'mars' }, 'the default map\'s synthetic Mars (150 m; runs open as missions)'));
    const rows = planner.params
      .filter((p) => ['choice', 'bool', 'int', 'real'].includes(p.type))
      .map((p) => el('label', { class: 'grid-param', title: p.doc },
        el('span', {}, p.key),
        el('input', { type: 'text', 'data-key': p.key, 'data-type': p.type,
          placeholder: p.choices ? p.choices.join(', ') : `${p.default}${p.unit ? ` ${p.unit}` : ''}` })));
    $('st-params').replaceChildren(...rows);
  }

  // The study document of the form.
  document() {
    const src = $('st-source').value;
    const runs = Number($('st-runs').value);
    const seed = Number($('st-seed').value);
    if (src !== 'grid') return { preset: src, runs, master_seed: seed };
    const planner = $('st-planner').value;
    const described = this.planners.find((p) => p.name === planner);
    const world = $('st-world').value === 'mars' ? { name: 'mars', terrain: {} }
      : { name: '60x60', grid: { rows: 60, cols: 60, obstacle_fraction: 0.05 } };
    const grid = {}, params = {};
    for (const input of $('st-params').querySelectorAll('input')) {
      const text = input.value.trim();
      if (!text) continue;
      const type = input.dataset.type;
      const values = text.split(',').map((s) => s.trim()).filter(Boolean).map((s) =>
        type === 'bool' ? s === 'true' || s === '1' : type === 'int' || type === 'real' ? Number(s) : s);
      if (values.length === 1) params[input.dataset.key] = values[0];
      else grid[input.dataset.key] = values;
    }
    const doc = { name: $('st-name').value.trim() || `${planner} grid`, planner, runs, master_seed: seed, worlds: [world] };
    const rovers = $('st-rovers').value.split(',').map((s) => Number(s.trim())).filter((n) => n > 0);
    if (rovers.length) doc.rovers = rovers;
    if (Object.keys(params).length) doc.params = params;
    if (Object.keys(grid).length) doc.grid = grid;
    // What the study reads follows the planner's description: where its rovers start, whether it
    // searches a PDM, and how its progress is read out (coverage levels; a detection curve is read
    // at the server's default distances).
    if (described?.starts === 'formation') doc.starts = 'formation';
    if (described?.ground === 'dem_pdm') doc.pdm = { random_gaussians: 4 };
    if (described?.progress?.measure === 'coverage') doc.levels = [0.9, 0.95, 0.97, 0.99, 1.0];
    return doc;
  }

  async launch() {
    const status = $('st-launch-status');
    status.textContent = 'launching…';
    try {
      const s = await sendJson('POST', '/api/studies', this.document());
      status.textContent = `queued: ${s.runs_total} runs`;
      this.launched = s.id;  // its line follows the study to its end (progress)
      await this.reload();
      await this.show(s.id);
    } catch (err) {
      status.textContent = err instanceof ApiError ? err.describe() : String(err);
    }
  }

  async reload() {
    try {
      this.studies = await getJson('/api/studies');
    } catch (err) {
      report(err);
      return;
    }
    // The shown study renamed (by another operator too): its title follows.
    const shown = this.current && this.studies.find((s) => s.id === this.current.id);
    if (shown && shown.name !== this.current.name) {
      Object.assign(this.current, { name: shown.name, version: shown.version });
      $('study-title').textContent = `${shown.name} · ${shown.id}`;
    }
    this.renderList();
    if (!this.current && this.studies.length) await this.show(this.studies[0].id);
  }

  renderList() {
    // A rename being typed (or its conflict) is not swept away by a refresh: it comes after.
    if (this.renaming) return;
    $('st-list').replaceChildren(...this.studies.map((s) => this.listItem(s)));
  }

  // One study's row: its button cancels a queued or running study and deletes an ended one.
  listItem(s) {
    return el('li', { class: this.current?.id === s.id ? 'selected' : '', 'data-study': s.id },
      el('button', { class: 'name', title: `show study ${s.id}`, onclick: () => this.show(s.id) }, `${s.name} · ${s.id.slice(0, 6)}`),
      el('button', { class: 'small rename', title: `rename ${s.name}`, 'aria-label': `rename study ${s.name}`, onclick: (e) => this.rename(s, e.currentTarget.closest('li')) }, '✎'),
      el('span', { class: `badge ${s.status}` }, s.status),
      el('span', { class: 'muted small' }, ` ${s.runs_done}/${s.runs_total}`),
      el('button', { class: 'end', title: isActive(s.status) ? 'cancel' : 'delete the study and its database',
        onclick: async () => { try { await sendJson('DELETE', `/api/studies/${s.id}`); } catch (err) { report(err); } this.reload(); } },
      isActive(s.status) ? 'cancel' : 'delete'));
  }

  // The study's name becomes an input (name_edit.js); saved with the version read.
  rename(s, row) {
    this.renaming = true;
    editName({
      row, object: 'study', what: 'study', id: s.id, name: s.name, version: s.version,
      save: (name, version) => api.renameStudy(s.id, name, version),
      done: (saved) => {
        this.renaming = false;
        if (saved) {
          Object.assign(s, { name: saved.name, version: saved.version });
          if (this.current?.id === s.id) {
            Object.assign(this.current, { name: saved.name, version: saved.version });
            $('study-title').textContent = `${saved.name} · ${s.id}`;
          }
        }
        this.reload();
      },
    });
  }

  async show(id) {
    this.unsubscribe();
    this.lastPlotted = -1;
    this.current = await getJson(`/api/studies/${id}`);
    this.renderList();
    $('study-title').textContent = `${this.current.name} · ${id}`;
    $('st-downloads').replaceChildren(
      el('button', { onclick: () => downloadWithToken(`/api/studies/${id}/runs.csv`, `study-${id}-runs.csv`) }, 'runs.csv'),
      el('button', { onclick: () => downloadWithToken(`/api/studies/${id}/study.sqlite`, `study-${id}.sqlite`) }, 'study.sqlite'));
    this.progress(this.current);
    // The stream first: a runs.csv that fails (a busy server's 503) must not leave the page
    // without the study's progress — the status would then stay "queued" for good.
    this.subscribe(id);
    await this.loadRuns();
  }

  // Follows the study's stream (snapshot, progress, done). A stream that closes before its done
  // frame (a dropped connection, a server restart) is opened again after a backoff: its snapshot
  // brings the state missed meanwhile. Only the newest subscription counts (a show() of another
  // study, or of this one again, replaces it).
  subscribe(id, attempt = 0) {
    const ws = new WebSocket(wsUrl(`/api/studies/${id}/stream`));
    this.ws = ws;
    let ended = false;
    ws.onmessage = (e) => {
      if (ws !== this.ws) return;
      attempt = 0;
      const msg = JSON.parse(e.data);
      const s = msg.type === 'snapshot' ? msg.study : msg;
      this.progress(s);
      if (msg.summary) this.current.summary = msg.summary;
      if (msg.type === 'done' || (msg.type === 'snapshot' && !isActive(s.status))) ended = true;
      // New runs: the plots follow while it runs (with the partial summary's rhythm) and at the end.
      if (msg.type === 'done' || (msg.summary && s.runs_done !== this.lastPlotted)) this.loadRuns().catch(report);
      if (msg.type === 'done') this.reload();
    };
    ws.onclose = () => {
      if (ws !== this.ws || ended) return;
      const wait = STREAM_RETRY_MS[Math.min(attempt, STREAM_RETRY_MS.length - 1)];
      this.retry = setTimeout(() => {
        if (ws === this.ws && this.current?.id === id) this.subscribe(id, attempt + 1);
      }, wait);
    };
  }

  unsubscribe() {
    clearTimeout(this.retry);
    const ws = this.ws;
    this.ws = null;  // first: its onclose then sees it replaced and does not reconnect
    if (ws) ws.close();
  }

  progress(s) {
    const done = s.runs_done ?? 0, total = s.runs_total ?? 0;
    $('st-progress').max = Math.max(1, total);
    $('st-progress').value = done;
    $('st-status').textContent = s.status;
    $('st-status').className = `badge ${s.status}`;
    $('st-counters').textContent = `${done.toLocaleString('en-US')} / ${total.toLocaleString('en-US')} runs` +
      (s.runs_per_s ? ` · ${fmt(s.runs_per_s)} runs/s` : '') +
      (s.status === RunStatus.Running ? ` · ETA ${duration(s.eta_s)}` : '') + (s.message ? ` · ${s.message}` : '');
    $('st-cancel').hidden = !isActive(s.status);
    // The launch line and the study's entry in the list follow it to its end (issue 27: they
    // read "queued" after the study ended).
    const id = s.id ?? this.current?.id;
    if (id && id === this.launched && s.status) $('st-launch-status').textContent = `${s.status}: ${done.toLocaleString('en-US')} / ${total.toLocaleString('en-US')} runs`;
    const entry = this.studies?.find((x) => x.id === id);
    if (entry && s.status && (entry.status !== s.status || entry.runs_done !== done)) {
      Object.assign(entry, { status: s.status, runs_done: done });
      // The whole row again, its button too: an ended study's reads "delete", not "cancel".
      const li = $('st-list').querySelector(`li[data-study="${id}"]`);
      if (li && !this.renaming) li.replaceWith(this.listItem(entry));
    }
  }

  async cancel() {
    if (!this.current) return;
    try { await sendJson('DELETE', `/api/studies/${this.current.id}`); } catch (err) { report(err); }
  }

  async loadRuns() {
    if (!this.current) return;
    const text = await (await request(`/api/studies/${this.current.id}/runs.csv`)).text();
    this.runs = parseCsv(text);
    this.lastPlotted = this.runs.length;
    this.renderRunsTable();
    this.fillBoxSelects();
    this.drawPlots();
  }

  config(row) {
    return this.current.configurations[row.config_id] || { name: row.config, rovers: 1, world: '', params: {} };
  }

  // A configuration's variant: its name without the world and team-size parts.
  variant(c) {
    return c.name.split(/[/ ·]+/).filter((p) => p !== c.world && p !== `${c.rovers}r`).join(' ') || c.name;
  }

  metricKeys() {
    if (!this.runs.length) return [];
    const skip = new Set(['run_index', 'config_id', 'config', 'replicate', 'seed', 'status', 'host', 'rank', 'version', 'cpu_s']);
    return Object.keys(this.runs[0]).filter((k) => !skip.has(k));
  }

  fillBoxSelects() {
    const sel = $('st-box-metric');
    const keys = this.metricKeys();
    const keep = sel.value;
    if ([...sel.options].map((o) => o.value).join() !== keys.join())
      sel.replaceChildren(...keys.map((k) => el('option', { value: k }, k)));
    const preferred = ['path_length_ratio', 'makespan', ...keys.filter((k) => k.startsWith('p_at_')).reverse(), 'legs_reached_pct'];
    sel.value = keys.includes(keep) ? keep : preferred.find((k) => keys.includes(k)) || keys[0] || '';
  }

  renderRunsTable() {
    // The metrics people read first, when the runs have them; else the first with values.
    const keys = this.metricKeys().filter((k) => k !== 'wall_s' && this.runs.some((r) => Number.isFinite(r[k])));
    const first = ['path_length_ratio', 'coverage', 'makespan', 'p_at_600m', 'legs_reached_pct', 'distance_m'].filter((k) => keys.includes(k));
    const metrics = [...first, ...keys.filter((k) => !first.includes(k))].slice(0, 4);
    const head = el('tr', {}, el('th', {}, 'run'), el('th', {}, 'configuration'), el('th', {}, 'status'),
      ...metrics.map((m) => el('th', {}, m)), el('th', {}, ''));
    const rows = this.runs.slice(0, 300).map((r) => el('tr', { class: 'run-row', 'data-run': r.run_index, onclick: () => this.openRun(r.run_index) },
      el('td', {}, r.run_index), el('td', {}, r.config), el('td', {}, r.status),
      ...metrics.map((m) => el('td', !Number.isFinite(r[m]) && isReadOut(m) ? { class: 'not-reached', title: notReachedWhy(m) } : {}, cellText(m, r[m]))),
      el('td', {}, el('button', { class: 'small' }, 'open'))));
    $('st-runs-table').replaceChildren(head, ...rows);
    $('st-runs-note').textContent = this.runs.length > 300 ? `first 300 of ${this.runs.length} runs (all in runs.csv)` : `${this.runs.length} runs`;
  }

  async openRun(index) {
    const box = $('st-run');
    try {
      const run = await getJson(`/api/studies/${this.current.id}/runs/${index}`);
      const params = Object.entries(run.params).map(([k, v]) => `${k}=${v}`).join(' ');
      const open = run.mission
        ? el('button', { id: 'st-open-mission', class: 'primary', onclick: async () => {
            try {
              const m = await sendJson('POST', `/api/studies/${this.current.id}/runs/${index}/mission`);
              await this.onMission(m);
            } catch (err) { report(err); }
          } }, 'open as a mission and replay')
        : el('span', { class: 'notice' }, `cannot open as a mission: ${run.mission_unavailable}`);
      // The seed as runs.csv prints it: 62-bit seeds do not fit a JavaScript number.
      const seed = this.runs.find((r) => r.run_index === index)?.seed ?? run.seed;
      box.replaceChildren(el('strong', {}, `run ${run.run_index}`), ` · ${run.config} · ${run.planner} · world ${run.world} · ${run.rovers} rover(s) · seed ${seed} · ${params} `, open);
      box.hidden = false;
    } catch (err) {
      report(err);
    }
  }

  drawPlots() {
    const host = $('st-plots');
    if (typeof Plot === 'undefined') {
      host.replaceChildren(el('p', { class: 'notice' }, 'the charting library (Observable Plot) did not load: run docker/setup-web.sh'));
      return;
    }
    const figures = [];
    const keys = this.metricKeys();
    const rows = this.runs.map((r) => ({ ...r, _c: this.config(r) }));
    // Paper 002 fig. 6.
    const levelKeys = keys.filter((k) => /^path_length_ratio@[\d.]+%$/.test(k));
    if (levelKeys.some((k) => rows.some((r) => Number.isFinite(r[k])))) {
      const data = [];
      for (const [variant, runs] of d3.group(rows, (r) => this.variant(r._c)))
        for (const k of levelKeys) {
          const s = meanStd(runs.map((r) => r[k]));
          if (s) data.push({ variant, coverage_pct: Number(k.split('@')[1].replace('%', '')), mean: s.mean, std: s.std, lo: s.mean - s.std, hi: s.mean + s.std, n: s.n });
        }
      figures.push(['fig6', 'Path length ratio vs coverage % (mean ± std per variant; paper 002 fig. 6)', data, Plot.plot({
        width: 420, height: 300, marginLeft: 50, color: { legend: true }, x: { label: 'coverage %' }, y: { label: 'path length ratio', grid: true },
        marks: [
          Plot.areaY(data, { x: 'coverage_pct', y1: 'lo', y2: 'hi', fill: 'variant', fillOpacity: 0.15 }),
          Plot.lineY(data, { x: 'coverage_pct', y: 'mean', stroke: 'variant', marker: 'circle' }),
          Plot.dot(REFERENCE.fig6, { x: 'level', y: 'value', symbol: 'diamond', r: 5, stroke: '#222', fill: '#ffd23f', title: 'label' }),
          Plot.text(REFERENCE.fig6.slice(0, 1), { x: 'level', y: 'value', text: () => 'paper 002 (one run)', dy: -10, fontSize: 10 }),
        ] })]);
    }
    // Paper 002 fig. 8.
    if (keys.includes('makespan') && new Set(rows.map((r) => r._c.rovers)).size > 1) {
      const data = rows.map((r) => ({ rovers: String(r._c.rovers), variant: this.variant(r._c), world: r._c.world, makespan: r.makespan }));
      const key = (d) => `${d.rovers} · ${d.variant}`;
      const refWorld = (data.find((d) => d.world === '60x60') || data[0]).world;
      const refs = data.some((d) => d.rovers === '4')
        ? REFERENCE.fig8.map((d, k) => ({ ...d, world: refWorld, key: `4 · ${k === 0 ? 'overlap' : 'voronoi'}` })) : [];
      figures.push(['fig8', 'Makespan per team size (box plots per variant; paper 002 fig. 8; ◆ paper 002 fig. 7)', data, Plot.plot({
        width: 860, height: 320, marginLeft: 50, marginBottom: 70, color: { legend: true },
        fx: { label: 'world', domain: [...new Set(this.current.configurations.map((c) => c.world))] },
        x: { label: 'rovers · variant', tickRotate: -30 }, y: { label: 'makespan (steps)', grid: true },
        marks: [
          Plot.boxY(data, { fx: 'world', x: key, y: 'makespan', fill: 'variant' }),
          Plot.dot(refs, { fx: 'world', x: 'key', y: 'value', symbol: 'diamond', r: 5, stroke: '#222', fill: '#ffd23f', title: 'label' }),
        ] })]);
    }
    // Paper 001: p vs distance.
    const pKeys = keys.filter((k) => /^p_at_[\d.]+m$/.test(k));
    if (pKeys.some((k) => rows.some((r) => Number.isFinite(r[k])))) {
      const data = [];
      for (const [variant, runs] of d3.group(rows, (r) => this.variant(r._c)))
        for (const k of pKeys) {
          const s = meanStd(runs.map((r) => r[k]));
          if (s) data.push({ method: variant, distance_m: Number(k.slice(5, -1)), mean: s.mean, std: s.std, lo: s.mean - s.std, hi: s.mean + s.std, n: s.n, not_reached: runs.length - s.n });
        }
      figures.push(['p-distance', 'Accumulated probability vs distance per route method (mean ± std over the runs that reached each distance; paper 001 — it gives no numbers in its text)', data, Plot.plot({
        width: 420, height: 300, marginLeft: 50, color: { legend: true }, x: { label: 'distance (m)' }, y: { label: 'accumulated probability', grid: true },
        marks: [
          Plot.areaY(data, { x: 'distance_m', y1: 'lo', y2: 'hi', fill: 'method', fillOpacity: 0.15 }),
          Plot.lineY(data, { x: 'distance_m', y: 'mean', stroke: 'method', marker: 'circle' }),
        ] })]);
    }
    // Any metric × any grouping.
    const metric = $('st-box-metric').value, group = $('st-box-group').value;
    if (metric) {
      const by = { config: (r) => r.config, variant: (r) => this.variant(r._c), world: (r) => r._c.world, rovers: (r) => `${r._c.rovers} rovers` }[group];
      const data = rows.filter((r) => Number.isFinite(r[metric])).map((r) => ({ group: by(r), [metric]: r[metric] }));
      // Runs that did not reach a read-out's distance or level are counted per group, not dropped
      // silently: a group whose runs all fell short keeps its place, labelled "not reached".
      const short = isReadOut(metric) ? rows.filter((r) => !Number.isFinite(r[metric])) : [];
      const shortBy = d3.rollup(short, (v) => v.length, by);
      const all = d3.rollup(rows, (v) => v.length, by);
      const domain = [...all.keys()];
      const notReached = [...shortBy].map(([g, n]) => ({ group: g, label: `not reached: ${n}/${all.get(g)}` }));
      const groups = domain.length;
      const title = `${metric} per ${group} (box plots)` + (short.length ? ` · not reached by ${short.length} of ${rows.length} runs (${notReachedWhy(metric)})` : '');
      figures.push(['box', title, data, Plot.plot({
        width: groups > 6 ? 860 : 420, height: 300, marginLeft: 80, marginBottom: 70, x: { label: group, tickRotate: -30, domain }, y: { label: metric, grid: true },
        marks: [Plot.boxY(data, { x: 'group', y: metric, fill: '#3ad6ff', stroke: '#ccc' }),
          Plot.text(notReached, { x: 'group', frameAnchor: 'top', dy: 8, text: 'label', fill: '#ffb347', ariaLabel: 'not reached' })] })]);
    }
    const name = this.current ? `study-${this.current.id}` : 'study';
    host.replaceChildren(...figures.map(([id, title, data, node]) => el('figure', { class: 'study-plot', 'data-plot': id },
      el('figcaption', {}, title,
        el('span', { class: 'plot-exports' },
          el('button', { class: 'small', onclick: () => exportPng(node, `${name}-${id}`) }, 'PNG'),
          el('button', { class: 'small', onclick: () => exportSvg(node, `${name}-${id}`) }, 'SVG'),
          el('button', { class: 'small', onclick: () => saveBlob(new Blob([toCsv(data)], { type: 'text/csv' }), `${name}-${id}.csv`) }, 'CSV'))),
      node)));
    if (!figures.length) host.replaceChildren(el('p', { class: 'muted' }, this.runs.length ? 'no plot for these metrics' : 'no runs yet'));
  }
}

