// The mission form's rover starts on the map (a numbered disc in the rover's colour, a line along
// its heading) as an OpenLayers vector layer (issue 24), shown while placing rovers or while the
// Mission tab is open. A feature per rover, updated in place when a start, the shown state or
// the map changes (checked on the frames the map view draws).

import Feature from 'ol/Feature.js';
import Point from 'ol/geom/Point.js';
import { Circle as CircleStyle, Fill, Icon, Stroke, Style, Text } from 'ol/style.js';
import { roverColour } from './util.js';

const LINE = 22;  // px, the heading line's length

// A line from the centre of a canvas eastwards (rotated by the style): black under the colour.
const lines = new Map();
function headingLine(colour) {
  if (lines.has(colour)) return lines.get(colour);
  const c = document.createElement('canvas');
  c.width = c.height = 2 * LINE + 4;
  const g = c.getContext('2d');
  const o = LINE + 2;
  g.beginPath();
  g.moveTo(o, o);
  g.lineTo(o + LINE, o);
  g.strokeStyle = '#000';
  g.lineWidth = 3;
  g.stroke();
  g.strokeStyle = colour;
  g.lineWidth = 2;
  g.stroke();
  lines.set(colour, c);
  return c;
}

function startStyle(k, heading) {
  const colour = roverColour(k);
  return [
    new Style({ image: new Icon({ img: headingLine(colour), rotation: (-heading * Math.PI) / 180, rotateWithView: false }) }),
    new Style({
      image: new CircleStyle({ radius: 8, fill: new Fill({ color: colour }), stroke: new Stroke({ color: '#000', width: 1.5 }) }),
      text: new Text({ text: String(k + 1), font: 'bold 10px system-ui, sans-serif', fill: new Fill({ color: '#000' }), offsetY: 0.5 }),
    }),
  ];
}

export class StartMarks {
  constructor(view, zIndex) {
    this.view = view;
    this.layer = view.addVectorLayer(zIndex);
    this.features = [];
    this.shownKey = [];
  }

  // rovers: [{x, y, heading} | null]; shown: whether the starts show at all.
  sync(rovers, shown) {
    this.layer.setVisible(shown);
    if (!shown) return;
    const source = this.layer.getSource();
    rovers.forEach((r, i) => {
      const key = r ? `${r.x} ${r.y} ${r.heading}` : '';
      if (key === this.shownKey[i]) return;
      this.shownKey[i] = key;
      let f = this.features[i];
      if (!r) {
        if (f) source.removeFeature(f);
        this.features[i] = null;
        return;
      }
      if (!f) {
        f = this.features[i] = new Feature(new Point([r.x, r.y]));
        source.addFeature(f);
      } else {
        f.getGeometry().setCoordinates([r.x, r.y]);
      }
      f.setStyle(startStyle(i, r.heading));
    });
    for (const f of this.features.splice(rovers.length)) if (f) source.removeFeature(f);
    this.shownKey.length = Math.min(this.shownKey.length, rovers.length);
  }
}
