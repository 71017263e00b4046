// Rover trails and poses on the map: TrailSet holds them (per rover the points so far, the last
// heading, the replay limit), TrailLayer shows them as OpenLayers features, so they pan and zoom
// with the map in OL's own render loop (and OL skips sub-pixel steps of long trails itself).

import Feature from 'ol/Feature.js';
import LineString from 'ol/geom/LineString.js';
import Point from 'ol/geom/Point.js';
import { asArray } from 'ol/color.js';
import { Icon, Stroke, Style } from 'ol/style.js';
import { roverColour } from './util.js';

const APPEND_MAX = 64;  // points appended one by one to a trail's line in a frame; more: set whole

export class TrailSet {
  constructor(style = {}) {
    this.paths = [];       // per rover: array of [x, y]
    this.headings = [];    // per rover: last heading (deg) or null
    this.limit = Infinity; // replay: points 0..limit are shown
    this.style = { width: 2, dash: null, alpha: 1, label: '', ...style };
    this.version = 0;      // bumps when drawn points may shrink/change (full redraw needed)
  }

  clear(rovers = 0) {
    this.paths = Array.from({ length: rovers }, () => []);
    this.headings = Array.from({ length: rovers }, () => null);
    this.limit = Infinity;
    this.version++;
  }

  ensure(k) {
    while (this.paths.length <= k) {
      this.paths.push([]);
      this.headings.push(null);
    }
  }

  append(k, points, pose) {
    this.ensure(k);
    const p = this.paths[k];
    for (const q of points) p.push(q);
    if (pose) this.headings[k] = pose.heading_deg;
  }

  setPaths(paths) {
    this.paths = paths.map((p) => p.slice());
    this.headings = paths.map(() => null);
    this.version++;
  }

  setLimit(limit) {
    if (limit === this.limit) return;
    this.limit = limit;
    this.version++;
  }

  get longest() {
    return this.paths.reduce((m, p) => Math.max(m, p.length), 0);
  }

  // Position and heading (deg) of rover k at the shown end of its trail.
  poseOf(k) {
    const p = this.paths[k];
    if (!p || p.length === 0) return null;
    const i = Math.min(p.length - 1, this.limit);
    let heading = this.limit >= p.length - 1 && this.headings[k] !== null ? this.headings[k] : null;
    if (heading === null) {
      // From the last move that changed the position.
      for (let j = i; j > 0; j--) {
        const dx = p[j][0] - p[j - 1][0], dy = p[j][1] - p[j - 1][1];
        if (dx || dy) {
          heading = (Math.atan2(dy, dx) * 180) / Math.PI;
          break;
        }
      }
    }
    return { x: p[i][0], y: p[i][1], heading: heading ?? 0 };
  }
}

// The trails and rovers of some TrailSets as two OL vector layers (issue 24): a line feature and
// a rover feature per rover, updated in place from the sets on every frame the map view draws —
// only the points added since the last frame are appended to a line (LineString's
// appendCoordinate); a replay seek or a reset sets it whole (setCoordinates).
export class TrailLayer {
  constructor(view, zIndex) {
    this.view = view;
    this.sets = [];
    this.lines = view.addVectorLayer(zIndex);
    this.rovers = view.addVectorLayer(zIndex + 0.5);
    this.shown = new Map();  // set → {version, lines: [Feature], counts: [n], rovers: [Feature], poses: [key]}
  }

  add(set) {
    this.sets.push(set);
    return set;
  }

  remove(set) {
    this.sets = this.sets.filter((s) => s !== set);
    const s = this.shown.get(set);
    if (!s) return;
    for (const f of s.lines) this.lines.getSource().removeFeature(f);
    for (const f of s.rovers) this.rovers.getSource().removeFeature(f);
    this.shown.delete(set);
  }

  // Per frame: the layers' opacity and visibility (the layer list's controls), then the features.
  sync(opacity, showLines, showRovers) {
    this.lines.setOpacity(opacity);
    this.lines.setVisible(showLines);
    this.rovers.setVisible(showRovers);
    for (const set of this.sets) this.syncSet(set);
  }

