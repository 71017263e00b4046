// The Mission tab: planner (from GET /api/planners), PDM, rovers placed by clicking on the map
// (heading by dragging from the click point), pace, and every planner parameter with its
// default, unit and doc, checked against min/max/choices before sending. A 400 from the server
// is shown next to the input its field names. Parameters come in the sections of the planner's
// own table (`group`), its common ones first and the rest folded away (`level`); the planner's
// presets ("paper 001", "fast preview") fill the form in.

import { api } from './api.js';
import { parseBbox } from './area_tool.js';
import { state } from './state.js';
import { StartMarks } from './start_marks.js';
import { history } from './undo_stack.js';
import { $, el, fmt, roverColour, showError } from './util.js';

// A number as a person reads it: 6 significant digits, so a default converted from radians shows
// "15", not "14.999999999999998", and 0.1 + 0.2 shows 0.3. Whole numbers stay exact (seeds).
// Lists are tidied element by element.
function tidy(v) {
  if (Array.isArray(v)) return v.map(tidy);
  if (typeof v !== 'number' || !Number.isFinite(v) || Number.isInteger(v)) return v;
  return Number(v.toPrecision(6));
}

// A section's title: its key from the table, capitalised ("RRT*" stays as it is).
const groupTitle = (g) => (g ? g.charAt(0).toUpperCase() + g.slice(1) : 'Other');

const FIELD_PREFIX = 'm-param-';

export class MissionForm {
  constructor({ view, onLaunched }) {
    this.view = view;
    this.onLaunched = onLaunched;
    this.rovers = [];      // {x, y, heading} or null (not placed yet)
    this.next = 0;         // the rover the next click places
    this.placing = false;
    this.drag = null;
    this.starts = new StartMarks(view, 50);  // an OL layer, following the rovers each frame
    view.onRender(() => this.starts.sync(this.rovers, state.tool === 'rovers' || this.showStarts));
    view.registerTool('rovers', {
      down: (p) => this.placeDown(p),
      move: (p) => this.placeMove(p),
      up: (p, e, moved) => this.placeUp(moved),
    });
    $('m-planner').addEventListener('change', () => {
      this.renderParams();
      this.renderPdmNote();
    });
    $('m-preset').addEventListener('change', () => this.applyPreset($('m-preset').value));
    $('m-rover-count').addEventListener('input', () => this.setCount(Number($('m-rover-count').value)));
    $('m-place').addEventListener('click', () => this.setPlacing(!this.placing));
    $('mission-form').addEventListener('submit', (e) => {
      e.preventDefault();
      this.launch();
    });
    $('m-pdm').addEventListener('change', () => {
      this.pdmChosen = true;  // the operator's choice ("none" too) is kept over the default
      state.pdmId = $('m-pdm').value;
      state.emit('pdm-selected', state.pdmId);
    });
    state.on('map', () => {
      this.pdmChosen = false;
      this.rovers = this.rovers.map(() => null);
      this.next = 0;
      this.renderRovers();
      this.renderPdms();
      this.defaultsLoading = this.loadMapDefaults();  // load() waits for it before filling in
    });
    $('m-file').addEventListener('change', (e) => this.runFile(e.target));
    // Drawing the mission area (area_tool.js) takes the map's pointer from rover placing.
    state.on('tool', (tool) => {
      if (tool !== 'area' || !this.placing) return;
      this.placing = false;
      $('m-place').setAttribute('aria-pressed', 'false');
      $('m-place').textContent = 'place on map';
      this.renderRovers();
    });
    state.on('pdms', () => this.renderPdms());
    state.on('pdm-selected', () => this.renderPdms());
    this.setCount(Number($('m-rover-count').value) || 1);
  }

  setPlanners(planners) {
    const sel = $('m-planner');
    const current = sel.value;
    sel.replaceChildren(...planners.map((p) => el('option', { value: p.name, title: p.summary }, p.name)));
    if (planners.some((p) => p.name === current)) sel.value = current;
    this.renderParams();
  }

  // The defaults that come from the selected map (GET /api/planners?map=ID): the coverage cell
  // (the map's own, or the smallest that fits the cell budget) and the body whose gravity the
  // energy model assumes. The form then shows them as the defaults, so they are not sent.
  async loadMapDefaults() {
    const map = state.map;
    if (!map) return;
    try {
      const planners = await api.plannersForMap(map.id);
      if (state.map !== map) return;  // another map was chosen meanwhile
      state.planners = planners;
      this.setPlanners(planners);
    } catch (err) {
      $('m-planner-summary').textContent = `map defaults unavailable: ${err.message}`;
    }
  }

