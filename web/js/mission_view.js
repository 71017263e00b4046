// One mission on the page — live or finished: its coverage grid and trails on the map, the dock's
// progress bar, metrics, charts and cancel button, the replay slider and the export links. The
// live view counts the frames it renders per second (window.__roverplan.fps, status line).

import { api, downloadWithToken, hasToken } from './api.js';
import { barChart, chartXAt, lineChart } from './charts.js';
import { CELL_STATE_NAMES, CoverageLayer } from './coverage_layer.js';
import { LiveStream } from './live_stream.js';
import { PlanLayer } from './plan_layer.js';
import { counters, state } from './state.js';
import { TrailLayer, TrailSet } from './trails.js';
import { $, el, fmt, report, roverColour } from './util.js';
import { Incidents, kindOf } from './incidents.js';
import { IncidentLayer } from './incidents_layer.js';
import { MissionClock } from './mission_clock.js';
import { RunStatus, isActive, isCompleted, isFinal, isRunStatus, isStopped, statusText } from './outcomes.js';

const pct = (v) => `${(v * 100).toFixed(1)} %`;
const SHOWN_METRICS = [
  ['coverage', 'coverage', pct],
  // Coverage under localisation error (issue 15): `coverage` is then the rover's own map.
  ['true_coverage', 'true coverage', pct],
  ['localisation_mae_m', 'loc. MAE', (v) => `${v.toFixed(2)} m`],
  ['map_accuracy', 'map accuracy', pct],
  ['bumps', 'bumps'],
  ['loop_closures', 'loop closures'],
  ['coverage_reachable', 'of reachable', (v) => `${(v * 100).toFixed(1)} %`],
  ['moves', 'moves'],
  ['makespan', 'makespan'],
  ['path_length_ratio', 'path ratio'],
  ['makespan_ratio', 'span ratio'],
  ['distance_m', 'distance', (v) => (v >= 10000 ? `${(v / 1000).toFixed(2)} km` : `${fmt(v)} m`)],
  ['energy_j', 'energy', (v) => (v >= 10000 ? `${(v / 1000).toFixed(1)} kJ` : `${fmt(v)} J`)],
  ['max_pitch_deg', 'max pitch', (v) => `${v.toFixed(1)}°`],
  ['revisits', 'revisits'],
  ['unreachable_cells', 'unreachable'],
  ['steps', 'steps'],
  // Team missions (paper 001 §4, SPEC §3.5).
  ['mean_trajectory_m', 'mean trajectory', (v) => `${fmt(v)} m`],
  ['mission_time_min', 'mission time', (v) => `${v.toFixed(1)} min`],
  ['accumulated_probability', 'probability', (v) => v.toFixed(3)],
  ['single_rover_probability', 'one rover', (v) => v.toFixed(3)],
  ['collisions', 'collisions'],
  ['min_separation_m', 'min separation', (v) => `${v.toFixed(2)} m`],
  ['exceedances', 'over 15°'],
  ['exceedance_fraction', 'over 15° share', (v) => `${(v * 100).toFixed(4)} %`],
  ['targets_reached', 'targets reached'],
  ['targets_skipped', 'skipped'],
  ['replans', 're-plans'],
  ['plan_wall_s', 'planning', (v) => `${v.toFixed(1)} s`],
];

// A progress frame as an operator reads it: a coverage run in steps and moves; a team mission's
// planning in legs (with the re-plans and waits so far), then its replay on the mission clock.
function progressInWords(p) {
  const extras = () => [p.replans ? `${fmt(p.replans)} re-plans` : '', p.waits ? `${fmt(p.waits)} waits` : ''].filter(Boolean).map((t) => ` · ${t}`).join('');
  if (p.phase === 'planning') return `planning: leg ${fmt(p.legs_done)} of ${fmt(p.legs_total)}${extras()}`;
  if (p.phase === 'replay') {
    const min = (s) => (s / 60).toFixed(1);
    return `replay: ${min(p.mission_time_s)} of ${min(p.mission_end_s)} min · search cells ${(100 * (p.coverage || 0)).toFixed(1)} %${extras()}`;
  }
  return `step ${fmt(p.step)} · moves ${fmt(p.moves)} · coverage ${(100 * (p.coverage || 0)).toFixed(1)} %`;
}

