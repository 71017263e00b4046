// The page's shared state and a tiny event bus between the modules.
//
// Events: 'map' (the selected map changed: detail), 'maps' (list reloaded), 'pdms' (the map's PDM
// list changed), 'pdm-selected' (id or ''), 'tool' (map click tool), 'mission' (a mission is now
// shown), 'render' (something on the map changed: redraw), 'zones' (the map's saved keep-out zones).

class AppState extends EventTarget {
  constructor() {
    super();
    this.maps = [];        // GET /api/maps
    this.map = null;       // the selected map (GET /api/maps/{id}, with pdms)
    this.pdms = [];        // the selected map's PDMs
    this.pdmId = '';       // the PDM shown and offered to missions
    this.planners = [];    // GET /api/planners
    this.tool = 'pan';     // 'pan' | 'pdm' | 'rovers' | 'zones' | 'area'
    this.zones = null;     // the selected map's saved keep-out zones (GeoJSON, local frame)
  }

  emit(type, detail) {
    this.dispatchEvent(new CustomEvent(type, { detail }));
  }

  on(type, fn) {
    this.addEventListener(type, (e) => fn(e.detail));
  }

  setTool(tool) {
    if (this.tool === tool) return;
    this.tool = tool;
    this.emit('tool', tool);
  }
}

export const state = new AppState();

// Counters the browser tests read (window.__roverplan).
export const counters = {
  mapDrawn: false,
  firstMapDrawMs: null,
  mapDraws: 0,
  layersLoaded: [],
  wsMessages: 0,
  gridFrames: 0,
  fullGridFrames: 0,
  diffGridFrames: 0,
  posesFrames: 0,
  progressFrames: 0,
  doneFrames: 0,
  liveRenders: 0,
  fps: 0,
  fpsPeak: 0,
  missionId: null,
  missionStatus: null,
  finalMetrics: null,
  replayStep: null,
  replayTime: null,  // s of mission time at the replay cursor (team missions), else null
  view3dReady: false,
  errors: [],
};
window.__roverplan = counters;
