// The PDM tab: a Gaussian mixture edited on the map (click to add, drag the centre to move,
// square handles for σx / σy, the round handle to rotate), numbers per component, random (G=4)
// from the server, clear, save. The brush (issue 27, "paint" mode): a drag lays round Gaussians
// of the brush's σ and weight along the stroke, one every σ (so neighbours overlap into an even
// band: the sum of Gaussians σ apart varies by under 1 % across the band); Shift or Alt + drag
// erases the components whose centre is under the brush. Gaussians rather than a raster brush:
// the server's PDM is a mixture (components, at most 256), so what is painted is what is saved,
// editable afterwards like any clicked Gaussian. Painting never pans: the tool takes the drag.
// A stroke is one step of the undo history. While editing, the mixture density is drawn on a coarse grid as
// an overlay (an OL image layer); once saved, the server's pdm.png for the new id is shown instead.
// Several operators (issue 26): unsaved components are a draft of the map (drafts.js), kept over
// map switches and reloads; "random (G=4)" makes a draft, not a saved PDM; "update" saves the
// components into the PDM they were loaded from, naming its version, and a 412 shows both; PDMs
// saved elsewhere arrive from the event stream (remoteChanged); both in pdm_versions.js.

import { api } from './api.js';
import { RasterOverlay } from './raster_overlay.js';
import { HANDLE, PdmHandles, ROT_OFFSET } from './pdm_handles.js';
import { clearDraft, loadDraft, saveDraft } from './drafts.js';
import { state } from './state.js';
import { rampLegend } from './legend.js';
import { followRemotePdm, randomComponents, showPdmConflict } from './pdm_versions.js';
import { history } from './undo_stack.js';
import { $, el, report, showError } from './util.js';

const GRID = 160;           // overlay cells on the longer side
const MAX_COMPONENTS = 256; // the server's limit (core/pdm/pdm.hpp kMaxComponents)
const CUTOFF = 4;           // overlay: a component adds to cells within 4σ (e^-8 beyond)
// A perceptual ramp (viridis-like) for the overlay and its legend.
const RAMP = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];

function rampColour(t) {
  const u = Math.max(0, Math.min(1, t)) * (RAMP.length - 1);
  const i = Math.min(RAMP.length - 2, Math.floor(u)), f = u - i;
  return RAMP[i].map((a, k) => Math.round(a + (RAMP[i + 1][k] - a) * f));
}

export class PdmEditor {
  constructor({ view, layers, conflicts }) {
    this.view = view;
    this.layers = layers;
    this.conflicts = conflicts;
    this.base = null;       // the saved PDM the components were loaded from {id, version, name, comps}
    this.comps = [];
    this.active = -1;
    this.dirty = false;     // edited since the last save/load
    this.drag = null;
    this.overlay = document.createElement('canvas');
    this.overlayCtx = this.overlay.getContext('2d');
    this.overlayMax = 0;
    this.mode = 'shape';    // 'shape': click adds, handles shape · 'paint': the brush
    this.stroke = null;     // the brush stroke in progress
    this.brushHover = null;
    this.editLayer = layers.addOverlay({ id: 'pdm-edit', label: 'PDM (editing)', legendTitle: 'PDM being edited (mixture density)', visible: true, opacity: 0.6, legend: () => this.legend() });
    // The density: an OL image layer under the other overlays (raster_overlay.js); the components
    // and their handles OL features dragged with Modify (pdm_handles.js); the brush stays on the
    // overlay canvas.
    this.density = new RasterOverlay(view, 20, 'pdm-density',
      () => (state.map && this.overlayMax > 0 ? { canvas: this.overlay, rect: [0, 0, state.map.width_m, state.map.height_m] } : null), { smooth: true });
    view.onRender(() => {
      this.density.layer.setOpacity(this.editLayer.opacity);
      this.density.layer.setVisible(this.showOverlay() && this.overlayMax > 0);
    });
    // Shaping: the handle Modify took follows the pointer; its path becomes the component's
    // centre, σ or rotation.
    this.olHandles = new PdmHandles(view, {
      grab: (p) => this.pointerDown(p), drag: (p) => this.pointerMove(p), release: () => this.pointerUp(),
    });
    view.onRender(() => this.olHandles.sync(this.comps, this.active, state.tool === 'pdm' && this.mode === 'shape' && Boolean(state.map)));
    view.addLayer({ id: 'pdm-edit', order: 20, draw: (ctx, v) => this.draw(ctx, v) });
    view.registerTool('pdm', {
      // Painting: a press is a brush stroke (no pan). Shaping: a press on a handle is Modify's,
      // which keeps it from the map's pan and passes the pointer's path on (pdm_handles.js).
      down: (p, e) => this.mode === 'paint' && this.strokeStart(p, e),
      move: (p) => this.strokeMove(p),
      up: () => this.strokeEnd(),
      click: (p) => this.add(p.x, p.y),
      hover: (p) => {
        if (this.mode !== 'paint') return;
        this.brushHover = p;
        view.invalidate();
      },
    });
    for (const mode of ['shape', 'paint']) $(`pdm-mode-${mode}`).addEventListener('click', () => this.setMode(mode));
    view.box.addEventListener('pointerleave', () => {
      this.brushHover = null;
      view.invalidate();
    });
    $('pdm-random').addEventListener('click', () => this.random());
    $('pdm-clear').addEventListener('click', () => this.clear());
    $('pdm-save').addEventListener('click', () => this.save());
    $('pdm-update').addEventListener('click', () => this.update());
    $('pdm-name').addEventListener('change', () => this.keepDraft());
    state.on('map', (map) => this.openDraft(map));
    state.on('pdms', () => this.renderList());
    state.on('presence', () => this.renderList());
    state.on('pdm-selected', () => this.renderList());
    this.renderComponents();
  }