export class MissionView {
  constructor({ view, layers, statusLine, selectMap, onFinished, onShown }) {
    this.view = view;
    this.layers = layers;
    this.statusLine = statusLine;
    this.selectMap = selectMap;
    this.onFinished = onFinished || (() => {});
    this.onShown = onShown || (() => {});
    this.coverage = new CoverageLayer(view, 30);
    this.trailLayer = new TrailLayer(view, 40);
    this.trails = this.trailLayer.add(new TrailSet({ width: 2 }));
    // Coverage under localisation error: where each rover believed it was (dashed, hollow marker);
    // `trails` are then the true positions. A layer of its own, so each can be toggled.
    this.beliefLayer = new TrailLayer(view, 41);
    this.believed = this.beliefLayer.add(new TrailSet({ width: 1.5, dash: [5, 4], hollow: true, label: 'believed' }));
    this.plan = new PlanLayer(view);
    this.compareSets = [];
    this.mission = null;
    this.result = null;
    this.progressCurve = { x: [], y: [] };
    this.renderTimes = [];
    this.stream = new LiveStream(this.handlers());

    const covLayer = layers.addOverlay({ id: 'coverage', label: 'coverage', legendTitle: 'coverage grid (cell state, visits)', visible: true, opacity: 0.6, legend: () => (this.coverage.ready ? CoverageLayer.legend() : null) });
    const trailLayer = layers.addOverlay({ id: 'trails', label: 'trails', legendTitle: 'rover trails', visible: true, opacity: 0.95, legend: () => this.trailLegend() });
    const planLayer = layers.addOverlay({ id: 'plan', label: 'team plan', legendTitle: 'team plan', visible: true, opacity: 0.9, legend: () => (this.plan.route.length || this.plan.paths.length ? el('div', { class: 'muted small' }, 'white: team route through the numbered targets; dashed: each rover\'s planned RRT* path') : null) });
    view.onRender(() => this.coverage.sync(covLayer.opacity, covLayer.visible));  // an OL layer
    view.onRender(() => this.plan.sync(planLayer.opacity, planLayer.visible));  // OL layers
    // Trails and rovers are OL layers (trails.js): their features follow the sets each frame.
    view.onRender(() => this.trailLayer.sync(trailLayer.opacity, trailLayer.visible, true));
    const beliefLayer = layers.addOverlay({ id: 'believed', label: 'believed trails', legendTitle: 'believed trails (localisation error)', visible: true, opacity: 0.95, legend: () => this.beliefLegend() });
    view.onRender(() => {
      const shown = beliefLayer.visible && this.hasBeliefs();
      this.beliefLayer.sync(beliefLayer.opacity, shown, shown);
    });
    view.onRender((t) => this.countFrame(t));
    view.onHover((p) => {
      this.plan.hover = p;
      if (this.plan.route.length) view.invalidate();
    });

    // Incidents: the dock's list, the clock's strip and a map layer; choosing one seeks there.
    this.incidents = new Incidents({
      view, list: $('incident-list'), summary: $('incident-summary'), count: $('incident-count'),
      onSelect: (it) => {
        this.replay.pause();
        this.replay.seek(it.at);
        this.replay.drawStrip();
      },
    });
    const incLayer = layers.addOverlay({ id: 'incidents', label: 'incidents', legendTitle: 'incidents', visible: true, opacity: 1, legend: () => this.incidents.legend() });
    this.incidentLayer = new IncidentLayer(view, 47, kindOf);
    view.onRender(() => this.incidentLayer.sync(this.incidents.items, this.incidents.selected, incLayer.opacity, incLayer.visible));
    this.bindIncidentClicks(view, incLayer);
    this.replay = new MissionClock({
      slider: $('replay-slider'), play: $('replay-play'), speed: $('replay-speed'), label: $('replay-label'), strip: $('replay-strip'),
      onSeek: (t, end) => this.seek(t, end),
      marks: () => this.incidents.marks(),
      onMark: (i) => this.incidents.select(i),
    });
    this.bindDockTabs();
    for (const id of ['chart-roll', 'chart-pitch-t', 'chart-speed', 'chart-energy-t', 'chart-pitch']) {
      $(id).addEventListener('click', (e) => {
        const x = chartXAt(e.currentTarget, e.clientX);
        if (x === null || !this.result || this.replay.slider.disabled) return;
        this.replay.pause();
        this.replay.seek(x);
      });
    }
    $('live-cancel').addEventListener('click', () => this.cancel());
    for (const id of ['export-geojson', 'export-csv', 'export-map-png', 'export-map-tif', 'export-mcap']) {
      $(id).addEventListener('click', (e) => {
        const a = e.currentTarget;
        if (a.classList.contains('disabled')) return e.preventDefault();
        if (hasToken()) {  // a plain link cannot carry the bearer token
          e.preventDefault();
          downloadWithToken(a.getAttribute('href'), a.getAttribute('download')).catch((err) => report(err));
        }
      });
    }
    window.addEventListener('resize', () => this.drawCharts(this.cursor ?? null));
    this.drawCharts();
  }

