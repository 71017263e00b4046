// The PDM editor's Gaussians on the map as OpenLayers features (issue 24): per component its 1σ
// ellipse, its axes (dashed) and four handles — the centre (numbered), σx (blue square), σy (green
// square) and the rotation (orange disc, ROT_OFFSET px beyond σx). OL's Modify takes a press on
// a handle and drags it; the editor (pdm_editor.js) turns the pointer's path into the component's
// new centre, σ or rotation, and every handle is placed again from the components (a σ handle
// stays on its axis). The features are updated in place when the components, the selection or
// the view (the rotation handle's pixel offset) changed, on the frames the map view draws.

import Feature from 'ol/Feature.js';
import LineString from 'ol/geom/LineString.js';
import Point from 'ol/geom/Point.js';
import Polygon from 'ol/geom/Polygon.js';
import Modify from 'ol/interaction/Modify.js';
import { Circle as CircleStyle, Fill, RegularShape, Stroke, Style, Text } from 'ol/style.js';

export const HANDLE = 7;       // px, half size
export const ROT_OFFSET = 26;  // px beyond the σx handle

// Modify telling the editor of the handle it took (a press it takes is no pan of the map: OL
// gives it to the interactions added later first, and Modify keeps a press it takes), of the
// pointer's path while dragging it and of the release.
class GrabModify extends Modify {
  handleDownEvent(e) {
    this.grabbed = super.handleDownEvent(e);
    if (this.grabbed) this.hooks.grab(this.mapView.eventPoint(e.originalEvent));
    return this.grabbed;
  }

  handleDragEvent(e) {
    super.handleDragEvent(e);
    if (this.grabbed) this.hooks.drag(this.mapView.eventPoint(e.originalEvent));
  }

  handleUpEvent(e) {
    const pass = super.handleUpEvent(e);
    if (this.grabbed) this.hooks.release();
    this.grabbed = false;
    return pass;
  }
}

const square = (colour) => new Style({ image: new RegularShape({ points: 4, radius: HANDLE * Math.SQRT2 / 1.4, angle: Math.PI / 4, fill: new Fill({ color: colour }), stroke: new Stroke({ color: '#000', width: 1 }) }), zIndex: 2 });
const STYLES = {
  sx: square('#4fb3ff'),
  sy: square('#6bd58b'),
  rot: new Style({ image: new CircleStyle({ radius: HANDLE - 1, fill: new Fill({ color: '#ffb347' }), stroke: new Stroke({ color: '#000', width: 1 }) }), zIndex: 2 }),
  axes: new Style({ stroke: new Stroke({ color: 'rgba(255,255,255,0.8)', width: 1.2, lineDash: [3, 3] }) }),
};
const ellipseStyle = (active) => new Style({ stroke: new Stroke({ color: active ? '#ffb347' : 'rgba(255,255,255,0.8)', width: active ? 2 : 1.2 }) });
const centreStyle = (i, active) => new Style({
  zIndex: 3,
  image: new CircleStyle({ radius: HANDLE, fill: new Fill({ color: active ? '#ffb347' : '#ffffff' }), stroke: new Stroke({ color: '#000', width: 1 }) }),
  text: new Text({ text: String(i + 1), font: 'bold 10px system-ui, sans-serif', fill: new Fill({ color: '#000' }), offsetY: 0.5 }),
});

export class PdmHandles {
  // hooks: {grab(p), drag(p), release()} with p a map view point {sx, sy, x, y}.
  constructor(view, hooks) {
    this.view = view;
    this.shapes = view.addVectorLayer(21);   // ellipses and axes, over the density (20)
    this.handles = view.addVectorLayer(22);  // the handles Modify drags
    this.parts = [];                         // per component {ellipse, axes, centre, sx, sy, rot}
    this.key = '';
    this.modify = new GrabModify({ source: this.handles.getSource(), pixelTolerance: HANDLE + 3, style: new Style({}) });
    this.modify.mapView = view;
    this.modify.hooks = hooks;
    this.modify.setActive(false);
    // A handle let go where the component did not follow it (σ at its minimum) goes back.
    this.modify.on('modifyend', () => {
      this.key = '';
      view.invalidate();
    });
    view.olMap.addInteraction(this.modify);
  }

  // The handles' places in local metres (rot: ROT_OFFSET px beyond σx at the view's scale).
  static places(g, scale) {
    const a = (g.rotation_deg * Math.PI) / 180, c = Math.cos(a), s = Math.sin(a);
    const sx = [g.x + c * g.sigma_x, g.y + s * g.sigma_x];
    const sy = [g.x - s * g.sigma_y, g.y + c * g.sigma_y];
    const off = ROT_OFFSET / scale;
    return { centre: [g.x, g.y], sx, sy, rot: [sx[0] + c * off, sx[1] + s * off] };
  }

  // Per frame: shown while shaping (the PDM tool, not the brush); the features follow the
  // components when they, the selection or the view changed.
  sync(comps, active, shown) {
    this.shapes.setVisible(shown);
    this.handles.setVisible(shown);
    this.modify.setActive(shown);
    if (!shown) return;
    const v = this.view;
    const key = `${JSON.stringify(comps)} ${active} ${v.viewVersion}`;
    if (key === this.key) return;
    this.key = key;
    const shapes = this.shapes.getSource(), handles = this.handles.getSource();
    comps.forEach((g, i) => {
      let p = this.parts[i];
      if (!p) {
        p = this.parts[i] = {
          ellipse: new Feature(new Polygon([])), axes: new Feature(new LineString([])),
          centre: new Feature(new Point([0, 0])), sx: new Feature(new Point([0, 0])), sy: new Feature(new Point([0, 0])), rot: new Feature(new Point([0, 0])),
        };
        p.axes.setStyle(STYLES.axes);
        for (const kind of ['sx', 'sy', 'rot']) p[kind].setStyle(STYLES[kind]);
        shapes.addFeatures([p.ellipse, p.axes]);
        handles.addFeatures([p.centre, p.sx, p.sy, p.rot]);
      }
      const h = PdmHandles.places(g, v.scale);
      const a = (g.rotation_deg * Math.PI) / 180, c = Math.cos(a), s = Math.sin(a);
      const ring = [];
      for (let j = 0; j <= 64; j++) {
        const t = (2 * Math.PI * j) / 64, u = g.sigma_x * Math.cos(t), w = g.sigma_y * Math.sin(t);
        ring.push([g.x + c * u - s * w, g.y + s * u + c * w]);
      }
      p.ellipse.getGeometry().setCoordinates([ring]);
      p.ellipse.setStyle(ellipseStyle(i === active));
      p.axes.getGeometry().setCoordinates([h.rot, h.centre, h.sy]);
      for (const kind of ['centre', 'sx', 'sy', 'rot']) p[kind].getGeometry().setCoordinates(h[kind]);
      p.centre.setStyle(centreStyle(i, i === active));
    });
    for (const p of this.parts.splice(comps.length)) {
      shapes.removeFeature(p.ellipse);
      shapes.removeFeature(p.axes);
      for (const kind of ['centre', 'sx', 'sy', 'rot']) handles.removeFeature(p[kind]);
    }
  }
}
