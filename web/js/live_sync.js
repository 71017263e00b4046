// Keeps every list, layer and form of the page current from the event stream (event_feed.js):
// maps list, the map's PDM list (and so the mission form's PDM choice), its zones layer and "N
// saved" count, the Runs tab, the studies list and who else is here (presence.js). Events of one
// kind arriving together cause one reload (coalesced over a frame), so a burst of 50 changes is
// one request, not 50.

import { clearDrafts } from './drafts.js';
import { noteChange } from './name_edit.js';
import { state } from './state.js';
import { report } from './util.js';

export class LiveSync {
  constructor({ feed, presence, mapsPanel, pdmEditor, zoneEditor, runs, studies, chooseMap }) {
    Object.assign(this, { feed, presence, mapsPanel, pdmEditor, zoneEditor, runs, studies, chooseMap });
    this.pending = new Map();  // kind -> timer
    feed.h.onEvents = (events) => events.forEach((e) => this.apply(e));
    feed.h.onReady = (msg) => presence.ready(msg);
    feed.h.onResync = () => this.reloadAll();
    feed.h.onStatus = (s) => document.body.classList.toggle('events-offline', s !== 'live');
    state.on('map', (map) => {
      feed.open(map?.id || '');
      presence.say();
    });
  }

  later(kind, fn) {
    if (this.pending.has(kind)) return;
    this.pending.set(kind, setTimeout(() => {
      this.pending.delete(kind);
      Promise.resolve(fn()).catch(report);
    }, 16));
  }

  apply(e) {
    const here = state.map?.id;
    noteChange(e);  // who renamed what, for a rename's conflict (name_edit.js)
    switch (e.object) {
      case 'presence': this.presence.event(e); break;
      case 'map':
        // The list, and the shown map's title when it was renamed (MapsPanel.reload).
        this.later('maps', () => this.mapsPanel.reload());
        if (e.kind === 'deleted') clearDrafts(e.id);
        if (e.kind === 'deleted' && e.id === here) {
          report(`the map you were viewing was deleted${e.by ? ` by ${e.by}` : ''}`);
          this.later('map-gone', () => this.mapsPanel.reload().then(() => this.chooseMap(this.mapsPanel.initialMapId())));
        }
        break;
      case 'pdm':
        if (e.map === here) this.later('pdms', () => this.pdmEditor.remoteChanged(e));
        break;
      case 'zone': case 'zones':
        if (e.map === here) this.later('zones', () => this.zoneEditor.remoteChanged(e));
        break;
      case 'mission': this.later('missions', () => this.runs.reload()); break;
      // The studies list is read when its tab is open (and whenever it is opened).
      case 'study':
        if (!document.getElementById('panel-studies').hidden) this.later('studies', () => this.studies.reload());
        break;
      default: break;
    }
  }

  reloadAll() {
    this.later('maps', () => this.mapsPanel.reload());
    if (state.map) {
      this.later('pdms', () => this.pdmEditor.remoteChanged(null));
      this.later('zones', () => this.zoneEditor.remoteChanged(null));
    }
    this.later('missions', () => this.runs.reload());
  }
}
