// The operator's page: wires the map view, layers, panels, the live mission view and the 3D view.

import { api, setToken, getToken } from './api.js';
import { LayerStack } from './layer_stack.js';
import { MapView } from './map_view.js';
import { MapsPanel, showMapTitle } from './maps_panel.js';
import { MissionForm } from './mission_form.js';
import { MissionView } from './mission_view.js';
import { PdmEditor } from './pdm_editor.js';
import { RunsPanel } from './runs.js';
import { StudiesPanel } from './studies.js';
import { counters, state } from './state.js';
import { $, report, setErrorReporter } from './util.js';
import { View3D } from './view3d.js';
import { ZoneEditor } from './zones.js';
import { AreaTool } from './area_tool.js';
import { RouteProfile } from './route_profile.js';
import { bindUndoControls, history as undoHistory } from './undo_stack.js';
import { ConflictView } from './conflict_view.js';
import { EventFeed } from './event_feed.js';
import { HistoryView } from './history_view.js';
import { LiveSync } from './live_sync.js';
import { Presence } from './presence.js';
import { FormDraft } from './form_draft.js';
import { reopenUsed } from './used_versions.js';

// --- status line: a message part and a live-mission part ---
const statusParts = { msg: '', live: '' };
function statusLine(text, part = 'msg') {
  statusParts[part] = text;
  $('status-line').textContent = [statusParts.live, statusParts.msg].filter(Boolean).join('  ·  ');
}
let msgTimer = null;
setErrorReporter((msg) => {
  statusLine(`⚠ ${msg}`);
  clearTimeout(msgTimer);
  msgTimer = setTimeout(() => statusLine(''), 12000);
});
window.addEventListener('error', (e) => counters.errors.push(String(e.message)));
window.addEventListener('unhandledrejection', (e) => {
  counters.errors.push(String(e.reason && e.reason.message ? e.reason.message : e.reason));
  report(e.reason && e.reason.message ? e.reason.message : String(e.reason));
  e.preventDefault();
});

// --- the modules ---
const view = new MapView($('map-canvas'));
view.padLeft = 256;   // the floating layers panel
view.padRight = 256;  // the floating legend panel
const layers = new LayerStack(view);
const missionView = new MissionView({ view, layers, statusLine, selectMap, onFinished: () => runs.reload(), onShown: (m) => setAddress(m ? { mission: m.id } : state.map ? { map: state.map.id } : {}) });
const conflicts = new ConflictView({ view });
const feed = new EventFeed({});
const presence = new Presence(feed);
state.presence = presence;
const pdmEditor = new PdmEditor({ view, layers, conflicts });
const missionForm = new MissionForm({ view, onLaunched: (m) => launched(m) });
const areaTool = new AreaTool({ view, missionView, form: missionForm });
const mapsPanel = new MapsPanel({ selectMap: chooseMap });
const zoneEditor = new ZoneEditor({ view, layers, conflicts });
const historyView = new HistoryView({ view, zoneEditor, pdmEditor });
// The mission form's "respect keep-out zones": on by default when the map has saved zones.
// A change saved by another operator keeps the operator's choice once the map has zones.
let keepOutShown = { map: '', n: 0 };
state.on('zones', (fc) => {
  const n = fc?.features?.length || 0;
  if (keepOutShown.map !== state.map?.id || keepOutShown.n === 0 || n === 0) $('m-keep-out').checked = n > 0;
  keepOutShown = { map: state.map?.id || '', n };
  $('m-keep-out').disabled = n === 0;
  $('m-keep-out-count').textContent = n ? `${n} saved on this map` : 'none on this map';
});
const runs = new RunsPanel({
  missionView,
  onDuplicate: async (file) => {
    await missionForm.load(file, chooseMap);
    await zoneEditor.loading;
    const reopened = await reopenUsed(file, { pdmEditor, zoneEditor });
    showTab('mission');
    if (reopened) $('m-file-status').textContent = reopened;
  },
});
const studies = new StudiesPanel({
  onMission: async (mission) => {
    showTab('runs');
    await launched(mission);
  },
});
const view3d = new View3D({ container: $('view3d'), message: $('view3d-message'), missionView });
const routeProfile = new RouteProfile({ view, layers, missionView });
const liveSync = new LiveSync({ feed, presence, mapsPanel, pdmEditor, zoneEditor, runs, studies, chooseMap });
const formDraft = new FormDraft(missionForm);
state.on('result', () => routeProfile.update());
bindUndoControls();
routeProfile.onHover = (p) => view3d.setMarker(p);
window.__roverplanApp = { view, layers, missionView, pdmEditor, missionForm, areaTool, mapsPanel, zoneEditor, runs, studies, view3d, state, undoHistory, routeProfile, feed, presence, conflicts, historyView, liveSync, formDraft };


