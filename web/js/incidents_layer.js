// A mission's incidents as markers on the map: an OpenLayers vector layer (issue 24) with a
// point feature per incident, shaped and coloured by its kind (incidents.js INCIDENT_KINDS); the
// selected one larger, ringed in white and above the others. The features follow the list on
// the frames the map view draws: updated in place when the list is another (the stream's or the
// result's), restyled when the selection moves.

import Feature from 'ol/Feature.js';
import Point from 'ol/geom/Point.js';
import { Circle as CircleStyle, Fill, RegularShape, Stroke, Style } from 'ol/style.js';

const EDGE = new Stroke({ color: '#000000b0', width: 1 });
const RING = new Style({ image: new CircleStyle({ radius: 13, stroke: new Stroke({ color: '#ffffff', width: 2 }) }), zIndex: 2 });

// The marker of a shape ('circle', 'square', 'diamond', 'triangle', 'cross') of radius r.
function shapeImage(shape, colour, r) {
  const fill = new Fill({ color: colour });
  if (shape === 'circle') return new CircleStyle({ radius: r, fill, stroke: EDGE });
  if (shape === 'square') return new RegularShape({ points: 4, radius: r * Math.SQRT2, angle: Math.PI / 4, fill, stroke: EDGE });
  if (shape === 'diamond') return new RegularShape({ points: 4, radius: r, angle: 0, fill, stroke: EDGE });
  if (shape === 'triangle') return new RegularShape({ points: 3, radius: r * 1.2, angle: 0, fill, stroke: EDGE });
  return new RegularShape({ points: 4, radius: r * 1.3, radius2: r * 0.45, angle: Math.PI / 4, fill, stroke: EDGE });  // cross
}

const styles = new Map();
function markerStyle(kind, selected) {
  const key = `${kind.shape} ${kind.colour} ${selected}`;
  if (!styles.has(key)) {
    const marker = new Style({ image: shapeImage(kind.shape, kind.colour, selected ? 7 : 5), zIndex: selected ? 1 : 0 });
    styles.set(key, selected ? [marker, RING] : [marker]);
  }
  return styles.get(key);
}

export class IncidentLayer {
  // kindOf(kind) → {colour, shape}
  constructor(view, zIndex, kindOf) {
    this.view = view;
    this.kindOf = kindOf;
    this.layer = view.addVectorLayer(zIndex);
    this.features = [];
    this.items = null;     // the list the features show
    this.selected = -1;
  }

  // Per frame: the layer list's controls, then the features when the list or selection changed.
  sync(items, selected, opacity, visible) {
    this.layer.setOpacity(opacity);
    this.layer.setVisible(visible);
    if (items !== this.items) {
      this.items = items;
      this.selected = selected;
      // In place: the features of the incidents kept move to their (same) place, new ones are
      // added, those past the new list's end go.
      const source = this.layer.getSource();
      const added = [];
      items.forEach((it, i) => {
        let f = this.features[i];
        if (!f) {
          f = this.features[i] = new Feature(new Point([it.x, it.y]));
          added.push(f);
        } else {
          f.getGeometry().setCoordinates([it.x, it.y]);
        }
        f.setStyle(markerStyle(this.kindOf(it.kind), i === selected));
      });
      for (const f of this.features.splice(items.length)) source.removeFeature(f);
      if (added.length) source.addFeatures(added);
      return;
    }
    if (selected === this.selected) return;
    for (const i of [this.selected, selected]) {
      const f = this.features[i];
      if (f) f.setStyle(markerStyle(this.kindOf(items[i].kind), i === selected));
    }
    this.selected = selected;
  }
}
