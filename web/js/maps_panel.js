// The Maps tab: DEM upload (file picker or drag-and-drop, several files as multipart parts named
// "file", e.g. .IMG + .LBL), name and cell size, an upload progress bar, the server's error in
// words; the list of maps to select or delete, and the selected map's facts.

import { api, uploadDem } from './api.js';
import { state } from './state.js';
import { editName } from './name_edit.js';
import { $, el, fmt, report, showError } from './util.js';

const LAST_MAP_KEY = 'roverplan.map';

// A map's scale warnings (GET /api/maps/{id} "warnings": coarse cells, heights that look like
// radii or counts), one line each with the import option that fixes it.
function scaleWarnings(m) {
  return (m?.warnings || []).map((w) => el('div', { class: 'scale-warning', dataset: { code: w.code } },
    '⚠ ', w.message, w.field ? el('span', { class: 'muted' }, ` (${w.field})`) : ''));
}

// A cell's size: "0.5 m", or "0.5 × 1 m" when its sides differ (a projected map with non-square
// pixels, an equirectangular one away from its standard parallel).
export function cellSizeText(map) {
  const w = Number(map.cell_size_m.toPrecision(4));
  const h = Number.isFinite(map.cell_height_m) ? Number(map.cell_height_m.toPrecision(4)) : w;
  return h === w ? `${w} m` : `${w} × ${h} m`;
}

// The title over the map: its name, size and cell size.
export function showMapTitle(map) {
  $('map-title').textContent = map ? `${map.name} — ${map.cols}×${map.rows} × ${cellSizeText(map)}` : 'no map';
  $('map-title').title = map ? `map ${map.id}` : 'The selected map';
}

export class MapsPanel {
  constructor({ selectMap }) {
    this.selectMap = selectMap;
    this.files = [];
    const input = $('dem-files');
    const zone = $('drop-zone');
    input.addEventListener('change', () => this.choose([...input.files]));
    zone.addEventListener('keydown', (e) => {
      if (e.key === 'Enter' || e.key === ' ') {
        e.preventDefault();
        input.click();
      }
    });
    zone.addEventListener('dragover', (e) => {
      e.preventDefault();
      zone.classList.add('over');
    });
    zone.addEventListener('dragleave', () => zone.classList.remove('over'));
    zone.addEventListener('drop', (e) => {
      e.preventDefault();
      zone.classList.remove('over');
      this.choose([...e.dataTransfer.files]);
    });
    // A file dropped anywhere else must not navigate the page away.
    window.addEventListener('dragover', (e) => e.preventDefault());
    window.addEventListener('drop', (e) => e.preventDefault());
    $('dem-upload').addEventListener('click', () => this.upload());
    $('dem-crop-unit').addEventListener('change', () => this.cropHelp());
    this.cropHelp();
    state.on('map', () => this.renderList());
  }

  choose(files) {
    this.files = files;
    $('dem-chosen').textContent = files.map((f) => `${f.name} (${fmt(f.size / 1024, 3)} KiB)`).join(', ');
    $('dem-upload').disabled = files.length === 0;
    showError($('dem-error'), null);
  }

  // The crop window's units: the file's CRS (as gdal_translate -projwin, lower-left corner) or its
  // pixels (as -srcwin, from the upper-left corner).
  cropHelp() {
    const px = $('dem-crop-unit').value === 'crop_px';
    $('dem-crop').placeholder = px ? 'COL,ROW,W,H (whole file)' : 'X0,Y0,W,H (whole file)';
    $('dem-crop-help').textContent = px
      ? 'Pixels of the file: first column and row from its upper-left corner, width and height.'
      : "The file's CRS units: lower-left corner X0, Y0, then width and height.";
  }