  // --- editing ---
  defaultSigma() {
    const m = state.map;
    return m ? Math.max(m.cell_size_m * 2, Math.min(m.width_m, m.height_m) * 0.08) : 10;
  }

  // --- the brush ---
  setMode(mode) {
    this.mode = mode;
    for (const m of ['shape', 'paint']) {
      $(`pdm-mode-${m}`).setAttribute('aria-pressed', String(m === mode));
      $(`pdm-mode-${m}`).classList.toggle('active', m === mode);
    }
    $('pdm-brush').hidden = mode !== 'paint';
    if (mode === 'paint' && !(Number($('pdm-brush-sigma').value) > 0)) $('pdm-brush-sigma').value = String(Number(this.defaultBrushSigma().toPrecision(3)));
    state.emit('pdm-mode', mode);
    this.view.invalidate();
  }

  defaultBrushSigma() {
    const m = state.map;
    return m ? Math.max(m.cell_size_m * 2, Math.min(m.width_m, m.height_m) * 0.03) : 5;
  }

  brush() {
    const m = state.map;
    let sigma = Number($('pdm-brush-sigma').value), weight = Number($('pdm-brush-weight').value);
    const minSigma = m ? m.cell_size_m / 2 : 0.01;
    $('pdm-brush-sigma').classList.toggle('invalid', !(sigma >= minSigma));
    $('pdm-brush-weight').classList.toggle('invalid', !(weight > 0));
    if (!(sigma >= minSigma)) sigma = this.defaultBrushSigma();
    if (!(weight > 0)) weight = 1;
    return { sigma, weight };
  }

  // Always takes the drag (returns true), so a stroke never pans the map.
  strokeStart(p, e) {
    const { sigma, weight } = this.brush();
    this.stroke = { before: JSON.parse(JSON.stringify(this.snapshot())), erase: e.shiftKey || e.altKey, sigma, weight, last: null, added: 0, removed: 0 };
    this.strokeMove(p);
    return true;
  }