  // One line under the planner summary: what this map sets by default.
  renderMapDefaults(p) {
    let box = $('m-map-defaults');
    if (!box) {
      box = el('div', { id: 'm-map-defaults', class: 'doc' });
      $('m-params').before(box);
    }
    const d = p && p.map_defaults;
    if (!d) return box.replaceChildren();
    const parts = [`body ${d.body === 'unknown' ? 'unknown (the CRS names none)' : d.body}`];
    if (d.gravity !== undefined) parts.push(`gravity ${fmt(d.gravity)} m/s²`);
    else if (p.params.some((i) => i.key === 'gravity')) parts.push('gravity: the parameter default');
    if (d.coverage_cell !== undefined) {
      const m = state.map;
      const grid = m ? ` (${Math.floor(m.height_m / d.coverage_cell + 1e-6)} × ${Math.floor(m.width_m / d.coverage_cell + 1e-6)} cells)` : '';
      parts.push(`coverage cell ${fmt(d.coverage_cell)} m${grid}`);
    }
    box.textContent = `This map's defaults: ${parts.join(', ')}.`;
  }

  get planner() {
    return state.planners.find((p) => p.name === $('m-planner').value) || null;
  }

  // --- parameters ---
  renderParams() {
    const p = this.planner;
    $('m-planner-summary').textContent = p ? p.summary : 'The server lists no planner.';
    const box = $('m-params');
    if (!p) {
      this.renderMapDefaults(null);
      return box.replaceChildren();
    }
    // Sections in the table's order; in each, the common parameters, then the rest folded.
    const groups = new Map();
    for (const info of p.params) {
      if (!groups.has(info.group)) groups.set(info.group, []);
      groups.get(info.group).push(info);
    }
    box.replaceChildren(...[...groups].map(([group, infos]) => {
      const common = infos.filter((i) => i.level === 'common');
      const rest = infos.filter((i) => i.level !== 'common');
      const more = rest.length ? el('details', { class: 'param-more' },
        el('summary', {}, `${rest.length} more ${groupTitle(group)} parameter${rest.length > 1 ? 's' : ''}`),
        ...rest.map((info) => this.paramRow(info))) : null;
      return el('fieldset', { class: 'param-group', dataset: { group } },
        el('legend', {}, groupTitle(group)), ...common.map((info) => this.paramRow(info)), more);
    }));
    this.renderPresets(p);
    this.renderMapDefaults(p);
    this.updateDependent();
  }

  // --- presets (the planner's own, from GET /api/planners) ---
  renderPresets(p) {
    const sel = $('m-preset');
    const presets = p.presets || [];
    sel.replaceChildren(el('option', { value: '' }, 'defaults'), ...presets.map((x) => el('option', { value: x.name, title: x.doc }, x.name)));
    sel.value = '';
    $('m-preset-doc').textContent = presets.length ? 'Defaults, or a preset: it sets the parameters it names, the rest take their defaults.' : '';
  }

  // Every parameter back to its default, then the preset's values.
  applyPreset(name) {
    const p = this.planner;
    if (!p) return;
    const preset = (p.presets || []).find((x) => x.name === name);
    for (const info of p.params) this.setInput(info, tidy(info.default));
    if (preset) for (const [key, value] of Object.entries(preset.params)) {
      const info = p.params.find((i) => i.key === key);
      if (info) this.setInput(info, tidy(value));
    }
    $('m-preset-doc').textContent = preset ? preset.doc : 'Every parameter at its default.';
    for (const n of document.querySelectorAll('#m-params .field-error')) n.textContent = '';
    this.updateDependent();
  }

  setInput(info, value) {
    const input = $(FIELD_PREFIX + info.key);
    if (!input) return;
    input.classList.remove('invalid');
    if (input.type === 'checkbox') input.checked = Boolean(value);
    else if (Array.isArray(value)) input.value = value.join(', ');
    else input.value = String(value);
  }