  // --- showing a mission ---
  async show(mission) {
    if (typeof mission === 'string') mission = await api.mission(mission);
    if (state.map?.id !== mission.map) {
      try {
        await this.selectMap(mission.map);
      } catch {
        report(`mission ${mission.id}: its map ${mission.map} is gone; showing it on the current map`);
      }
    }
    this.reset(mission);
    this.stream.open(mission.id);
    this.onShown(mission);
  }

  // No mission shown (another map was chosen): the stream closed, the layers and the dock empty.
  clear() {
    this.stream.close();
    this.replay.disable();
    this.incidents.clear();
    this.mission = null;
    this.result = null;
    state.emit('result', null);
    this.cursor = null;
    this.clockTimes = null;
    this.progressCurve = { x: [], y: [] };
    this.coverage.reset();
    this.plan.clear();
    this.trails.clear(0);
    this.setCompare([]);
    counters.missionId = null;
    counters.missionStatus = null;
    counters.finalMetrics = null;
    this.progressText = '';
    $('live-title').textContent = 'no mission';
    $('live-title').title = '';
    this.setStatus('');
    this.setProgress(0);
    this.renderMetrics(null);
    this.setExports(null);
    $('live-counters').replaceChildren();
    this.layers.renderLegends();
    this.drawCharts();
    this.view.invalidate();
    this.onShown(null);
  }

  reset(mission) {
    this.stream.close();
    this.replay.pause();
    this.incidents.clear();
    this.mission = mission;
    this.result = null;
    state.emit('result', null);
    this.cursor = null;
    this.clockTimes = null;
    this.progressCurve = { x: [], y: [] };
    this.coverage.reset();
    this.plan.clear();
    this.trails.clear((mission.spec?.rovers || []).length);
    this.believed.clear();
    this.layers.renderLegends();
    this.lastProgress = mission.progress || null;
    this.progressText = '';
    counters.missionId = mission.id;
    counters.missionStatus = mission.status;
    counters.finalMetrics = null;
    counters.fps = 0;
    counters.fpsPeak = 0;
    this.renderTimes = [];
    this.liveSince = performance.now();
    $('live-title').textContent = `${mission.planner} · ${mission.id}`;
    $('live-title').title = JSON.stringify(mission.spec || {});
    this.setStatus(mission.status, mission.message || '');
    this.setProgress(mission.progress?.fraction ?? (isCompleted(mission.status) ? 1 : 0));
    this.renderMetrics(mission.metrics);
    this.setExports(null);
    this.replay.disable();
    this.renderCounters();
    this.drawCharts();
    this.view.invalidate();
  }