  strokeMove(p) {
    const st = this.stroke;
    if (!st) return;
    this.brushHover = p;
    if (st.erase) {
      // Along the segment since the last event, every σ/2, so a fast drag leaves no gap.
      const from = st.last || [p.x, p.y];
      const n = Math.max(1, Math.ceil(Math.hypot(p.x - from[0], p.y - from[1]) / (st.sigma / 2)));
      const keep = this.comps.filter((g) => {
        for (let k = 0; k <= n; k++) {
          const x = from[0] + ((p.x - from[0]) * k) / n, y = from[1] + ((p.y - from[1]) * k) / n;
          if (Math.hypot(g.x - x, g.y - y) <= st.sigma) return false;
        }
        return true;
      });
      st.removed += this.comps.length - keep.length;
      if (keep.length !== this.comps.length) {
        this.comps = keep;
        this.active = -1;
        this.changed(true, false);
      }
      st.last = [p.x, p.y];
      this.view.invalidate();
      return;
    }
    const m = state.map;
    const inside = (x, y) => m && x >= 0 && y >= 0 && x <= m.width_m && y <= m.height_m;
    const place = (x, y) => {
      if (this.comps.length >= MAX_COMPONENTS) {
        st.full = true;
        return;
      }
      if (!inside(x, y)) return;
      this.comps.push({ x, y, sigma_x: st.sigma, sigma_y: st.sigma, rotation_deg: 0, weight: st.weight });
      st.added++;
    };
    const before = this.comps.length;
    if (!st.last) {
      place(p.x, p.y);
      st.last = [p.x, p.y];
    } else {
      // One Gaussian every σ along the stroke, from the last one laid.
      let [lx, ly] = st.last;
      let d = Math.hypot(p.x - lx, p.y - ly);
      while (d >= st.sigma) {
        lx += ((p.x - lx) / d) * st.sigma;
        ly += ((p.y - ly) / d) * st.sigma;
        place(lx, ly);
        d = Math.hypot(p.x - lx, p.y - ly);
      }
      st.last = [lx, ly];
    }
    if (this.comps.length !== before) {
      this.active = this.comps.length - 1;
      this.changed(true, false);
    } else {
      this.view.invalidate();
    }
  }

  strokeEnd() {
    const st = this.stroke;
    this.stroke = null;
    if (!st) return;
    const label = st.erase ? `erase ${st.removed} Gaussian${st.removed === 1 ? '' : 's'}` : `paint ${st.added} Gaussian${st.added === 1 ? '' : 's'}`;
    history.push(this, label, st.before, this.snapshot());
    $('pdm-save-status').textContent = st.full ? `the PDM is full (${MAX_COMPONENTS} components, the server's limit): erase or save` : '';
    this.changed(st.added > 0 || st.removed > 0);
  }

  add(x, y) {
    const m = state.map;
    if (!m || x < 0 || y < 0 || x > m.width_m || y > m.height_m) return;
    const s = this.defaultSigma();
    history.record(this, 'add Gaussian', () => {
      this.comps.push({ x, y, sigma_x: s, sigma_y: s * 0.6, rotation_deg: 0, weight: 1 });
      this.active = this.comps.length - 1;
    });
    this.changed(true);
  }

  remove(i) {
    history.record(this, `remove Gaussian ${i + 1}`, () => {
      this.comps.splice(i, 1);
      this.active = Math.min(this.active, this.comps.length - 1);
    });
    this.changed(true);
  }

  clear() {
    history.record(this, 'clear the PDM', () => {
      this.comps = [];
      this.active = -1;
    });
    this.changed(true);
    showError($('pdm-error'), null);
  }

  // --- undo (undo_stack.js): the components and which one is active ---
  snapshot() {
    return { comps: this.comps, active: this.active };
  }

  restore(s) {
    this.comps = s.comps;
    this.active = Math.min(s.active, this.comps.length - 1);
    this.changed(true);
  }

  // A map's draft (drafts.js) comes back when the map is shown again or the page reloaded.
  openDraft(map) {
    const d = map ? loadDraft(map.id, 'pdm') : null;
    this.comps = d && Array.isArray(d.comps) ? d.comps : [];
    this.base = d?.base || null;
    this.active = this.comps.length ? 0 : -1;
    this.dirty = Boolean(d);
    $('pdm-name').value = d?.name || '';
    $('pdm-save-status').textContent = d ? `unsaved draft restored (${this.comps.length} component${this.comps.length === 1 ? '' : 's'})` : '';
    showError($('pdm-error'), null);
    this.changed();
    this.renderList();
  }

  keepDraft() {
    const m = state.map;
    if (!m) return;
    if (this.dirty && this.comps.length) saveDraft(m.id, 'pdm', { comps: this.comps, name: $('pdm-name').value, base: this.base });
    else clearDraft(m.id, 'pdm');
  }