  paramRow(info) {
    const id = FIELD_PREFIX + info.key;
    const shown = tidy(info.default);
    const limits = [info.min !== undefined ? `min ${fmt(info.min)}` : '', info.max !== undefined ? `max ${fmt(info.max)}` : ''].filter(Boolean).join(', ');
    const help = `${info.doc}${info.unit ? ` [${info.unit}]` : ''} — default ${JSON.stringify(shown)}${limits ? `; ${limits}` : ''}`;
    let input;
    switch (info.type) {
      case 'choice':
        input = el('select', { id }, info.choices.map((c) => el('option', { value: c }, c)));
        input.value = info.default;
        break;
      case 'bool':
        input = el('input', { id, type: 'checkbox', checked: Boolean(info.default) });
        break;
      case 'int':
      case 'real':
        input = el('input', {
          id, type: 'number', value: String(shown), step: info.type === 'int' ? '1' : 'any',
          min: info.min !== undefined ? String(tidy(info.min)) : undefined, max: info.max !== undefined ? String(tidy(info.max)) : undefined,
        });
        break;
      default:  // real_list
        input = el('input', { id, type: 'text', value: (shown || []).join(', '), placeholder: 'comma-separated numbers' });
    }
    input.title = help;
    input.dataset.key = info.key;
    input.setAttribute('aria-describedby', `${id}-doc`);
    input.addEventListener('change', () => {
      this.clearFieldError(`params.${info.key}`);
      this.updateDependent();
    });
    return el('div', { class: 'param', dataset: { param: info.key } },
      el('div', { class: 'form-row' }, el('label', { for: id, title: help }, info.key), input, info.unit ? el('span', { class: 'unit' }, info.unit) : null),
      el('div', { class: 'doc', id: `${id}-doc`, title: help }, `${info.doc} (default ${Array.isArray(shown) ? `[${shown.join(', ')}]` : shown}${limits ? `; ${limits}` : ''})`),
      el('div', { class: 'field-error', dataset: { field: `params.${info.key}` } }));
  }

  // cost_table only means something with pattern = custom.
  updateDependent() {
    const pattern = $(`${FIELD_PREFIX}pattern`);
    const row = document.querySelector('[data-param="cost_table"]');
    if (pattern && row) row.classList.toggle('hidden-param', pattern.value !== 'custom');
  }

  // The parameters that differ from their defaults, validated. Returns {params, errors}.
  readParams() {
    const p = this.planner;
    const params = {}, errors = [];
    if (!p) return { params, errors: [['planner', 'choose a planner']] };
    const pattern = $(`${FIELD_PREFIX}pattern`);
    for (const info of p.params) {
      const input = $(FIELD_PREFIX + info.key);
      if (!input) continue;
      const field = `params.${info.key}`;
      let value;
      if (info.type === 'bool') value = input.checked;
      else if (info.type === 'choice') {
        value = input.value;
        if (!info.choices.includes(value)) errors.push([field, `must be one of ${info.choices.join(', ')}`]);
      } else if (info.type === 'real_list') {
        if (info.key === 'cost_table' && pattern && pattern.value !== 'custom') continue;
        const text = input.value.trim();
        value = text === '' ? [] : text.split(/[\s,;]+/).filter(Boolean).map(Number);
        if (value.some((v) => !Number.isFinite(v))) errors.push([field, 'must be numbers separated by commas']);
      } else {
        const text = input.value.trim();
        value = Number(text);
        if (text === '' || !Number.isFinite(value)) errors.push([field, 'must be a number']);
        else if (info.type === 'int' && !Number.isInteger(value)) errors.push([field, 'must be a whole number']);
        else if (info.min !== undefined && value < info.min) errors.push([field, `must be at least ${fmt(info.min)}`]);
        else if (info.max !== undefined && value > info.max) errors.push([field, `must be at most ${fmt(info.max)}`]);
      }
      // Left as shown (the default rounded for reading): the server's exact default applies.
      if (JSON.stringify(value) !== JSON.stringify(tidy(info.default))) params[info.key] = value;
    }
    return { params, errors };
  }

  // --- rovers ---
  setCount(n) {
    if (!Number.isInteger(n) || n < 1 || n > 64) {
      $('m-rover-count').classList.add('invalid');
      return;
    }
    $('m-rover-count').classList.remove('invalid');
    // Fewer rovers drop placements: a step of the undo history (the first call builds the list).
    if (this.rovers.length && n !== this.rovers.length) {
      const before = this.snapshot();
      before.rovers = before.rovers.slice();
      this.resize(n);
      history.push(this, `${n} rovers`, before, this.snapshot());
    } else {
      this.resize(n);
    }
    this.renderRovers();
    this.view.invalidate();
  }