  syncSet(set) {
    let s = this.shown.get(set);
    if (!s) {
      s = { version: -1, lines: [], counts: [], rovers: [], poses: [] };
      this.shown.set(set, s);
    }
    const whole = s.version !== set.version;
    s.version = set.version;
    const n = set.paths.length;
    for (let i = 0; i < n; i++) {
      const path = set.paths[i];
      const end = Math.min(path.length, set.limit + 1);
      if (!s.lines[i]) {
        s.lines[i] = new Feature(new LineString([]));
        s.lines[i].setStyle(lineStyle(set.style, i));
        s.counts[i] = 0;
        this.lines.getSource().addFeature(s.lines[i]);
      }
      const geom = s.lines[i].getGeometry();
      // A long stretch at once (a seek ahead) is set whole: appendCoordinate is a change event a point.
      if (whole || end < s.counts[i] || end - s.counts[i] > APPEND_MAX) {
        geom.setCoordinates(path.slice(0, end).map(([x, y]) => [x, y]));
      } else {
        for (let j = s.counts[i]; j < end; j++) geom.appendCoordinate([path[j][0], path[j][1]]);
      }
      s.counts[i] = end;
      this.syncRover(set, s, i);
    }
    for (const f of s.lines.splice(n)) this.lines.getSource().removeFeature(f);
    for (const f of s.rovers.splice(n)) if (f) this.rovers.getSource().removeFeature(f);
    s.counts.length = Math.min(s.counts.length, n);
    s.poses.length = Math.min(s.poses.length, n);
  }

  // Rover i's arrow at the shown end of its trail, pointing along its heading.
  syncRover(set, s, i) {
    const pose = set.poseOf(i);
    const key = pose ? `${pose.x} ${pose.y} ${pose.heading}` : '';
    if (key === s.poses[i]) return;
    s.poses[i] = key;
    let f = s.rovers[i];
    if (!pose) {
      if (f) this.rovers.getSource().removeFeature(f);
      s.rovers[i] = null;
      return;
    }
    if (!f) {
      f = s.rovers[i] = new Feature(new Point([0, 0]));
      this.rovers.getSource().addFeature(f);
    }
    f.getGeometry().setCoordinates([pose.x, pose.y]);
    const colour = roverColour(i + (set.style.colourOffset || 0));
    f.setStyle(new Style({ image: new Icon({ img: arrow(colour, Boolean(set.style.hollow)), rotation: (-pose.heading * Math.PI) / 180, rotateWithView: false }) }));
  }
}

// A trail's line: the rover's colour at the set's alpha, its width and dash.
function lineStyle(style, k) {
  const colour = asArray(roverColour(k + (style.colourOffset || 0))).slice();
  colour[3] = style.alpha ?? 1;
  return new Style({ stroke: new Stroke({ color: colour, width: style.width, lineDash: style.dash || undefined, lineCap: 'round', lineJoin: 'round' }) });
}

// A rover's arrow pointing east (rotated by its style): filled with a black edge, or hollow in
// the rover's colour for a believed pose (localisation error). One canvas per colour and kind.
const arrows = new Map();
function arrow(colour, hollow) {
  const key = `${colour} ${hollow}`;
  if (arrows.has(key)) return arrows.get(key);
  const c = document.createElement('canvas');
  c.width = c.height = 24;
  const g = c.getContext('2d');
  g.translate(12, 12);
  g.beginPath();
  g.moveTo(9, 0);
  g.lineTo(-6, 6);
  g.lineTo(-3, 0);
  g.lineTo(-6, -6);
  g.closePath();
  g.lineJoin = 'round';
  if (hollow) {
    g.strokeStyle = colour;
    g.lineWidth = 2;
    g.stroke();
  } else {
    g.fillStyle = colour;
    g.strokeStyle = '#000';
    g.lineWidth = 1.5;
    g.fill();
    g.stroke();
  }
  arrows.set(key, c);
  return c;
}