  // `list`: false during a brush stroke (the component list is redrawn once, at its end).
  changed(edited = false, list = true) {
    if (edited) this.dirty = true;
    if (list) this.keepDraft();
    $('pdm-update').disabled = !(this.base && this.dirty && this.comps.length);
    $('pdm-history').disabled = !state.pdmId;
    this.computeOverlay();
    if (list) this.renderComponents();
    this.layers.renderLegends();
    this.view.invalidate();
  }

  // Screen positions of a component's handles.
  handles(g) {
    const v = this.view;
    const a = (g.rotation_deg * Math.PI) / 180, c = Math.cos(a), s = Math.sin(a);
    const [cx, cy] = v.worldToScreen(g.x, g.y);
    const [hx, hy] = v.worldToScreen(g.x + c * g.sigma_x, g.y + s * g.sigma_x);
    const [vx, vy] = v.worldToScreen(g.x - s * g.sigma_y, g.y + c * g.sigma_y);
    const len = Math.hypot(hx - cx, hy - cy) || 1;
    const rx = hx + ((hx - cx) / len) * ROT_OFFSET, ry = hy + ((hy - cy) / len) * ROT_OFFSET;
    return { centre: [cx, cy], sx: [hx, hy], sy: [vx, vy], rot: [rx, ry] };
  }

  hit(p) {
    // The active component's handles first, then any centre.
    const order = [...this.comps.keys()].sort((a, b) => (b === this.active) - (a === this.active));
    for (const i of order) {
      const h = this.handles(this.comps[i]);
      for (const kind of ['rot', 'sx', 'sy', 'centre']) {
        const [hx, hy] = h[kind];
        if (Math.abs(p.sx - hx) <= HANDLE + 3 && Math.abs(p.sy - hy) <= HANDLE + 3) return { i, kind };
      }
    }
    return null;
  }

  pointerDown(p) {
    const h = this.hit(p);
    if (!h) return false;
    const before = this.snapshot();
    this.active = h.i;
    const g = this.comps[h.i];
    this.drag = { ...h, dx: g.x - p.x, dy: g.y - p.y, before: JSON.parse(JSON.stringify(before)) };
    this.renderComponents();
    this.view.invalidate();
    return true;
  }

  pointerMove(p) {
    const d = this.drag;
    if (!d) return;
    const g = this.comps[d.i];
    const minSigma = state.map ? state.map.cell_size_m / 2 : 0.01;
    const a = (g.rotation_deg * Math.PI) / 180, c = Math.cos(a), s = Math.sin(a);
    const rx = p.x - g.x, ry = p.y - g.y;
    if (d.kind === 'centre') {
      g.x = p.x + d.dx;
      g.y = p.y + d.dy;
    } else if (d.kind === 'sx') {
      g.sigma_x = Math.max(minSigma, Math.abs(c * rx + s * ry));
    } else if (d.kind === 'sy') {
      g.sigma_y = Math.max(minSigma, Math.abs(-s * rx + c * ry));
    } else if (d.kind === 'rot') {
      let deg = (Math.atan2(ry, rx) * 180) / Math.PI;
      if (deg < 0) deg += 360;
      g.rotation_deg = Math.round(deg * 10) / 10;
    }
    this.changed(true);
  }

  pointerUp() {
    const d = this.drag;
    this.drag = null;
    // The whole drag is one step (nothing when the handle was only clicked).
    if (d) history.push(this, d.kind === 'centre' ? `move Gaussian ${d.i + 1}` : `shape Gaussian ${d.i + 1}`, d.before, this.snapshot());
  }