  handlers() {
    return {
      snapshot: (m) => {
        if (m.grid) this.coverage.reset(m.grid.rows, m.grid.cols, m.grid.cell_size_m, m.grid.origin ?? [0, 0]);
        this.trails.clear(m.rovers.length);
        for (const r of m.rovers) this.trails.append(r.rover, r.trail, r.pose);
        this.believed.clear();
        for (const r of m.rovers) if (r.believed_trail) this.believed.append(r.rover, r.believed_trail, r.pose);
        this.plan.clear();
        if (m.route || m.paths) this.plan.apply(m, true);
        this.layers.renderLegends();
        this.onStatus(m.status);
        if (m.progress) this.onProgress(m.progress);
        if (m.metrics) this.renderMetrics(m.metrics);
        if (m.incidents?.length && !this.result) this.incidents.live({ from: 0, complete: m.incidents_complete, incidents: m.incidents });
        this.view.invalidate();
      },
      grid: (buffer) => {
        const type = this.coverage.applyFrame(buffer);
        this.view.invalidate();
        return type;
      },
      poses: (m) => {
        for (const r of m.rovers) {
          this.trails.append(r.rover, r.append, r.pose);
          if (r.believed) this.believed.append(r.rover, r.believed, r.pose);
        }
        this.step = m.step;
        this.view.invalidate();
      },
      overlay: (m) => {
        const first = !this.plan.route.length && !this.plan.paths.length;
        this.plan.apply(m);
        if (first) this.layers.renderLegends();  // the team plan's legend, now it has one
        this.view.invalidate();
      },
      incidents: (m) => {
        // Live until the stored result replaces them (onDone).
        if (this.result) return;
        const before = this.incidents.items.length;
        this.incidents.live(m);
        if (!before && m.incidents?.length) setTimeout(() => this.layers.renderLegends(), 200);  // the kinds' legend
      },
      progress: (m) => this.onProgress(m),
      status: (m) => this.onStatus(m.status),
      done: (m) => this.onDone(m),
      closed: (info) => {
        if (!info.done) {
          this.setStatus(counters.missionStatus || '', `stream closed${info.code !== 1000 ? ` (code ${info.code})` : ''} before the end`);
          report(`mission stream closed before the end (code ${info.code}${info.reason ? `: ${info.reason}` : ''})`);
        }
        this.updateStatusLine(true);
      },
    };
  }

  // A live status. A final one before the "done" frame: a cancelled run is final at once and its
  // partial result is stored after (the done frame then brings it).
  onStatus(status) {
    this.setStatus(status, isFinal(status) ? 'storing its result…' : '');
  }

  onProgress(p) {
    this.lastProgress = p;
    this.setProgress(p.fraction ?? 0);
    if (!p.phase && Number.isFinite(p.moves) && Number.isFinite(p.coverage)) {  // coverage runs
      const c = this.progressCurve;
      if (c.x.length === 0 || p.moves >= c.x[c.x.length - 1]) {
        c.x.push(p.moves);
        c.y.push(p.coverage);
      }
      if (!this.chartPending) {
        this.chartPending = true;
        setTimeout(() => {
          this.chartPending = false;
          if (!this.result) this.drawCharts();
        }, 200);
      }
    }
    this.progressText = progressInWords(p);
    this.renderCounters();
  }

  // The server's last progress, and what the grid frames say (they arrive even when the server
  // sends few progress frames).
  renderCounters() {
    let grid = '';
    if (this.coverage.ready) {
      const [, , obstacles, visited] = this.coverage.counts();
      grid = `grid: ${fmt(visited)} visited · ${fmt(obstacles)} obstacles of ${fmt(this.coverage.rows * this.coverage.cols)} cells`;
    }
    $('live-counters').replaceChildren(this.progressText || '', this.progressText && grid ? document.createElement('br') : '', grid);
  }

