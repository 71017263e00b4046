// A team mission's plan over the map (server stream "overlay" frames, result.json "overlays"):
// the team route through the search cells (white, numbered targets) and each rover's planned
// RRT* path as it is accepted (thin, in the rover's colour, under its simulated trail).
// Target numbers are decluttered (issue 27: "596061626364"): a number is drawn only where it
// overlaps no number already drawn (route order first), and the target nearest the cursor always
// shows its number, boxed. Drawn as OpenLayers features (issue 24): two vector layers, the lines
// and dots, and the numbers over them.

import Feature from 'ol/Feature.js';
import LineString from 'ol/geom/LineString.js';
import MultiPoint from 'ol/geom/MultiPoint.js';
import Point from 'ol/geom/Point.js';
import { Circle as CircleStyle, Fill, Stroke, Style, Text } from 'ol/style.js';
import { roverColour } from './util.js';

export class PlanLayer {
  constructor(view) {
    this.view = view;
    this.ol = olParts(view);
    this.clear();
    this.hover = null;    // the cursor on the map {sx, sy}, or null
    this.labelled = [];   // the targets whose numbers the last frame drew (tests read it)
  }

  clear() {
    this.route = [];  // [[x, y]...]: the start cell's centre, then the targets
    this.paths = [];  // per rover: [[x, y]...]
  }

  get empty() {
    return this.route.length === 0 && this.paths.every((p) => p.length === 0);
  }

  // A snapshot's or an overlay frame's {route?, paths?}; snapshot paths are whole, frame paths append.
  apply(msg, whole = false) {
    if (Array.isArray(msg.route)) this.route = msg.route.map((p) => [p[0], p[1]]);
    if (whole && Array.isArray(msg.paths)) {
      this.paths = msg.paths.map((p) => p.map((q) => [q[0], q[1]]));
      return;
    }
    for (const p of msg.paths || []) {
      while (this.paths.length <= p.rover) this.paths.push([]);
      for (const q of p.append) this.paths[p.rover].push([q[0], q[1]]);
    }
  }

  // result.json's overlays: [{key, rover, points}].
  setFromResult(overlays) {
    this.clear();
    for (const o of overlays || []) {
      if (o.key === 'route') this.route = o.points;
      else if (o.key === 'path') {
        while (this.paths.length <= o.rover) this.paths.push([]);
        this.paths[o.rover] = o.points;
      }
    }
  }

  // --- on the map: OL features (issue 24), updated in place on the frames the map view draws ---
  // Per frame: the layer list's controls; the rovers' planned paths (appended in place), the
  // route and its dots when the route is another, the numbers when the view, route or hovered
  // target changed.
  sync(opacity, visible) {
    const ol = this.ol;
    for (const l of [ol.layer, ol.numbers]) {
      l.setOpacity(opacity);
      l.setVisible(visible);
    }
    const source = ol.layer.getSource();
    this.paths.forEach((path, i) => {
      if (!ol.paths[i]) {
        ol.paths[i] = new Feature(new LineString([]));
        ol.paths[i].setStyle(new Style({ stroke: new Stroke({ color: roverColour(i), width: 1, lineDash: [3, 3], lineJoin: 'round' }) }));
        ol.counts[i] = 0;
        source.addFeature(ol.paths[i]);
      }
      const geom = ol.paths[i].getGeometry();
      if (path.length < ol.counts[i] || ol.sources[i] !== path) {
        geom.setCoordinates(path.map(([x, y]) => [x, y]));
      } else if (path.length > ol.counts[i]) {
        for (let j = ol.counts[i]; j < path.length; j++) geom.appendCoordinate([path[j][0], path[j][1]]);
      }
      ol.counts[i] = path.length;
      ol.sources[i] = path;
    });
    for (const f of ol.paths.splice(this.paths.length)) source.removeFeature(f);
    ol.counts.length = ol.sources.length = ol.paths.length;
    if (ol.routeShown !== this.route) {
      ol.routeShown = this.route;
      const coords = this.route.map(([x, y]) => [x, y]);
      const parts = [ol.route, ol.start, ol.targets];
      if (!coords.length) {
        if (source.hasFeature(ol.route)) for (const f of parts) source.removeFeature(f);
      } else {
        ol.route.getGeometry().setCoordinates(coords);
        ol.start.getGeometry().setCoordinates(coords[0]);
        ol.targets.getGeometry().setCoordinates(coords.slice(1));
        if (!source.hasFeature(ol.route)) source.addFeatures(parts);
      }
    }
    this.syncNumbers();
  }

