// Zones drawn and edited with OpenLayers' interactions (issue 24) on the zone layer of zones.js:
// Draw (a polygon, click by click; a click on its first corner closes it), Modify (drag a corner;
// drag an edge to add one) and Snap (a click or a drag within HIT_PX of a saved zone's corner lands
// on that corner). The editor (zones.js) keeps the model — its zones and the ring being drawn, with
// undo and drafts: every click Draw takes is passed on as the ring's corners, every corner Modify
// moved as the zone's ring, and every change of the model made elsewhere (undo, Backspace, a
// restored draft) is put back into Draw's sketch (sync).
// Interactions see an event last-added first: Snap moves the pointer's coordinate, then Modify
// takes a press on a corner or an edge (and keeps it from the map's DragPan, added before), else
// Draw has it: a click adds a corner, a drag pans the map (Draw lets the press through).

import Draw from 'ol/interaction/Draw.js';
import Modify from 'ol/interaction/Modify.js';
import Snap from 'ol/interaction/Snap.js';
import { primaryAction } from 'ol/events/condition.js';
import Polygon from 'ol/geom/Polygon.js';
import { Circle as CircleStyle, Fill, Stroke, Style } from 'ol/style.js';
import { sketchStyle } from './zone_style.js';

export const HIT_PX = 9;  // how near (CSS px) a press must be to a corner to take it

// Draw, telling after each release what its sketch holds now.
class RingDraw extends Draw {
  handleUpEvent(e) {
    const pass = super.handleUpEvent(e);
    this.afterUp?.();
    return pass;
  }
}

// Modify, telling when it took a press (the model before it is kept for the undo step).
class GrabModify extends Modify {
  handleDownEvent(e) {
    this.grabbed = super.handleDownEvent(e);
    this.downPixel = e.pixel;
    if (this.grabbed) this.onGrab?.();
    return this.grabbed;
  }

  handleUpEvent(e) {
    const pass = super.handleUpEvent(e);
    this.grabbed = false;
    return pass;
  }
}

const near = (a, b) => Math.abs(a[0] - b[0]) <= 1e-9 * (1 + Math.abs(a[0])) && Math.abs(a[1] - b[1]) <= 1e-9 * (1 + Math.abs(a[1]));
const sameRing = (a, b) => (a?.length || 0) === (b?.length || 0) && (a || []).every((c, i) => near(c, b[i]));

export class ZoneInteractions {
  // editor: {drawing, mayStartAt(x, y), setDrawing(ring), finish(), grabbed(), moved(feature, before)}
  constructor(editor, view, source) {
    this.editor = editor;
    this.view = view;
    this.sketch = null;    // Draw's sketch coordinates while a ring is drawn
    this.syncing = false;  // the sketch is being rebuilt from the model: its events are ours
    this.before = null;    // the model when Modify took a press
    this.draw = new RingDraw({
      type: 'Polygon', style: sketchStyle, snapTolerance: HIT_PX + 3,
      geometryFunction: (coords, geometry) => this.sketchGeometry(coords, geometry),
      condition: (e) => primaryAction(e) && (Boolean(editor.drawing) || editor.mayStartAt(...e.coordinate)),
    });
    this.draw.afterUp = () => this.fromSketch();
    this.draw.on('drawabort', () => { this.sketch = null; });
    this.draw.on('drawend', () => {
      this.sketch = null;
      if (!this.syncing) editor.finish();  // a click on the first (or last) corner
    });
    this.modify = new GrabModify({
      source, pixelTolerance: HIT_PX,
      style: new Style({ image: new CircleStyle({ radius: 6, fill: new Fill({ color: 'rgba(255, 255, 255, 0.35)' }), stroke: new Stroke({ color: '#ffffff', width: 1.5 }) }) }),
    });
    this.modify.onGrab = () => { this.before = editor.grabbed(); };
    this.modify.on('modifyend', (e) => {
      const [dx, dy] = [e.mapBrowserEvent.pixel[0] - this.modify.downPixel[0], e.mapBrowserEvent.pixel[1] - this.modify.downPixel[1]];
      // A press on an edge inserts a corner there; without a drag that is no edit.
      editor.moved(e.features.getArray(), this.before, Math.hypot(dx, dy) > 3);
      this.before = null;
    });
    this.snap = new Snap({ source, edge: false, vertex: true, pixelTolerance: HIT_PX });
    for (const i of [this.draw, this.modify, this.snap]) {
      i.setActive(false);
      view.olMap.addInteraction(i);
    }
  }

  // Draw's polygon from its sketch coordinates ([[corner, ..., the point under the pointer]]),
  // kept to read the corners back (committed).
  sketchGeometry(coords, geometry) {
    this.sketch = coords;
    const rings = coords[0].length ? [coords[0].concat([coords[0][0]])] : [];
    if (!geometry) return new Polygon(rings);
    geometry.setCoordinates(rings);
    return geometry;
  }

  // The corners Draw's sketch holds (local metres): without the point under the pointer; null
  // when nothing is drawn.
  committed() {
    if (!this.sketch) return null;
    return this.sketch[0].slice(0, -1).map(([x, y]) => [x, y]);
  }

  fromSketch() {
    if (this.syncing) return;
    const have = this.committed();
    if (have && !sameRing(have, this.editor.drawing)) this.editor.setDrawing(have);
    this.sync();
  }

  // The interactions follow the tool and the model: Draw and Snap while the zones tool is on,
  // Modify when no ring is being drawn; Draw's sketch holds the model's ring.
  sync(active) {
    if (active !== undefined) this.active = active;
    const on = Boolean(this.active);
    const want = this.editor.drawing;
    this.draw.setActive(on);
    this.modify.setActive(on && !want);
    this.snap.setActive(on);
    if (!on || sameRing(this.committed(), want)) return;
    this.syncing = true;
    try {
      this.draw.abortDrawing();
      if (want && want.length) this.draw.appendCoordinates(want.map(([x, y]) => [x, y]));
    } finally {
      this.syncing = false;
    }
  }
}