  async onDone(m) {
    counters.missionStatus = m.status;
    counters.finalMetrics = m.metrics;
    this.setStatus(m.status, m.message || '');
    if (isCompleted(m.status)) this.setProgress(1);
    this.renderMetrics(m.metrics);
    this.coverage.keepFinal();
    this.updateStatusLine(true);
    if (isCompleted(m.status) || m.status === RunStatus.Cancelled) {
      try {
        this.result = await api.result(m.mission);
        if (this.mission?.id !== m.mission) return;
        this.trails.setPaths(this.result.rovers.map((r) => r.path));
        this.believed.setPaths(this.result.rovers.some((r) => r.believed_path) ? this.result.rovers.map((r) => r.believed_path || []) : []);
        this.layers.renderLegends();
        if (this.result.overlays) this.plan.setFromResult(this.result.overlays);
        this.layers.renderLegends();
        this.setExports(m.mission);
        // A team mission replays on its clock (s), a coverage run in steps.
        this.clockTimes = this.missionClockTimes(this.result);
        const unit = this.clockTimes ? 's' : 'step';
        this.incidents.set(this.result, unit);
        this.layers.renderLegends();  // the incidents' kinds
        this.replay.enable(unit === 's' ? this.result.metrics.mission_time_s : this.trails.longest - 1, unit);
        state.emit('result', this.result);  // the route profile's samples
      } catch (err) {
        if (err.status !== 409) report(err);
      }
    }
    this.drawCharts();
    this.view.invalidate();
    this.onFinished(m);
  }

  async cancel() {
    if (!this.mission) return;
    try {
      const id = this.mission.id;
      await api.cancel(id);
      // The final status or frame may have come in while the request was out.
      if (this.stream.live && this.mission?.id === id && isActive(counters.missionStatus)) this.setStatus('cancelling');
    } catch (err) {
      report(err);
    }
  }

  // --- replay ---
  // The times (s) of a team track's points (one a second from 0, as the pitch series; the longest
  // rover's: one may never leave its start), or null for a result without a mission clock.
  missionClockTimes(r) {
    if (!Number.isFinite(r?.metrics?.mission_time_s)) return null;
    let best = null;
    for (const [key, s] of Object.entries(r.series || {}))
      if (/^pitch_deg_rover_\d+$/.test(key) && s.x_label === 'time (s)' && (!best || s.x.length > best.length)) best = s.x;
    return best && best.length >= 2 ? best : null;
  }

  // t: s of mission time (team) or a step (coverage).
  seek(t, end) {
    if (!this.result) return;
    this.cursor = end ? null : t;
    let step = t;
    if (this.clockTimes) {  // the last point at or before t
      const x = this.clockTimes;
      let lo = 0, hi = x.length - 1;
      while (lo < hi) {
        const mid = (lo + hi + 1) >> 1;
        if (x[mid] <= t + 1e-9) lo = mid;
        else hi = mid - 1;
      }
      step = lo;
    }
    // The grid is the rovers' own map: under localisation error it is rebuilt from the believed paths.
    const paths = this.result.rovers.map((r) => r.believed_path || r.path);
    if (end) {
      this.trails.setLimit(Infinity);
      this.believed.setLimit(Infinity);
      this.coverage.restoreFinal();
    } else {
      this.trails.setLimit(step);
      this.believed.setLimit(step);
      this.coverage.replayTo(paths, step);
    }
    counters.replayStep = step;
    counters.replayTime = this.clockTimes ? t : null;
    this.scheduleCharts();
    this.view.invalidate();
  }

  // Charts follow the replay cursor at most ~20 times a second (four time series a frame while
  // the clock plays would cost more than the map).
  scheduleCharts() {
    if (this.chartTimer) return;
    this.chartTimer = setTimeout(() => {
      this.chartTimer = null;
      this.drawCharts(this.cursor ?? null);
    }, 50);
  }