  resize(n) {
    while (this.rovers.length < n) this.rovers.push(null);
    this.rovers.length = n;
    this.next = Math.min(this.next, n - 1);
    const free = this.rovers.findIndex((r) => r === null);
    if (free >= 0) this.next = free;
  }

  // --- undo (undo_stack.js): the rovers' starts and headings, their count ---
  snapshot() {
    return { rovers: this.rovers, next: this.next };
  }

  restore(s) {
    this.rovers = s.rovers;
    this.next = Math.min(s.next, this.rovers.length - 1);
    $('m-rover-count').value = String(this.rovers.length);
    $('m-rover-count').classList.remove('invalid');
    const free = this.rovers.findIndex((r) => r === null);
    if (free >= 0) this.next = free;
    this.renderRovers();
    this.view.invalidate();
  }

  setPlacing(on) {
    this.placing = on;
    $('m-place').setAttribute('aria-pressed', String(on));
    $('m-place').textContent = on ? 'placing… (click map)' : 'place on map';
    state.setTool(on ? 'rovers' : 'pan');
    this.renderRovers();
  }

  // Entering the Mission tab: place rovers straight away when some are not placed yet.
  activate() {
    if (this.rovers.some((r) => r === null)) this.setPlacing(true);
    else if (this.placing) state.setTool('rovers');
  }

  placeDown(p) {
    const m = state.map;
    if (!m || p.x < 0 || p.y < 0 || p.x > m.width_m || p.y > m.height_m) return false;
    const k = this.next;
    this.before = JSON.parse(JSON.stringify(this.snapshot()));  // the placement and its heading drag: one step
    const heading = this.rovers[k]?.heading ?? 0;
    this.rovers[k] = { x: p.x, y: p.y, heading };
    this.drag = { k, sx: p.sx, sy: p.sy, x: p.x, y: p.y };
    this.clearFieldError('rovers');
    this.renderRovers();
    this.view.invalidate();
    return true;
  }

  placeMove(p) {
    const d = this.drag;
    if (!d || Math.hypot(p.sx - d.sx, p.sy - d.sy) < 6) return;
    let deg = (Math.atan2(p.y - d.y, p.x - d.x) * 180) / Math.PI;
    if (deg < 0) deg += 360;
    this.rovers[d.k].heading = Math.round(deg);
    this.renderRovers();
    this.view.invalidate();
  }

  placeUp() {
    if (!this.drag) return;
    history.push(this, `place rover ${this.drag.k + 1}`, this.before, this.snapshot());
    this.drag = null;
    const free = this.rovers.findIndex((r) => r === null);
    if (free >= 0) {
      this.next = free;
    } else {
      this.next = 0;
      this.setPlacing(false);  // all placed: back to panning
    }
    this.renderRovers();
  }

  renderRovers() {
    const box = $('m-rovers');
    const head = el('div', { class: 'rover-row rover-head' }, el('span', {}, '#'), el('span', {}, 'x (m, east)'), el('span', {}, 'y (m, north)'), el('span', {}, 'heading (°)'));
    box.replaceChildren(head, ...this.rovers.map((r, k) => {
      const num = (key, label) => el('input', {
        type: 'number', step: 'any', value: r ? String(Math.round(r[key] * 100) / 100) : '', placeholder: key === 'heading' ? '0°' : 'click map',
        'aria-label': `rover ${k + 1} ${label}`, dataset: { rover: String(k), key },
        onchange: (e) => {
          const v = Number(e.target.value);
          if (e.target.value.trim() === '' || !Number.isFinite(v)) return e.target.classList.add('invalid');
          e.target.classList.remove('invalid');
          history.record(this, `rover ${k + 1} ${label}`, () => {
            this.rovers[k] = { x: 0, y: 0, heading: 0, ...(this.rovers[k] || {}), [key]: v };
          });
          this.view.invalidate();
        },
      });
      return el('div', { class: `rover-row${this.placing && k === this.next ? ' next' : ''}`, title: `rover ${k + 1}: x, y (m), heading (° ccw from east)` },
        el('span', { class: 'rover-dot', style: `background:${roverColour(k)}` }),
        num('x', 'x (m)'), num('y', 'y (m)'), num('heading', 'heading (deg)'));
    }));
  }

