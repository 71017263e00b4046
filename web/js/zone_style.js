// How keep-out zones look, as OpenLayers styles (zones.js, zone_interactions.js) and in the
// legend: a diagonal hatch in the zone colour, the outline solid when saved and dashed while the
// edits are unsaved, white and wider for the selected zone, square corner handles while the zones
// tool is on; the ring being drawn is a white dashed line with handles.

import { Fill, RegularShape, Stroke, Style } from 'ol/style.js';
import MultiPoint from 'ol/geom/MultiPoint.js';

export const ZONE_COLOUR = '#ff7a45';

// A hatch tile (diagonal lines), for a canvas pattern.
export function hatchCanvas(size = 8) {
  const c = document.createElement('canvas');
  c.width = c.height = size;
  const g = c.getContext('2d');
  g.strokeStyle = ZONE_COLOUR;
  g.lineWidth = 1.5;
  g.beginPath();
  g.moveTo(0, size);
  g.lineTo(size, 0);
  g.moveTo(-size / 2, size / 2);
  g.lineTo(size / 2, -size / 2);
  g.moveTo(size / 2, size * 1.5);
  g.lineTo(size * 1.5, size / 2);
  g.stroke();
  return c;
}

let pattern = null;  // made once: OL takes a CanvasPattern as a fill colour
function hatch() {
  if (!pattern) pattern = document.createElement('canvas').getContext('2d').createPattern(hatchCanvas(), 'repeat');
  return pattern;
}

// Square handles on every corner of a polygon's outer ring (or a line's points).
const HANDLES = new Style({
  image: new RegularShape({
    points: 4, radius: 5.5, angle: Math.PI / 4,
    fill: new Fill({ color: '#0b0d10' }), stroke: new Stroke({ color: '#ffffff', width: 1.5 }),
  }),
  geometry: (f) => {
    const g = f.getGeometry();
    const coords = g.getType() === 'Polygon' ? g.getCoordinates()[0].slice(0, -1) : g.getType() === 'LineString' ? g.getCoordinates() : [];
    return new MultiPoint(coords);
  },
});

// A zone feature: its properties `selected` and `dirty`; `editing` adds the corner handles.
export function zoneStyle(feature, editing) {
  const selected = feature.get('selected'), dirty = feature.get('dirty');
  const styles = [new Style({
    fill: new Fill({ color: hatch() }),
    stroke: new Stroke({ color: selected ? '#ffffff' : ZONE_COLOUR, width: selected ? 3 : 2, lineDash: dirty ? [6, 3] : undefined }),
  })];
  if (editing) styles.push(HANDLES);
  return styles;
}

// The ring being drawn (OL Draw's sketch, or the unfinished ring shown while the tool is off).
const SKETCH_LINE = new Style({ stroke: new Stroke({ color: '#ffffff', width: 2, lineDash: [5, 4] }) });
export function sketchStyle(feature) {
  const type = feature.getGeometry().getType();
  if (type === 'Point') return null;  // Draw's pointer marker: the crosshair cursor says it
  return [SKETCH_LINE, HANDLES];
}

// The legend's swatch: the hatch in a box outlined in the zone colour.
export function zoneSwatch(canvas) {
  const g = canvas.getContext('2d');
  g.fillStyle = g.createPattern(hatchCanvas(), 'repeat');
  g.fillRect(0, 0, canvas.width, canvas.height);
  g.strokeStyle = ZONE_COLOUR;
  g.lineWidth = 2;
  g.strokeRect(1, 1, canvas.width - 2, canvas.height - 2);
}