  // --- comparison: other runs' trails on the map ---
  setCompare(runs) {
    for (const s of this.compareSets) this.trailLayer.remove(s);
    this.compareSets = runs.map((r, i) => {
      const s = new TrailSet({ width: 2.5, dash: i === 0 ? null : [6, 4], colourOffset: i === 0 ? 0 : 4, label: r.label });
      s.setPaths(r.paths);
      return this.trailLayer.add(s);
    });
    this.trails.setPaths(runs.length ? [] : this.result ? this.result.rovers.map((r) => r.path) : this.trails.paths);
    this.layers.renderLegends();
    this.view.invalidate();
  }

  hasBeliefs() {
    return this.believed.paths.some((p) => p.length > 0);
  }

  beliefLegend() {
    // Nothing to explain without localisation error: the layer's row title says when it applies.
    if (!this.hasBeliefs()) return null;
    return el('div', { class: 'muted small' }, 'dashed, hollow marker: where each rover believed it was; the solid trails are where it truly went');
  }

  trailLegend() {
    const sets = this.compareSets.length ? this.compareSets : [this.trails];
    const rows = [];
    sets.forEach((s) => {
      s.paths.forEach((_, k) => {
        const c = roverColour(k + (s.style.colourOffset || 0));
        rows.push(el('span', {}, el('span', { class: 'swatch', style: `background:${c}` }), `${s.style.label ? `${s.style.label} ` : ''}rover ${k + 1}${s.style.dash ? ' (dashed)' : ''}`));
      });
    });
    return rows.length ? el('div', { class: 'swatches' }, rows) : null;  // no mission: no legend
  }

  // --- dock widgets ---
  // The badge holds the status (a RunStatus, the page's own 'cancelling', or '' for none) in
  // words; what went wrong (warnings, the failure, a closed stream) goes on its own line under it,
  // clamped to three lines with the whole text as its tooltip.
  setStatus(status, message = '') {
    const badge = $('live-status');
    badge.textContent = statusText(status);
    badge.className = `badge ${status || ''}`;
    badge.hidden = !status;
    const line = $('live-message');
    line.textContent = message;
    line.title = message;
    line.hidden = !message;
    line.classList.toggle('error', isStopped(status));
    const running = isActive(status);
    $('live-cancel').disabled = !running;
    $('live-cancel').hidden = !running;  // its room goes to the mission's title
    if (isRunStatus(status)) counters.missionStatus = status;
  }

  setProgress(f) {
    $('live-progress').value = Math.max(0, Math.min(1, f || 0));
  }

  renderMetrics(metrics) {
    const table = $('metrics');
    if (!metrics) {
      table.replaceChildren();
      return;
    }
    const cells = SHOWN_METRICS.filter(([k]) => metrics[k] !== undefined).map(([k, label, f]) => [label, f ? f(metrics[k]) : fmt(metrics[k]), k]);
    // One metric a row: two a row were cut at 1280 px ("probability 0.139" read "0").
    table.replaceChildren(...cells.map(([label, value, key]) =>
      el('tr', {}, el('td', {}, label), el('td', { dataset: { metric: key }, title: value }, value))));
  }

  setExports(id) {
    for (const [node, file] of [[$('export-geojson'), 'result.geojson'], [$('export-csv'), 'result.csv'], [$('export-map-png'), 'map.png'], [$('export-map-tif'), 'map.tif'], [$('export-mcap'), 'replay.mcap']]) {
      if (id) {
        node.href = `/api/missions/${id}/${file}`;
        node.setAttribute('download', `mission-${id}-${file}`);
        node.classList.remove('disabled');
        node.removeAttribute('aria-disabled');
      } else {
        node.removeAttribute('href');
        node.classList.add('disabled');
        node.setAttribute('aria-disabled', 'true');
      }
    }
  }