  // The DEM import options as the server reads them (maps/dem_import_options), checked here
  // for shape first. Returns [fields, error] with error = [field, message] or null.
  importFields() {
    const cell = $('dem-cell').value.trim();
    const crop = $('dem-crop').value.trim().replace(/\s+/g, '');
    const cropKey = $('dem-crop-unit').value;
    const scale = $('dem-vscale').value.trim();
    const offset = $('dem-voffset').value.trim();
    const fields = { name: $('dem-name').value.trim(), cell, vertical_scale: scale === '1' ? '' : scale,
      vertical_offset: offset === '0' ? '' : offset, body: $('dem-body').value === 'auto' ? '' : $('dem-body').value };
    if (cell !== '' && !(Number(cell) >= 0)) return [fields, ['cell', 'cell size must be a positive number of metres']];
    if (crop !== '') {
      const v = crop.split(',').map(Number);
      if (v.length !== 4 || v.some((x) => !Number.isFinite(x)) || !(v[2] > 0 && v[3] > 0))
        return [fields, [cropKey, 'crop must be four numbers X0,Y0,W,H with a positive width and height']];
      fields[cropKey] = crop;
    }
    if (scale !== '' && !(Number.isFinite(Number(scale)) && Number(scale) !== 0))
      return [fields, ['vertical_scale', 'vertical scale must be a non-zero number']];
    if (offset !== '' && !(Number.isFinite(Number(offset)) && Math.abs(Number(offset)) <= 1e8))
      return [fields, ['vertical_offset', 'vertical offset must be a number of metres within ±1e8']];
    return [fields, null];
  }

  fieldInput(field) {
    return { cell: $('dem-cell'), name: $('dem-name'), crop: $('dem-crop'), crop_px: $('dem-crop'), vertical_scale: $('dem-vscale'), vertical_offset: $('dem-voffset'), body: $('dem-body') }[field];
  }

  async upload() {
    if (this.files.length === 0) return;
    const bar = $('dem-progress'), text = $('dem-progress-text'), button = $('dem-upload');
    for (const n of ['dem-cell', 'dem-name', 'dem-crop', 'dem-vscale', 'dem-voffset', 'dem-body']) $(n).classList.remove('invalid');
    $('dem-warnings').replaceChildren();
    const [fields, bad] = this.importFields();
    if (bad) {
      showError($('dem-error'), `${bad[1]} (field: ${bad[0]})`);
      this.fieldInput(bad[0]).classList.add('invalid');
      if (bad[0] !== 'cell') $('dem-options').open = true;
      return;
    }
    showError($('dem-error'), null);
    button.disabled = true;
    bar.hidden = false;
    bar.value = 0;
    text.textContent = 'uploading…';
    try {
      const map = await uploadDem(this.files, fields, (f, loaded, phase) => {
        if (phase === 'processing') {
          bar.removeAttribute('value');  // indeterminate while the server imports
          text.textContent = 'importing…';
        } else if (Number.isFinite(f)) {
          bar.value = f;
          text.textContent = `${Math.round(f * 100)} %`;
        }
      });
      text.textContent = `added “${map.name}”`;
      // What the cells and heights say about the map (issue 27: honest scale), shown where the
      // operator looks after an upload, and kept in the map's details and the mission form.
      $('dem-warnings').replaceChildren(...scaleWarnings(map));
      this.choose([]);
      $('dem-files').value = '';
      $('dem-name').value = '';
      await this.reload();
      await this.selectMap(map.id);
    } catch (err) {
      text.textContent = '';
      showError($('dem-error'), `upload refused: ${err.message}${err.field ? ` (field: ${err.field})` : ''}${err.status ? ` — HTTP ${err.status}` : ''}`);
      const field = this.fieldInput(err.field);
      if (field) field.classList.add('invalid');
      if (field && !['cell', 'name'].includes(err.field)) $('dem-options').open = true;
      button.disabled = this.files.length === 0;
    } finally {
      bar.hidden = true;
      bar.value = 0;
    }
  }

  async reload() {
    state.maps = await api.maps();
    // The shown map renamed (here or by another operator): its name, version and title follow.
    const shown = state.map && state.maps.find((m) => m.id === state.map.id);
    if (shown && (shown.name !== state.map.name || shown.version !== state.map.version)) {
      Object.assign(state.map, { name: shown.name, version: shown.version });
      showMapTitle(state.map);
    }
    this.renderList();
    state.emit('maps', state.maps);
    return state.maps;
  }

  // The map to show first: the last one used in this browser, else the first.
  initialMapId() {
    let last = '';
    try { last = localStorage.getItem(LAST_MAP_KEY) || ''; } catch { /* no storage */ }
    if (state.maps.some((m) => m.id === last)) return last;
    return state.maps.length ? state.maps[0].id : null;
  }