  // --- overlay ---
  computeOverlay() {
    this.density.changed();
    const m = state.map;
    if (!m || this.comps.length === 0) {
      this.overlayMax = 0;
      return;
    }
    const k = GRID / Math.max(m.width_m, m.height_m);
    const cols = Math.max(1, Math.round(m.width_m * k)), rows = Math.max(1, Math.round(m.height_m * k));
    const dx = m.width_m / cols, dy = m.height_m / rows;
    const values = new Float32Array(rows * cols);
    // Each component over the cells within CUTOFF σ of its centre only: a brush stroke of a few
    // hundred small Gaussians redraws at pointer speed.
    let wsum = 0;
    for (const g of this.comps) wsum += g.weight;
    for (const g of wsum > 0 ? this.comps : []) {
      const a = (g.rotation_deg * Math.PI) / 180, ca = Math.cos(a), sa = Math.sin(a);
      const reach = CUTOFF * Math.max(g.sigma_x, g.sigma_y);
      const c0 = Math.max(0, Math.floor((g.x - reach) / dx)), c1 = Math.min(cols - 1, Math.ceil((g.x + reach) / dx));
      const r0 = Math.max(0, Math.floor((m.height_m - g.y - reach) / dy)), r1 = Math.min(rows - 1, Math.ceil((m.height_m - g.y + reach) / dy));
      const k = g.weight / (2 * Math.PI * g.sigma_x * g.sigma_y) / wsum;
      for (let r = r0; r <= r1; r++) {
        const ry = m.height_m - (r + 0.5) * dy - g.y;
        for (let c = c0; c <= c1; c++) {
          const rx = (c + 0.5) * dx - g.x;
          const u = (ca * rx + sa * ry) / g.sigma_x, v = (-sa * rx + ca * ry) / g.sigma_y;
          values[r * cols + c] += k * Math.exp(-0.5 * (u * u + v * v));
        }
      }
    }
    let max = 0;
    for (let i = 0; i < values.length; i++) if (values[i] > max) max = values[i];
    this.overlay.width = cols;
    this.overlay.height = rows;
    const img = this.overlayCtx.createImageData(cols, rows);
    for (let i = 0; i < values.length; i++) {
      const t = max > 0 ? values[i] / max : 0;
      const [R, G, B] = rampColour(t);
      img.data.set([R, G, B, Math.round(255 * Math.min(1, t * 1.6))], 4 * i);
    }
    this.overlayCtx.putImageData(img, 0, 0);
    this.overlayMax = max;
  }

  showOverlay() {
    return Boolean(this.editLayer && this.editLayer.visible) && this.comps.length > 0 && (this.dirty || !state.pdmId);
  }

  draw(ctx, view) {
    const m = state.map;
    if (!m) return;
    if (state.tool !== 'pdm') return;
    if (this.mode === 'paint') return this.drawBrush(ctx, view);
  }

  // Paint mode: the centres as dots and the brush (radius σ: what Shift/Alt erases) under the cursor.
  drawBrush(ctx, view) {
    ctx.fillStyle = 'rgba(255,255,255,0.85)';
    for (const g of this.comps) {
      const [x, y] = view.worldToScreen(g.x, g.y);
      ctx.fillRect(x - 1.5, y - 1.5, 3, 3);
    }
    const p = this.brushHover;
    if (!p) return;
    const { sigma } = this.brush();
    const erase = this.stroke ? this.stroke.erase : false;
    ctx.beginPath();
    ctx.arc(p.sx, p.sy, sigma * view.scale, 0, 2 * Math.PI);
    ctx.strokeStyle = 'rgba(0,0,0,0.7)';
    ctx.lineWidth = 3;
    ctx.stroke();
    ctx.strokeStyle = erase ? '#ff6b6b' : '#ffb347';
    ctx.lineWidth = 1.5;
    ctx.setLineDash(erase ? [4, 3] : []);
    ctx.stroke();
    ctx.setLineDash([]);
  }

  legend() {
    if (!this.showOverlay()) return null;
    const hi = this.overlayMax > 0 ? this.overlayMax : 1;
    return rampLegend({ lo: 0, hi, unit: '/m²', colourAt: (v) => rampColour(v / hi) });
  }