  drawCharts(cursorStep = null) {
    const r = this.result;
    const cov = r?.series?.coverage_vs_moves;
    const rovers = r ? r.rovers.length : 1;
    const team = r?.series?.probability_vs_distance_team;
    const caption = (id, text) => { $(id).previousElementSibling.textContent = text; };
    caption('chart-coverage', team ? 'accumulated probability vs distance (m)' : 'coverage vs moves');
    caption('chart-energy', team ? 'trajectory per rover (m)' : 'energy per rover (J)');
    if (team) {
      // Team missions: accumulated probability vs distance, the team against one rover (paper 001 fig. 11).
      const single = r.series.probability_vs_distance_single;
      const yMax = Math.max(0.05, ...team.y);
      lineChart($('chart-coverage'), [
        { x: team.x, y: team.y, colour: '#4fb3ff', label: 'team' },
        ...(single ? [{ x: single.x, y: single.y, colour: '#ffb14f', label: 'one rover' }] : []),
      ], { yMin: 0, yMax, legend: true, empty: 'no probability curve' });
    } else {
      const truth = r?.series?.true_coverage_vs_moves;
      const lines = cov ? [{ x: cov.x, y: cov.y, colour: '#4fb3ff', label: truth ? 'believed' : undefined }] : [{ ...this.progressCurve, colour: '#4fb3ff' }];
      if (truth) lines.push({ x: truth.x, y: truth.y, colour: '#ff7a45', label: 'true' });
      lineChart($('chart-coverage'), lines,
        { yMin: 0, yMax: 1, legend: Boolean(truth), empty: 'waiting for progress', cursorX: cursorStep !== null ? cursorStep * rovers : null });
    }
    const pitch = [];
    if (r) {
      for (const [key, s] of Object.entries(r.series || {})) {
        const m = /^pitch_deg_rover_(\d+)$/.exec(key);
        if (m) pitch.push({ x: s.x, y: s.y, colour: roverColour(Number(m[1])), width: 1, label: `rover ${Number(m[1]) + 1}` });
      }
    }
    // The limit lines are the mission's own attitude limit (team missions report it); a team's
    // series run on the mission clock (s), one point a second, as its replay does.
    const limit = Number(r?.metrics?.attitude_limit_deg ?? 15);
    caption('chart-pitch', `pitch (deg) per ${team ? 'second' : 'move'}, ±${fmt(Number(limit.toPrecision(4)))}°`);
    lineChart($('chart-pitch'), pitch, {
      refLines: [{ y: limit, label: `+${fmt(Number(limit.toPrecision(4)))}°` }, { y: -limit, label: `−${fmt(Number(limit.toPrecision(4)))}°` }], legend: true, cursorX: cursorStep,
      empty: r ? 'no pitch series' : 'after the run (result.json)',
    });
    const bars = r ? r.rovers.map((rv, k) => ({ label: `rover ${k + 1}`, value: (team ? rv.metrics?.trajectory_m : rv.metrics?.energy_j ?? rv.metrics?.trajectory_m) ?? 0, colour: roverColour(k) })) : [];
    barChart($('chart-energy'), bars, { empty: r ? 'no energy metric' : 'after the run' });
    if (!$('dock-motion').hidden) this.drawMotionCharts(cursorStep, limit);
  }