async function selectMap(id) {
  if (!id) {
    state.map = null;
    state.pdms = [];
    state.pdmId = '';
    showMapTitle(null);
    await layers.setMap(null);
    state.emit('map', null);
    view.invalidate(true);
    return;
  }
  const map = await api.map(id);
  state.map = map;
  state.pdms = map.pdms || [];
  // The map's body holds its first PDMs only; pdms_total says when the listing has more.
  if ((map.pdms_total || 0) > state.pdms.length) state.pdms = await api.pdms(id);
  state.pdmId = '';
  showMapTitle(map);
  mapsPanel.remember(id);
  view.setExtent(map.width_m, map.height_m, true, map.tiles);  // before the layers: their tiles take its projection
  const loading = layers.setMap(map);
  state.emit('map', map);
  state.emit('pdms', state.pdms);
  await loading;
}

// A map the operator chose: a mission shown on another map is closed, not drawn over the new one.
async function chooseMap(id) {
  if (missionView.mission && missionView.mission.map !== id) missionView.clear();
  if (!missionView.mission) setAddress(id ? { map: id } : {});
  await selectMap(id);
}

// --- the address: #mission=ID (or #map=ID) so a reload or a shared link opens the same view ---
function readAddress() {
  const q = new URLSearchParams(location.hash.replace(/^#/, ''));
  return { mission: q.get('mission') || '', map: q.get('map') || '' };
}
function setAddress(parts) {
  const q = new URLSearchParams();
  for (const [k, v] of Object.entries(parts)) if (v) q.set(k, v);
  const hash = q.toString() ? `#${q}` : '';
  if (hash !== location.hash) history.replaceState(null, '', `${location.pathname}${location.search}${hash}`);
}
// Opens what the address names. Returns '' when it did, else why not (said once a map is shown, so
// the map's own status message does not replace it).
async function openAddress() {
  const { mission, map } = readAddress();
  if (mission) {
    try {
      await missionView.show(mission);
      return '';
    } catch (err) {
      return err.status === 404 ? `mission ${mission} (from the address) does not exist` : String(err.message || err);
    }
  }
  if (map && state.maps.some((m) => m.id === map)) {
    await chooseMap(map);
    return '';
  }
  return map ? `map ${map} (from the address) does not exist` : 'nothing';
}
window.addEventListener('hashchange', () => {
  const { mission, map } = readAddress();
  if ((mission && mission !== missionView.mission?.id) || (!mission && map && map !== state.map?.id))
    openAddress().then((why) => why && why !== 'nothing' && report(why)).catch(report);
});

async function launched(mission) {
  await missionView.show(mission);
  runs.reload();
}

let addressNotice = '';  // why the address could not be opened, once the first map is drawn
// First map drawn (the tests print it): the first frame after the elevation's first tile arrived.
view.onRender(() => {
  counters.mapDraws++;
  if (!counters.mapDrawn && layers.get('elevation').tileShown) {
    counters.mapDrawn = true;
    counters.firstMapDrawMs = Math.round(performance.now());
    statusLine(`map drawn ${counters.firstMapDrawMs} ms after page start`);
    if (addressNotice) report(addressNotice);
    addressNotice = '';
  }
});

// --- cursor readout ---
view.onHover((p) => {
  if (!p) return;
  const cell = missionView.cellReadout(p.x, p.y);
  $('readout').textContent = layers.readout(p.x, p.y) + (cell ? `   ${cell}` : '');
});

// --- tools follow the tabs ---
const TOOL_HELP = {
  pan: 'drag to pan · wheel or +/− to zoom',
  pdm: 'PDM: click to add a Gaussian · drag handles to shape it · drag elsewhere to pan',
  'pdm-paint': 'PDM brush: drag to paint Gaussians along the stroke · Shift/Alt + drag erases · the map does not pan · Ctrl+Z undoes a stroke',
  rovers: 'Mission: click to place the next rover, drag from it to set its heading',
  area: 'Mission area: drag a rectangle on the map · Escape cancels',
  zones: 'Zones: click to add corners, click the first (or Enter) to close · Backspace: last corner · drag a corner · Delete removes the selected · Ctrl+Z undoes',
};
const toolHelp = () => {
  $('tool-label').textContent = TOOL_HELP[state.tool === 'pdm' && pdmEditor.mode === 'paint' ? 'pdm-paint' : state.tool] || '';
};
state.on('tool', (tool) => {
  view.setTool(tool);
  toolHelp();
  view.invalidate();
});
state.on('pdm-mode', toolHelp);
state.on('pdm-selected', (id) => layers.setPdm(id));

const TABS = ['maps', 'pdm', 'mission', 'runs', 'studies'];
// What this page edits, told to the others on the map (presence.js): the zones while drawing
// them, the PDM loaded (or a new one) in the PDM tab, the mission in the Mission tab.
function sayEditing() {
  const tab = TABS.find((t) => !$(`panel-${t}`).hidden);
  presence.setEditing(state.tool === 'zones' ? 'zones'
    : tab === 'pdm' ? (pdmEditor.base ? `pdm:${pdmEditor.base.id}` : 'pdm:new')
      : tab === 'mission' ? 'mission' : '');
}
state.on('tool', () => sayEditing());
state.on('pdm-selected', () => sayEditing());

function showTab(name) {
  for (const t of TABS) {
    const active = t === name;
    $(`tab-${t}`).classList.toggle('active', active);
    $(`tab-${t}`).setAttribute('aria-selected', String(active));
    $(`tab-${t}`).tabIndex = active ? 0 : -1;
    $(`panel-${t}`).hidden = !active;
  }
  missionForm.showStarts = name === 'mission';
  if (name === 'pdm') state.setTool('pdm');
  else if (name === 'mission') missionForm.activate();
  else state.setTool('pan');
  if (name === 'mission' && !missionForm.placing) state.setTool('pan');
  if (name === 'runs') runs.reload();
  sayEditing();
  // The study view covers the map and the dock while the Studies tab is open.
  $('studies-view').hidden = name !== 'studies';
  if (name === 'studies') studies.activate(state.planners).catch(report);
  view.invalidate();
}
for (const t of TABS) {
  $(`tab-${t}`).addEventListener('click', () => showTab(t));
  $(`tab-${t}`).addEventListener('keydown', (e) => {
    const i = TABS.indexOf(t);
    const j = e.key === 'ArrowRight' ? (i + 1) % TABS.length : e.key === 'ArrowLeft' ? (i + TABS.length - 1) % TABS.length : -1;
    if (j >= 0) {
      e.preventDefault();
      showTab(TABS[j]);
      $(`tab-${TABS[j]}`).focus();
    }
  });
}

// --- the layer list folds (a click on its title) to show more of the map ---
function foldLayers(folded) {
  $('layers-toggle').setAttribute('aria-expanded', String(!folded));
  $('layer-list').hidden = folded;
}
$('layers-toggle').addEventListener('click', () => foldLayers($('layers-toggle').getAttribute('aria-expanded') === 'true'));
foldLayers(false);

// --- map / 3D switch, zoom buttons, PNG export ---
function showView(which) {
  const is3d = which === '3d';
  $('view-map').classList.toggle('active', !is3d);
  $('view-3d').classList.toggle('active', is3d);
  $('view-map').setAttribute('aria-selected', String(!is3d));
  $('view-3d').setAttribute('aria-selected', String(is3d));
  $('map-view').hidden = is3d;
  $('view3d').hidden = !is3d;
  if (is3d) view3d.show();
  else {
    view3d.hide();
    view.resize();
    view.invalidate(true);
  }
}
$('view-map').addEventListener('click', () => showView('map'));
$('view-3d').addEventListener('click', () => showView('3d'));
// The toolbar's zoom works on the view shown: the 2D map or the 3D terrain (issue 27: in 3D it
// did nothing).
const in3d = () => !$('view3d').hidden;
$('zoom-in').addEventListener('click', () => (in3d() ? view3d.zoom(1.25) : view.zoomStep(1)));
$('zoom-out').addEventListener('click', () => (in3d() ? view3d.zoom(0.8) : view.zoomStep(-1)));
$('zoom-fit').addEventListener('click', () => (in3d() ? view3d.fit() : view.fit()));
$('export-png').addEventListener('click', () => {
  const url = $('view3d').hidden ? view.snapshot().toDataURL('image/png') : view3d.toDataURL();
  if (!url) return;
  const a = document.createElement('a');
  a.href = url;
  a.download = `roverplan-${state.map ? state.map.id : 'map'}${$('view3d').hidden ? '' : '-3d'}.png`;
  document.body.append(a);
  a.click();
  a.remove();
});

// --- token ---
const tokenInput = $('token');
tokenInput.value = getToken();
tokenInput.addEventListener('change', () => {
  setToken(tokenInput.value.trim());
  start();
});

// --- start ---
async function start() {
  try {
    state.planners = await api.planners();
    missionForm.setPlanners(state.planners);
    await mapsPanel.reload();
    const why = await openAddress();
    if (why) {
      await chooseMap(mapsPanel.initialMapId());
      if (why !== 'nothing') {
        if (counters.mapDrawn) report(why);
        else addressNotice = why;  // said after "map drawn …", which would replace it
      }
    }
    runs.reload();
  } catch (err) {
    if (err.status === 401) report('the server wants a token: enter it at the top right');
    else report(err);
  }
}
showTab('maps');
start();
