// Keep-out zones (issue 13; QGroundControl's geofence, MMGIS's draw tool): draw, edit and delete
// polygons on the map, saved with the map (PUT /api/maps/{id}/zones, local frame: metres from the
// map's lower-left corner). The zones are features of an OpenLayers vector layer over the tiles
// (issue 24), drawn and edited with OL's Draw, Modify and Snap (zone_interactions.js), styled by
// zone_style.js; this file keeps the model, the panel, undo, drafts and saving.
//
// Tool 'zones': a click adds a corner to the zone being drawn; a click on its first corner (or
// Enter, or "finish") closes it (3 points at least); Backspace removes its last corner; Escape
// asks, then drops it. Without a zone in progress, dragging a corner moves it (dragging an edge
// adds one), a click inside a zone selects it, Delete removes the selected one. A corner within a
// few pixels of another zone's corner snaps onto it. Every edit is a step of the page's undo
// history (undo_stack.js).
// state.zones holds the zones as last saved/loaded (what missions get); edits are kept here until
// "save zones", and in the map's draft (drafts.js) so they survive switching maps and reloading.
// Several operators (issue 26): each zone keeps its id and version; a save sends them with the
// set's version the edits started from (If-Match), and another operator's save meanwhile is shown
// as a conflict (conflict_view.js) rather than overwritten. Changes saved elsewhere arrive from
// the event stream (remoteChanged): loaded at once when nothing here is unsaved, else the edits
// stay and the count of saved zones says what the server has.

import { api } from './api.js';
import { clearDraft, loadDraft, saveDraft } from './drafts.js';
import { state } from './state.js';
import { showZoneConflict } from './zone_conflict.js';
import { area, inside, zonesFromGeoJson, zonesToGeoJson } from './zone_geometry.js';
import { history } from './undo_stack.js';
import { $, el, fmt, showError } from './util.js';
import Feature from 'ol/Feature.js';
import LineString from 'ol/geom/LineString.js';
import Polygon from 'ol/geom/Polygon.js';
import { sketchStyle, zoneStyle, zoneSwatch } from './zone_style.js';
import { ZoneInteractions } from './zone_interactions.js';

const plural = (n) => `${n} zone${n === 1 ? '' : 's'}`;

export class ZoneEditor {
  constructor({ view, layers, conflicts }) {
    this.view = view;
    this.layers = layers;
    this.conflicts = conflicts;  // conflict_view.js
    this.baseVersion = 0;   // the set's version the edits started from (sent in If-Match)
    this.baseZones = null;  // that set (GeoJSON): what "keep both" merges against
    this.zones = [];        // [{ring: [[x, y], ...] (open), name, id, version}]
    this.drawing = null;    // the ring in progress
    this.selected = -1;
    this.dirty = false;
    // The zones as OL features (one a zone, updated in place), and the unfinished ring while the
    // tool is off (Draw shows it while the tool is on).
    this.olLayer = view.addVectorLayer(45, { style: (f) => zoneStyle(f, state.tool === 'zones') });
    this.features = [];
    this.ringLayer = view.addVectorLayer(46, { style: sketchStyle });
    this.layer = layers.addOverlay({
      id: 'zones', label: 'keep-out zones', legendTitle: 'Keep-out zones', visible: true, opacity: 0.8,
      legend: () => this.legend(), ol: this.olLayer,
    });
    this.ol = new ZoneInteractions(this, view, this.olLayer.getSource());
    view.registerTool('zones', {
      click: (p) => this.click(p),
    });
    $('zones-draw').addEventListener('click', () => this.setActive(state.tool !== 'zones'));
    $('zones-finish').addEventListener('click', () => this.finish());
    $('zones-delete').addEventListener('click', () => this.removeSelected());
    $('zones-save').addEventListener('click', () => this.save());
    $('zones-import').addEventListener('change', (e) => this.importFile(e.target));
    view.canvas.addEventListener('keydown', (e) => {
      if (state.tool !== 'zones') return;
      if (e.key === 'Enter') this.finish();
      else if (e.key === 'Escape') this.cancel(true);
      else if (e.key === 'Backspace' && this.drawing) this.removeLastVertex();
      else if (e.key === 'Delete' || e.key === 'Backspace') this.removeSelected();
      else return;
      e.preventDefault();
    });
    state.on('tool', (tool) => {
      $('zones-draw').setAttribute('aria-pressed', String(tool === 'zones'));
      $('zones-draw').classList.toggle('active', tool === 'zones');
      if (tool !== 'zones') this.cancel();
      this.olLayer.changed();  // the corner handles come and go with the tool
      this.render();
    });
    state.on('map', (map) => { this.loading = this.load(map); });  // awaited by used_versions.js
    state.on('presence', () => this.renderList());
    this.renderList();
  }