  remember(id) {
    try { localStorage.setItem(LAST_MAP_KEY, id); } catch { /* no storage */ }
  }

  renderList() {
    // A rename being typed (or its conflict) is not swept away by a list refresh: it comes after.
    if (this.renaming) {
      this.listStale = true;
      this.renderInfo();
      return;
    }
    const list = $('map-list');
    list.replaceChildren(...state.maps.map((m) => el('li', { class: state.map?.id === m.id ? 'selected' : '', dataset: { map: m.id } },
      el('button', { class: 'name', title: `${m.name} — ${m.id}`, onclick: () => this.selectMap(m.id) }, m.name),
      el('span', { class: 'meta' }, `${m.cols}×${m.rows} · ${fmt(m.cell_size_m)} m`),
      el('button', { class: 'small rename', title: `rename ${m.name}`, 'aria-label': `rename map ${m.name}`, onclick: (e) => this.rename(m, e.currentTarget.closest('li')) }, '✎'),
      el('button', { class: 'small', title: `delete ${m.name}`, 'aria-label': `delete map ${m.name}`, onclick: () => this.remove(m) }, '✕'))));
    this.renderInfo();
  }

  renderInfo() {
    const m = state.map;
    const node = $('map-info');
    $('m-scale-note').replaceChildren(...scaleWarnings(m));
    if (!m) {
      node.replaceChildren('No map selected.');
      return;
    }
    const c = m.classes || {};
    const line = (k, v) => el('div', {}, `${k}: `, el('b', {}, v));
    node.replaceChildren(
      line('size', `${m.cols} × ${m.rows} cells · ${fmt(m.width_m)} × ${fmt(m.height_m)} m`),
      line('cell', `${fmt(m.cell_size_m)} × ${fmt(m.cell_height_m ?? m.cell_size_m)} m`),
      line('elevation', `${fmt(m.elevation?.min)} … ${fmt(m.elevation?.max)} m`),
      line('classes', `traversable ${fmt(c.traversable_pct, 2)} %, high risk ${fmt(c.high_risk_pct, 2)} %, impassable ${fmt(c.impassable_pct, 2)} %, nodata ${fmt(c.nodata_pct, 2)} %`),
      line('CRS', m.crs || 'none'),
      line('body', `${m.body || 'unknown'}${m.body_source === 'declared' ? ' (declared at upload)' : ''}`),
      ...(m.crop || m.crop_px || m.vertical_offset || (m.vertical_scale !== undefined && m.vertical_scale !== 1)
        ? [line('imported', [m.crop ? `crop ${m.crop.map((v) => fmt(v)).join(', ')}` : '', m.crop_px ? `pixels ${m.crop_px.join(', ')}` : '',
          m.vertical_scale !== undefined && m.vertical_scale !== 1 ? `heights × ${fmt(m.vertical_scale)}` : '',
          m.vertical_offset ? `heights + ${fmt(m.vertical_offset)} m` : ''].filter(Boolean).join(' · '))] : []),
      line('source', `${(m.source_files || []).join(', ')} (${m.driver || '?'})`),
      ...scaleWarnings(m));
  }

  // The map's name becomes an input (name_edit.js); saved with the version read.
  rename(m, row) {
    this.renaming = true;
    editName({
      row, object: 'map', what: 'map', id: m.id, name: m.name, version: m.version,
      save: (name, version) => api.renameMap(m.id, name, version),
      done: (saved) => {
        this.renaming = false;
        if (saved) {
          Object.assign(m, { name: saved.name, version: saved.version });
          if (state.map?.id === m.id) {
            Object.assign(state.map, { name: saved.name, version: saved.version });
            showMapTitle(state.map);
          }
        }
        this.listStale = false;
        this.reload().catch(report);
      },
    });
  }

  async remove(m) {
    if (!window.confirm(`Delete the map “${m.name}” and its PDMs? Missions keep their results.`)) return;
    try {
      // Show another map first, so nothing still loads from the one being deleted.
      if (state.map?.id === m.id) {
        const other = state.maps.find((x) => x.id !== m.id);
        await this.selectMap(other ? other.id : null);
      }
      await api.deleteMap(m.id);
      await this.reload();
    } catch (err) {
      report(err);
    }
  }
}
