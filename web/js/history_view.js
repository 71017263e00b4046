// History (issue 26): the saved versions of a map's zone set or of a PDM (the server keeps the
// last 50: GET .../history), listed with who saved each and when; "view" draws one on the map
// (cyan, dashed) beside what is shown now, "restore" makes it the newest version (POST
// .../restore naming the current version, so a save meanwhile is a 412, not lost).

import { api } from './api.js';
import { drawEllipses, drawRings } from './conflict_view.js';
import { state } from './state.js';
import { $, el, report, showError } from './util.js';

const SHOWN = '#3ad6ff';

export class HistoryView {
  constructor({ view, zoneEditor, pdmEditor }) {
    Object.assign(this, { view, zoneEditor, pdmEditor });
    this.target = null;   // {what: 'zones' | 'pdms/ID', title}
    this.viewing = null;  // {version, draw(ctx, v)}
    view.addLayer({ id: 'history', order: 59, draw: (ctx, v) => this.viewing?.draw(ctx, v) });
    $('zones-history').addEventListener('click', () => this.open({ what: 'zones', title: "this map's keep-out zones" }));
    $('pdm-history').addEventListener('click', () => {
      const p = state.pdms.find((q) => q.id === state.pdmId);
      if (p) this.open({ what: `pdms/${p.id}`, title: `PDM “${p.name}”` });
    });
    state.on('map', () => this.close());
  }

  currentVersion() {
    const t = this.target;
    if (t.what === 'zones') return state.zones?.version ?? 0;
    return state.pdms.find((p) => `pdms/${p.id}` === t.what)?.version ?? 0;
  }

  async open(target) {
    const map = state.map;
    if (!map) return;
    this.target = target;
    this.viewing = null;
    const node = $('history-panel');
    node.hidden = false;
    node.replaceChildren(el('div', { class: 'float-title' }, `saved versions of ${target.title}`), el('div', { class: 'muted' }, 'loading…'));
    let list;
    try {
      list = await api.history(map.id, target.what);
    } catch (err) {
      report(err);
      this.close();
      return;
    }
    if (this.target !== target) return;
    const current = this.currentVersion();
    node.replaceChildren(
      el('div', { class: 'float-title' }, `saved versions of ${target.title} (the last 50 are kept)`),
      list.length ? el('ul', {}, ...list.map((h) => el('li', { dataset: { version: String(h.version) } },
        el('b', {}, `v${h.version}`), el('span', { class: 'when' }, `${h.by || 'unknown'} · ${h.at.replace('T', ' ').slice(0, 19)}${h.version === current ? ' · current' : ''}`),
        el('button', { class: 'small', onclick: (e) => this.show(h.version, e.currentTarget.closest('li')) }, 'view'),
        h.version === current ? null : el('button', { class: 'small', onclick: () => this.restore(h.version) }, 'restore'))))
        : el('div', { class: 'muted' }, 'never saved'),
      el('div', { id: 'history-error', class: 'error', role: 'alert', hidden: true }),
      el('div', { class: 'form-row' }, el('button', { onclick: () => this.close() }, 'close')));
    // The versions drawn stay in sight: the map is fitted below the panel.
    this.view.padTop = node.offsetHeight + 8;
    this.view.fit();
  }

  async show(version, li) {
    const map = state.map, t = this.target;
    try {
      const h = await api.historyVersion(map.id, t.what, version);
      if (t !== this.target) return;
      if (t.what === 'zones') {
        const rings = (h.body?.features || []).map((f) => f.geometry.coordinates[0].slice(0, -1));
        this.viewing = { version, draw: (ctx, v) => drawRings(ctx, v, rings, SHOWN, [4, 3]) };
      } else {
        const comps = h.body?.meta?.components || [];
        this.viewing = { version, draw: (ctx, v) => drawEllipses(ctx, v, comps, SHOWN, [4, 3]) };
      }
      for (const x of $('history-panel').querySelectorAll('li')) x.classList.toggle('viewing', x === li);
      this.view.invalidate();
    } catch (err) {
      showError($('history-error'), err);
    }
  }

  async restore(version) {
    const map = state.map, t = this.target;
    const editor = t.what === 'zones' ? this.zoneEditor : this.pdmEditor;
    if (editor.dirty && !window.confirm(`Restore v${version}? Your unsaved edits of ${t.title} are dropped.`)) return;
    try {
      const out = await api.restore(map.id, t.what, version, this.currentVersion());
      if (t.what === 'zones') this.zoneEditor.saved(out);
      else {
        this.pdmEditor.dirty = false;
        this.pdmEditor.updated(out);
      }
      await this.open(t);
    } catch (err) {
      if (err.code === 'version_conflict') {
        // Someone saved meanwhile: the list is read again (with their version), then why.
        await this.open(t);
        showError($('history-error'), `not restored: ${err.message}`);
      } else showError($('history-error'), err);
    }
  }

  close() {
    this.target = null;
    this.viewing = null;
    $('history-panel').hidden = true;
    $('history-panel').replaceChildren();
    this.view.padTop = 0;
    this.view.invalidate();
  }
}