  setActive(on) {
    state.setTool(on ? 'zones' : 'pan');
  }

  async load(map) {
    this.zones = [];
    this.drawing = null;
    this.selected = -1;
    this.dirty = false;
    this.baseVersion = 0;
    state.zones = { type: 'FeatureCollection', features: [], version: 0 };
    showError($('zones-error'), null);
    $('zones-status').textContent = '';
    if (map) {
      try {
        const fc = await api.zones(map.id);
        if (state.map?.id !== map.id) return;  // another map was chosen meanwhile
        state.zones = fc;
        this.zones = zonesFromGeoJson(fc);
        this.baseVersion = fc.version ?? 0;
        this.baseZones = fc;
      } catch (err) {
        showError($('zones-error'), `zones not loaded: ${err.message}`);
      }
      // Unsaved edits from before a reload or a map switch come back, on the version they started from.
      const draft = loadDraft(map.id, 'zones');
      if (draft && Array.isArray(draft.zones)) {
        this.zones = draft.zones;
        this.drawing = draft.drawing || null;
        this.baseVersion = draft.baseVersion ?? 0;
        this.baseZones = draft.baseZones || null;
        this.dirty = true;
        $('zones-status').textContent = `unsaved edits restored (${plural(this.zones.length)})`;
      }
    }
    this.changed();
    state.emit('zones', state.zones);
  }

  // The zones saved elsewhere changed (an event, or null after a resync): the saved set is read
  // again; the editor follows it unless it holds unsaved edits, which are never dropped silently.
  async remoteChanged(e) {
    const map = state.map;
    if (!map) return;
    const fc = await api.zones(map.id);
    if (state.map?.id !== map.id || (fc.version ?? 0) === (state.zones?.version ?? 0)) return;
    state.zones = fc;
    const who = e?.by ? e.by : 'another operator';
    if (!this.dirty && !this.drawing) {
      this.zones = zonesFromGeoJson(fc);
      this.baseVersion = fc.version ?? 0;
      this.baseZones = fc;
      this.selected = Math.min(this.selected, this.zones.length - 1);
      $('zones-status').textContent = `${who} saved the zones (v${fc.version})`;
    } else {
      $('zones-status').textContent = `${who} saved the zones (v${fc.version}); your unsaved edits are kept — saving shows both`;
    }
    this.changed();
    state.emit('zones', state.zones);
  }

  // An older saved set (a run's, used_versions.js) as unsaved edits on the current version.
  loadVersion(fc, version) {
    history.record(this, `load zones v${version}`, () => {
      this.zones = zonesFromGeoJson(fc);
      this.drawing = null;
      this.selected = -1;
    });
    $('zones-status').textContent = `zones v${version} loaded (now v${state.zones?.version ?? 0}): save zones makes them the newest`;
    this.changed(true);
  }

  // Unsaved edits are kept per map in the browser; none once saved or back to what the server has.
  keepDraft() {
    const m = state.map;
    if (!m) return;
    if (this.dirty || this.drawing) saveDraft(m.id, 'zones', { zones: this.zones, drawing: this.drawing, baseVersion: this.baseVersion, baseZones: this.baseZones });
    else clearDraft(m.id, 'zones');
  }

  // --- editing (the interactions call these: zone_interactions.js) ---
  // A press may start a zone here: on the map, not inside a zone (a click there selects it).
  mayStartAt(x, y) {
    const m = state.map;
    return Boolean(m) && x >= 0 && y >= 0 && x <= m.width_m && y <= m.height_m && !this.zones.some((z) => inside(z.ring, x, y));
  }

  // The corners Draw holds after a click: one corner more (or a new ring), kept on the map.
  setDrawing(ring) {
    const m = state.map;
    if (!m) return;
    const clamp = ([x, y]) => [Math.min(Math.max(x, 0), m.width_m), Math.min(Math.max(y, 0), m.height_m)];
    history.record(this, 'add a zone corner', () => {
      if (!this.drawing) this.selected = -1;
      this.drawing = ring.length ? ring.map(clamp) : null;
    });
    this.changed();
  }

  // Modify took a corner (or an edge): the model before it, for the undo step.
  grabbed() {
    return JSON.parse(JSON.stringify(this.snapshot()));
  }