  // The PDM menu: the one shown on the map, else (until the operator picks one, "none" included)
  // the map's most recently saved PDM — a search planner without one searches the whole map as
  // equally likely, which sends the routes round the map's edges.
  renderPdms() {
    const sel = $('m-pdm');
    sel.replaceChildren(el('option', { value: '' }, 'none'), ...state.pdms.map((p) => el('option', { value: p.id }, p.name)));
    if (state.pdms.some((p) => p.id === state.pdmId)) {
      sel.value = state.pdmId;
    } else if (!this.pdmChosen && state.pdms.length) {
      const latest = state.pdms.reduce((a, b) => (String(b.created_at || '') > String(a.created_at || '') ? b : a));
      sel.value = latest.id;
      state.pdmId = latest.id;
      queueMicrotask(() => state.emit('pdm-selected', latest.id));  // the map shows it too
    } else {
      sel.value = '';
    }
    this.renderPdmNote();
  }

  // A warning under the menu when a planner that searches a PDM (ground dem_pdm) has none.
  renderPdmNote() {
    const note = $('m-pdm-note');
    const p = this.planner;
    const needs = p && p.ground === 'dem_pdm' && !$('m-pdm').value;
    note.hidden = !needs;
    note.textContent = needs
      ? (state.pdms.length
        ? `${p.name} without a PDM takes every place as equally likely: its route sweeps the whole map, edges first. Choose a PDM.`
        : `${p.name} without a PDM takes every place as equally likely: its route sweeps the whole map, edges first. Make one in the PDM tab.`)
      : '';
  }

  // --- errors ---
  clearErrors() {
    for (const n of document.querySelectorAll('#mission-form .field-error')) n.textContent = '';
    for (const n of document.querySelectorAll('#mission-form .invalid')) n.classList.remove('invalid');
    showError($('m-error'), null);
  }

  clearFieldError(field) {
    const n = document.querySelector(`#mission-form .field-error[data-field="${field}"]`);
    if (n) n.textContent = '';
  }

  // Puts an error next to its input; returns whether a place was found.
  fieldError(field, message) {
    let key = field, input = null;
    const rover = /^rovers(\[(\d+)\])?(\.(\w+))?/.exec(field);
    if (rover) {
      key = 'rovers';
      if (rover[2] !== undefined) input = document.querySelector(`#m-rovers input[data-rover="${rover[2]}"][data-key="${rover[4] || 'x'}"]`);
    } else if (field.startsWith('params.')) {
      input = $(FIELD_PREFIX + field.slice(7));
    } else if (field === 'pace') {
      input = $('m-pace');
    } else if (field === 'pdm') {
      input = $('m-pdm');
    } else if (field.startsWith('area')) {
      key = 'area';
      input = $('m-area');
    } else if (field === 'planner') {
      input = $('m-planner');
    }
    if (input) input.classList.add('invalid');
    input?.closest('details')?.setAttribute('open', '');  // a folded parameter is shown
    const node = document.querySelector(`#mission-form .field-error[data-field="${key}"]`);
    if (node) {
      node.textContent = message;
      node.closest('.param')?.scrollIntoView({ block: 'center' });
    }
    return Boolean(node || input);
  }

  // --- launch ---
  // --- mission files (GET /api/missions/{id}/mission.json) ---
  // "Duplicate and edit": the file's map, planner, PDM, rovers, parameters, pace and name in the
  // form, to change and launch.
  async load(file, selectMap) {
    // The form sends rectangles (area.bbox); a polygon area runs as it is from "open mission file".
    if (file.area?.polygon) throw new Error('this mission\'s area is a polygon: the form draws rectangles only; run its mission file (open mission file) to plan it again');
    if (state.map?.id !== file.map) await selectMap(file.map);
    await this.defaultsLoading;
    const sel = $('m-planner');
    if (![...sel.options].some((o) => o.value === file.planner)) throw new Error(`this server has no planner ${file.planner}`);
    sel.value = file.planner;
    this.renderParams();
    for (const [key, value] of Object.entries(file.params || {})) {
      const input = $(FIELD_PREFIX + key);
      if (!input) throw new Error(`planner ${file.planner} has no parameter ${key}`);
      if (input.type === 'checkbox') input.checked = Boolean(value);
      else input.value = Array.isArray(value) ? value.join(', ') : String(value);
    }
    this.updateDependent();
    $('m-pdm').value = file.pdm || '';
    $('m-pdm').dispatchEvent(new Event('change'));
    const rovers = (file.rovers || []).map((r) => ({ x: r.x, y: r.y, heading: r.heading ?? 0 }));
    $('m-rover-count').value = String(rovers.length);
    this.rovers = rovers;
    this.next = 0;
    this.setPlacing(false);  // every rover is placed
    this.renderRovers();
    if (file.pace !== undefined) $('m-pace').value = String(file.pace);
    $('m-name').value = file.name ? `${file.name} (copy)` : '';
    $('m-area').value = file.area?.bbox ? file.area.bbox.join(', ') : '';
    $('m-area').dispatchEvent(new Event('input'));  // the outline follows
    this.view.invalidate();
  }