  // --- panel ---
  renderComponents() {
    const node = $('pdm-components');
    if (this.comps.length === 0) {
      node.replaceChildren(el('div', { class: 'muted small' }, 'No component yet: click the map.'));
      return;
    }
    // Keep focus and caret while typing into a field of this list.
    const focused = document.activeElement && node.contains(document.activeElement) ? document.activeElement.dataset.key : null;
    node.replaceChildren(...this.comps.map((g, i) => {
      const field = (key, label, step, min) => el('label', {}, label,
        el('input', {
          type: 'number', step, min, value: String(Number(g[key].toFixed(3))), dataset: { key: `${i}.${key}` },
          'aria-label': `component ${i + 1} ${label}`,
          onchange: (e) => {
            const v = Number(e.target.value);
            if (!Number.isFinite(v) || (min !== undefined && v < Number(min)) || ((key === 'sigma_x' || key === 'sigma_y') && v <= 0)) {
              e.target.classList.add('invalid');
              return;
            }
            e.target.classList.remove('invalid');
            history.record(this, `Gaussian ${i + 1} ${label}`, () => {
              g[key] = v;
              this.active = i;
            });
            this.changed(true);
          },
        }));
      return el('div', { class: `pdm-comp${i === this.active ? ' active' : ''}`, dataset: { component: String(i) } },
        el('span', { class: 'idx' }, String(i + 1)),
        field('x', 'x (m)', 'any'), field('y', 'y (m)', 'any'), field('weight', 'weight', 'any', '0'),
        field('sigma_x', 'σx (m)', 'any', '0'), field('sigma_y', 'σy (m)', 'any', '0'), field('rotation_deg', 'rot (°)', 'any'),
        el('button', { class: 'small remove', title: `remove component ${i + 1}`, onclick: () => this.remove(i) }, 'remove'));
    }));
    if (focused) {
      const again = node.querySelector(`[data-key="${focused}"]`);
      if (again) again.focus();
    }
  }

  renderList() {
    const list = $('pdm-list');
    if (!state.pdms.length) {
      list.replaceChildren(el('li', { class: 'muted small' }, 'none yet'));
      return;
    }
    list.replaceChildren(...state.pdms.map((p) => el('li', { class: state.pdmId === p.id ? 'selected' : '', dataset: { pdm: p.id } },
      el('button', { class: 'name', title: `${p.name} — ${p.id} (${p.kind || 'PDM'}, v${p.version ?? 1})`, onclick: () => this.select(p) }, p.name),
      el('span', { class: 'meta' }, p.kind || ''),
      this.editingMark(p),
      el('button', { class: 'small', 'aria-label': `delete PDM ${p.name}`, title: 'delete', onclick: () => this.deletePdm(p) }, '✕'))));
  }

  // "✎ name" on a PDM another operator is editing now (presence.js).
  editingMark(p) {
    const names = state.presence?.editorsOf(`pdm:${p.id}`) || [];
    return names.length ? el('span', { class: 'editing-mark', title: `${names.join(', ')} editing it now` }, `✎ ${names.join(', ')}`) : null;
  }

  // Shows a saved PDM (the server's layer) and loads its components for further editing; unsaved
  // components are not replaced without asking.
  select(p) {
    if (this.dirty && this.comps.length && !window.confirm(`Load “${p.name}” and drop your ${this.comps.length} unsaved component${this.comps.length === 1 ? '' : 's'}?`)) return;
    // Loading a saved PDM replaces the components being edited: undoable like an edit.
    history.record(this, `load PDM ${p.name}`, () => {
      this.comps = (p.components || []).map((g) => ({ ...g }));
      this.active = this.comps.length ? 0 : -1;
    });
    this.dirty = false;
    this.base = { id: p.id, version: p.version ?? 1, name: p.name, comps: (p.components || []).map((g) => ({ ...g })) };
    $('pdm-name').value = p.name;
    state.pdmId = p.id;
    state.emit('pdm-selected', p.id);
    this.changed();
  }

  // An older version's components (a run's, used_versions.js) as unsaved edits of PDM `p`: the
  // base stays its current version, so "update" makes them the newest.
  loadVersion(p, comps, version) {
    history.record(this, `load v${version} of PDM ${p.name}`, () => {
      this.comps = comps.map((g) => ({ ...g }));
      this.active = this.comps.length ? 0 : -1;
    });
    this.base = { id: p.id, version: p.version ?? 1, name: p.name, comps: (p.components || []).map((g) => ({ ...g })) };
    $('pdm-name').value = p.name;
    $('pdm-save-status').textContent = `v${version} of “${p.name}” loaded (now v${p.version}): update makes it the newest`;
    this.changed(true);
  }