  // Modify let go: the rings of its features (kept on the map) become the zones'. `dragged`: the
  // pointer moved; a press on an edge without a drag inserted a corner, which is dropped again.
  moved(features, before, dragged) {
    const m = state.map;
    if (!before || !m) return;
    if (!dragged) {
      const z = features.length ? features[0].get('zone') : -1;
      this.restore({ ...before, selected: z >= 0 ? z : before.selected });
      return;
    }
    const clamp = ([x, y]) => [Math.min(Math.max(x, 0), m.width_m), Math.min(Math.max(y, 0), m.height_m)];
    const zs = [];
    for (const f of features) {
      const z = f.get('zone');
      if (!(z >= 0 && z < this.zones.length)) continue;
      this.zones[z].ring = f.getGeometry().getCoordinates()[0].slice(0, -1).map((c) => clamp(c));
      zs.push(z);
    }
    if (!zs.length) return;
    this.selected = zs[0];
    const moved = before.zones[zs[0]]?.ring || [];
    const now = this.zones[zs[0]].ring;
    const i = now.findIndex((c, k) => !moved[k] || c[0] !== moved[k][0] || c[1] !== moved[k][1]);
    const label = now.length > moved.length ? `add a corner to zone ${zs[0] + 1}` : `move corner ${i + 1} of zone ${zs[0] + 1}`;
    history.push(this, label, before, this.snapshot());
    this.changed(true);
  }

  // --- undo (undo_stack.js): the zones, the ring being drawn, the selection ---
  snapshot() {
    return { zones: this.zones, drawing: this.drawing, selected: this.selected };
  }

  restore(s) {
    this.zones = s.zones;
    this.drawing = s.drawing;
    this.selected = Math.min(s.selected, this.zones.length - 1);
    // Unsaved unless the zones are back to what the server has.
    this.dirty = JSON.stringify(this.zones) !== JSON.stringify(zonesFromGeoJson(this.baseZones || { features: [] }));
    this.changed();
  }

  // A click the interactions left to the page (not drawing, not on a corner): inside a zone
  // selects it (outside, Draw has started a zone).
  click(p) {
    if (this.drawing) return;
    const z = this.zones.findIndex((zone) => inside(zone.ring, p.x, p.y));
    if (z < 0) return;
    this.selected = z;
    this.changed();
  }

  finish() {
    if (!this.drawing) return;
    if (this.drawing.length >= 3 && area(this.drawing) > 0) {
      history.record(this, 'close a zone', () => {
        this.zones.push({ ring: this.drawing, name: '' });
        this.selected = this.zones.length - 1;
        this.drawing = null;
      });
      this.changed(true);
    } else {
      showError($('zones-error'), 'a zone needs at least 3 points that enclose an area');
    }
  }

  // Drops the ring being drawn. `ask`: Escape asks first when corners would be lost; leaving the
  // tool does not ask, and either way Ctrl+Z brings the ring back.
  cancel(ask = false) {
    if (!this.drawing) return;
    const n = this.drawing.length;
    if (ask && n > 0 && !window.confirm(`Discard the unfinished zone (${n} corner${n === 1 ? '' : 's'})?`)) return;
    history.record(this, 'discard the unfinished zone', () => {
      this.drawing = null;
    });
    this.changed();
  }

  // Backspace while drawing: the last corner goes (the ring too when it was the only one).
  removeLastVertex() {
    if (!this.drawing) return;
    history.record(this, 'remove the last zone corner', () => {
      this.drawing.pop();
      if (!this.drawing.length) this.drawing = null;
    });
    this.changed();
  }

  remove(z) {
    history.record(this, `delete zone ${z + 1}`, () => {
      this.zones.splice(z, 1);
      this.selected = -1;
    });
    this.changed(true);
  }

  removeSelected() {
    if (this.selected >= 0) this.remove(this.selected);
  }

  async save() {
    const m = state.map;
    if (!m) return;
    const button = $('zones-save');
    button.disabled = true;
    $('zones-status').textContent = 'saving…';
    showError($('zones-error'), null);
    try {
      this.saved(await api.saveZones(m.id, zonesToGeoJson(this.zones), 'local', this.baseVersion));
      $('zones-status').textContent = `saved ${plural(this.zones.length)}`;
    } catch (err) {
      $('zones-status').textContent = '';
      if (err.code === 'version_conflict') this.conflicted(m, err.current);
      else showError($('zones-error'), `zones refused: ${err.message}${err.field ? ` (field: ${err.field})` : ''}`);
    } finally {
      button.disabled = false;
      this.changed();
    }
  }