  // "Open mission file": the file is sent as it is, so the server checks its map's digest and the
  // run is the same as the one that wrote it.
  async runFile(input) {
    const f = input.files && input.files[0];
    input.value = '';
    if (!f) return;
    const status = $('m-file-status');
    try {
      if (f.size > 64 * 1024) throw new Error(`${f.name} is ${Math.round(f.size / 1024)} KB: a mission file is at most 64 KB`);
      let file;
      try {
        file = JSON.parse(await f.text());
      } catch {
        throw new Error(`${f.name} is not JSON`);
      }
      status.textContent = `sending ${f.name}…`;
      const mission = await api.launch(file);
      status.textContent = `launched ${mission.id} from ${f.name}`;
      await this.onLaunched(mission);
    } catch (err) {
      status.textContent = '';
      showError($('m-error'), `${f.name}: ${err.message}${err.field ? ` (field: ${err.field})` : ''}`);
    }
  }

  async launch() {
    this.clearErrors();
    const map = state.map;
    if (!map) return showError($('m-error'), 'select a map first');
    const { params, errors } = this.readParams();
    const missing = this.rovers.findIndex((r) => r === null);
    if (missing >= 0) errors.push([`rovers[${missing}]`, `place rover ${missing + 1} on the map (click it)`]);
    const paceText = $('m-pace').value.trim();
    const pace = Number(paceText);
    if (paceText === '' || !Number.isFinite(pace) || pace < 0 || pace > 1e6) errors.push(['pace', 'pace must be a number of steps per second in [0, 1e6]']);
    // The mission area (issue 24): x0, y0, x1, y1 in the map's local metres; the server checks it
    // against the map.
    const areaText = $('m-area').value.trim();
    const bbox = areaText === '' ? null : parseBbox(areaText);
    if (areaText !== '' && !bbox) errors.push(['area', 'area must be four numbers x0, y0, x1, y1 (metres)']);
    if (errors.length) {
      for (const [f, msg] of errors) this.fieldError(f, msg);
      showError($('m-error'), `not sent: ${errors.map(([f, m]) => `${f}: ${m}`).join('; ')}`);
      return;
    }
    const body = {
      map: map.id,
      planner: this.planner.name,
      rovers: this.rovers.map((r) => ({ x: r.x, y: r.y, heading: r.heading })),
      params,
      pace,
    };
    if ($('m-pdm').value) body.pdm = $('m-pdm').value;
    // Keep-out zones (issue 13): the map's saved zones, when the operator keeps the box ticked.
    if ($('m-keep-out').checked && state.zones?.features?.length) body.keep_out = state.zones;
    if ($('m-name').value.trim()) body.name = $('m-name').value.trim();
    if (bbox) body.area = { bbox };
    const button = $('m-launch');
    button.disabled = true;
    $('m-launch-status').textContent = 'sending…';
    try {
      const mission = await api.launch(body);
      $('m-launch-status').textContent = `launched ${mission.id}`;
      this.setPlacing(false);
      await this.onLaunched(mission);
    } catch (err) {
      $('m-launch-status').textContent = '';
      const placed = err.field ? this.fieldError(err.field, err.message) : false;
      showError($('m-error'), `the server refused the mission: ${err.message}${err.field ? ` (field: ${err.field})` : ''}${placed ? '' : ''}`);
    } finally {
      button.disabled = false;
    }
  }
}