  // Roll, pitch (both with the mission's attitude limit), speed and energy of every rover against
  // mission time, all on the mission's x range so the replay cursor is at the same x in each.
  drawMotionCharts(cursor, limit) {
    const r = this.result;
    const perRover = (name) => Object.entries(r?.series || {}).flatMap(([key, s]) => {
      const m = new RegExp(`^${name}_rover_(\\d+)$`).exec(key);
      return m ? [{ x: s.x, y: s.y, colour: roverColour(Number(m[1])), width: 1, label: `rover ${Number(m[1]) + 1}` }] : [];
    });
    const clock = Boolean(this.clockTimes);
    const range = clock ? { xMin: 0, xMax: r.metrics.mission_time_s } : {};
    const l = fmt(Number(limit.toPrecision(4)));
    const refLines = [{ y: limit, label: `+${l}°` }, { y: -limit, label: `−${l}°` }];
    const empty = r ? 'no series (team missions)' : 'after the run (result.json)';
    const unit = clock ? 's' : 'move';
    $('chart-roll').previousElementSibling.textContent = `roll (deg) per ${unit === 's' ? 'second' : 'move'}, ±${l}°`;
    $('chart-pitch-t').previousElementSibling.textContent = `pitch (deg) per ${unit === 's' ? 'second' : 'move'}, ±${l}°`;
    $('chart-speed').previousElementSibling.textContent = 'speed (m/s), mean of each second';
    $('chart-energy-t').previousElementSibling.textContent = 'drive energy used (J)';
    lineChart($('chart-roll'), perRover('roll_deg'), { ...range, refLines, cursorX: cursor, empty });
    lineChart($('chart-pitch-t'), perRover('pitch_deg'), { ...range, refLines, legend: true, cursorX: cursor, empty });
    lineChart($('chart-speed'), perRover('speed_mps'), { ...range, yMin: 0, cursorX: cursor, empty });
    lineChart($('chart-energy-t'), perRover('energy_j'), { ...range, yMin: 0, cursorX: cursor, empty });
  }

  // The dock's panes: overview charts, the motion charts against time, the incident list.
  bindDockTabs() {
    const tabs = ['overview', 'motion', 'incidents', 'profile'];
    for (const name of tabs) {
      $(`dock-tab-${name}`).addEventListener('click', () => {
        for (const other of tabs) {
          const on = other === name;
          $(`dock-tab-${other}`).classList.toggle('active', on);
          $(`dock-tab-${other}`).setAttribute('aria-selected', String(on));
          $(`dock-${other}`).hidden = !on;
        }
        this.drawCharts(this.cursor ?? null);
        if (name === 'incidents') this.incidents.rows[this.incidents.selected]?.scrollIntoView({ block: 'nearest' });
      });
    }
  }

  // A click (not a drag) on the map in pan mode selects the incident marker under it.
  bindIncidentClicks(view, layer) {
    view.onPanClick((p) => {
      if (!layer.visible || !this.incidents.items.length) return;
      const i = this.incidents.hit(p.sx, p.sy);
      if (i >= 0) {
        this.incidents.select(i, { centre: false });
        this.replay.drawStrip();
      }
    });
  }

  // --- frames per second of the live view ---
  // While a mission is live the view renders on every animation frame (the stream's data is
  // applied as it comes, and drawn at the display's rate when the page keeps up).
  countFrame(t) {
    if (!this.stream.live) return;
    this.view.invalidate();
    counters.liveRenders++;
    const times = this.renderTimes;
    times.push(t);
    while (times.length && times[0] < t - 1000) times.shift();
    counters.fps = times.length;
    if (times.length > counters.fpsPeak && t - (this.liveSince || 0) > 1000) counters.fpsPeak = times.length;
    if (!this.statusTimer) this.statusTimer = setTimeout(() => this.updateStatusLine(), 250);
  }

  updateStatusLine(final = false) {
    this.statusTimer = null;
    this.renderCounters();
    const c = counters;
    if (final) c.fps = 0;
    const cellInfo = this.coverage.ready ? ` · grid ${this.coverage.rows}×${this.coverage.cols}` : '';
    if (!this.stream.live) final = true;
    this.statusLine(`${final ? 'stream ended' : `live ${c.fps} fps`} · ${c.gridFrames} grid frames · ${c.posesFrames} poses${cellInfo}`, 'live');
  }

  cellReadout(x, y) {
    const c = this.coverage.cellAt(x, y);
    return c ? `cell ${CELL_STATE_NAMES[c.state] || c.state}${c.visits ? ` ×${c.visits}` : ''}` : '';
  }
}