  // A GeoJSON file: its Polygon features (other geometries, e.g. an export's tracks, are skipped)
  // replace the saved zones; a file that names a CRS (a "crs" member, as our result.geojson
  // exports write) is taken as being in the map's CRS and converted by the server (?crs=map).
  async importFile(input) {
    const m = state.map, file = input.files[0];
    input.value = '';
    if (!m || !file) return;
    if ((this.dirty || this.drawing) && !window.confirm(`Importing replaces the saved zones; your unsaved zone edits (${plural(this.zones.length)}) are dropped. Import?`)) return;
    showError($('zones-error'), null);
    try {
      const fc = JSON.parse(await file.text());
      const all = Array.isArray(fc.features) ? fc.features : [];
      const polygons = all.filter((f) => f && f.geometry && f.geometry.type === 'Polygon');
      const crs = fc.crs ? 'map' : 'local';
      const body = { type: 'FeatureCollection', features: polygons };
      if (fc.crs) body.crs = fc.crs;
      this.saved(await api.saveZones(m.id, body, crs, this.baseVersion));
      this.selected = -1;
      $('zones-status').textContent = `imported ${polygons.length} zone${polygons.length === 1 ? '' : 's'} (${crs === 'map' ? "map's CRS" : 'local metres'})` +
        (all.length > polygons.length ? `, skipped ${all.length - polygons.length} other features` : '');
      state.emit('zones', state.zones);
    } catch (err) {
      // An import replaces the set (its coordinates may be in the map's CRS, so it is not merged
      // here): theirs are loaded and shown, and importing again replaces them knowingly.
      if (err.code === 'version_conflict') {
        if (err.current) this.saved(err.current);
        showError($('zones-error'), `import not applied: ${err.message}; their zones (v${err.current?.version ?? '?'}) are shown now — import again to replace them`);
      }
      else showError($('zones-error'), `import refused: ${err.message}${err.field ? ` (field: ${err.field})` : ''}`);
    }
    this.changed();
  }

  // The set as the server stored it: the editor's zones, the saved ones and the base version.
  saved(fc) {
    state.zones = fc;
    this.zones = zonesFromGeoJson(fc);
    this.baseVersion = fc.version ?? 0;
    this.baseZones = fc;
    this.dirty = false;
    this.changed();
    state.emit('zones', state.zones);
  }

  // A 412 (issue 26): another operator saved this map's zones after these edits started; both
  // are shown and the operator chooses (zone_merge.js). `mine`: the zones this page tried to save.
  conflicted(map, current, mine = this.zones) {
    if (!current) return this.load(map);
    return showZoneConflict(this, map, current, mine);
  }

  changed(edited = false) {
    if (edited) this.dirty = true;
    if (edited) showError($('zones-error'), null);
    this.keepDraft();
    this.renderList();
    this.layers.renderLegends();
    this.render();
  }

  // --- panel ---
  renderList() {
    const list = $('zone-list');
    list.replaceChildren(...this.zones.map((z, i) => el('li', { class: i === this.selected ? 'selected' : '', dataset: { zone: String(i) } },
      el('button', { class: 'name', onclick: () => { this.selected = i; this.changed(); } }, z.name || `zone ${i + 1}`),
      el('span', { class: 'meta' }, `${z.ring.length} points · ${fmt(area(z.ring))} m²`),
      el('button', { class: 'small', title: `delete zone ${i + 1}`, 'aria-label': `delete zone ${i + 1}`, onclick: () => this.remove(i) }, '✕'))));
    $('zones-finish').disabled = !this.drawing;
    $('zones-delete').disabled = this.selected < 0;
    const saved = state.zones?.features?.length ?? 0;
    const n = this.zones.length;
    $('zones-summary').textContent = this.dirty ? `${n} zone${n === 1 ? '' : 's'}, not saved (missions use the ${saved} saved)` : `${saved} saved`;
    const editors = state.presence?.editorsOf('zones') || [];
    $('zones-editors').textContent = editors.length ? `✎ ${editors.join(', ')} editing zones now` : '';
  }

  legend() {
    if (!this.zones.length && !this.drawing) return null;
    const swatch = el('canvas', { width: 28, height: 14, class: 'zone-swatch' });
    zoneSwatch(swatch);
    return el('div', { class: 'zone-legend' }, swatch,
      el('span', {}, `no rover enters (${this.zones.length} zone${this.zones.length === 1 ? '' : 's'}${this.dirty ? ', unsaved' : ''})`));
  }

  // --- the OL features: updated in place from the model (not rebuilt), then the interactions ---
  render() {
    const source = this.olLayer.getSource();
    const closed = (ring) => [[...ring, ring[0]].map(([x, y]) => [x, y])];
    this.zones.forEach((z, i) => {
      let f = this.features[i];
      if (!f) {
        f = new Feature({ geometry: new Polygon(closed(z.ring)) });
        this.features.push(f);
        source.addFeature(f);
      } else {
        f.getGeometry().setCoordinates(closed(z.ring));
      }
      f.setProperties({ zone: i, selected: i === this.selected, dirty: this.dirty });
    });
    for (const f of this.features.splice(this.zones.length)) source.removeFeature(f);
    const editing = state.tool === 'zones';
    const ring = this.ringLayer.getSource();
    ring.clear();
    if (this.drawing && !editing) ring.addFeature(new Feature(new LineString(this.drawing.map(([x, y]) => [x, y]))));
    this.ringLayer.setVisible(this.layer.visible);
    this.ol.sync(editing);
  }
}