  // The target numbers: decluttered in screen space (a number only where it overlaps no number
  // already shown, route order first; the hovered target's always, boxed), made again only when
  // the view, the route or the hovered target changed.
  syncNumbers() {
    const ol = this.ol, view = this.view;
    const screen = this.route.map(([x, y]) => view.worldToScreen(x, y));
    let hovered = -1, best = 12;  // the nearest target within 12 px of the cursor
    if (this.hover) {
      screen.forEach(([sx, sy], i) => {
        const d = Math.hypot(sx - this.hover.sx, sy - this.hover.sy);
        if (i > 0 && d < best) {
          best = d;
          hovered = i;
        }
      });
    }
    const key = `${view.viewVersion} ${hovered}`;
    if (key === ol.numbersKey && ol.numbersRoute === this.route) return;
    ol.numbersKey = key;
    ol.numbersRoute = this.route;
    const boxes = [];
    const box = (i) => [screen[i][0] + 4, screen[i][1] - 13, measure(String(i)), 10];
    const hit = (a, b) => a[0] < b[0] + b[2] + 2 && b[0] < a[0] + a[2] + 2 && a[1] < b[1] + b[3] + 1 && b[1] < a[1] + a[3] + 1;
    if (hovered > 0) boxes.push(box(hovered));
    this.labelled = [];
    const features = [];
    for (let i = 1; i < screen.length; i++) {
      if (i === hovered) continue;
      const b = box(i);
      if (boxes.some((o) => hit(o, b))) continue;
      boxes.push(b);
      this.labelled.push(i);
      features.push(numberFeature(this.route[i], i, false));
    }
    if (hovered > 0) {
      features.push(numberFeature(this.route[hovered], hovered, true));
      this.labelled.push(hovered);
    }
    const source = ol.numbers.getSource();
    source.clear();
    source.addFeatures(features);
  }
}

const FONT = '10px sans-serif';
let measurer = null;
function measure(text) {
  if (!measurer) {
    measurer = document.createElement('canvas').getContext('2d');
    measurer.font = FONT;
  }
  return measurer.measureText(text).width;
}

// Target i's number right of and above its dot; the hovered one yellow on a dark box.
function numberFeature([x, y], i, hovered) {
  const f = new Feature(new Point([x, y]));
  f.setStyle(new Style({
    zIndex: hovered ? 1 : 0,
    text: new Text({
      text: String(i), font: FONT, textAlign: 'left', textBaseline: 'alphabetic', offsetX: 4, offsetY: -4,
      fill: new Fill({ color: hovered ? '#ffd23f' : '#ffffff' }),
      backgroundFill: hovered ? new Fill({ color: 'rgba(0,0,0,0.8)' }) : undefined,
      padding: hovered ? [1, 2, 2, 2] : undefined,
    }),
  }));
  return f;
}

// The route's and the dots' styles.
const ROUTE = new Style({ stroke: new Stroke({ color: 'rgba(255,255,255,0.85)', width: 2, lineJoin: 'round' }) });
const DOT = (r) => new Style({ image: new CircleStyle({ radius: r, fill: new Fill({ color: '#ffffff' }) }) });

function olParts(view) {
  const route = new Feature(new LineString([]));
  route.setStyle(ROUTE);
  const start = new Feature(new Point([0, 0]));
  start.setStyle(DOT(5));
  const targets = new Feature(new MultiPoint([]));
  targets.setStyle(DOT(3));
  return {
    layer: view.addVectorLayer(35), numbers: view.addVectorLayer(35.5, { declutter: false }),
    paths: [], counts: [], sources: [], route, start, targets, routeShown: null, numbersKey: '', numbersRoute: null,
  };
}