  // A draft of G=4 random Gaussians (issue 26: it used to save a PDM on the server by itself).
  random() {
    const m = state.map;
    if (!m) return;
    showError($('pdm-error'), null);
    const seed = Math.max(0, Math.floor(Number($('pdm-seed').value) || 0));
    if (this.dirty && this.comps.length && !window.confirm(`Replace your ${this.comps.length} unsaved component${this.comps.length === 1 ? '' : 's'} with random ones? (Ctrl+Z brings them back)`)) return;
    history.record(this, `random G=4 seed ${seed}`, () => {
      this.comps = randomComponents(m, 4, seed);
      this.active = 0;
    });
    this.base = null;
    if (state.pdmId) {
      state.pdmId = '';
      state.emit('pdm-selected', '');
    }
    $('pdm-name').value = `random G=4 seed ${seed}`;
    this.changed(true);
    $('pdm-save-status').textContent = 'random draft: not saved';
  }

  async save() {
    const m = state.map;
    if (!m) return;
    showError($('pdm-error'), null);
    if (this.comps.length === 0) {
      showError($('pdm-error'), 'add at least one Gaussian: click the map (field: components)');
      return;
    }
    try {
      const name = $('pdm-name').value.trim() || `PDM ${new Date().toISOString().slice(0, 16).replace('T', ' ')}`;
      const p = await api.createPdm(m.id, { name, components: this.comps });
      this.dirty = false;
      this.base = { id: p.id, version: p.version ?? 1, name: p.name, comps: this.comps.map((g) => ({ ...g })) };
      await this.refresh();
      state.pdmId = p.id;
      state.emit('pdm-selected', p.id);
      $('pdm-save-status').textContent = `saved “${p.name}” (${p.id})`;
      this.changed();
    } catch (err) {
      showError($('pdm-error'), err);
      const f = /^components\[(\d+)\]\.(\w+)$/.exec(err.field || '');
      if (f) {
        const input = document.querySelector(`[data-key="${f[1]}.${f[2] === 'rotation' ? 'rotation_deg' : f[2]}"]`);
        if (input) input.classList.add('invalid');
      }
    }
  }

  // The components into the PDM they were loaded from, naming the version read; on a 412 both
  // versions are shown and the operator chooses.
  async update() {
    const m = state.map, b = this.base;
    if (!m || !b || !this.comps.length) return;
    showError($('pdm-error'), null);
    const name = $('pdm-name').value.trim() || b.name;
    try {
      this.updated(await api.changePdm(m.id, b.id, { name, components: this.comps }, b.version));
    } catch (err) {
      if (err.code === 'version_conflict' && err.current) await this.conflicted(m, err.current);
      else showError($('pdm-error'), err);
    }
  }

  updated(p) {
    this.dirty = false;
    this.comps = (p.components || this.comps).map((g) => ({ ...g }));
    this.base = { id: p.id, version: p.version, name: p.name, comps: this.comps.map((g) => ({ ...g })) };
    $('pdm-name').value = p.name;
    $('pdm-save-status').textContent = `saved “${p.name}” (v${p.version})`;
    const i = state.pdms.findIndex((q) => q.id === p.id);
    if (i >= 0) state.pdms[i] = p;
    state.pdmId = p.id;
    state.emit('pdms', state.pdms);
    state.emit('pdm-selected', p.id);
    this.changed();
  }

  // A 412 on update: both shown, the operator chooses (pdm_versions.js).
  conflicted(map, current) {
    return showPdmConflict(this, map, current);
  }

  // A PDM of this map changed elsewhere (pdm_versions.js).
  remoteChanged(e) {
    return followRemotePdm(this, e);
  }

  async deletePdm(p) {
    try {
      await api.deletePdm(p.map, p.id);
      if (state.pdmId === p.id) {
        state.pdmId = '';
        state.emit('pdm-selected', '');
      }
      await this.refresh();
    } catch (err) {
      report(err);
    }
  }

  async refresh() {
    if (!state.map) return;
    state.pdms = await api.pdms(state.map.id);
    state.emit('pdms', state.pdms);
  }
}
