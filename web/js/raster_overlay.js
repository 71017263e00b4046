// An OpenLayers image layer (issue 24) showing a small canvas stretched over a rectangle of the
// map's local metres — a grid of cells: the coverage grid (coverage_layer.js), the PDM density
// being edited (pdm_editor.js). OL asks for a picture of the view's extent (ImageCanvas source)
// when the view moved or after `changed()`; the canvas is drawn into it, smoothed or one block a
// cell.

import ImageLayer from 'ol/layer/Image.js';
import ImageCanvas from 'ol/source/ImageCanvas.js';

export class RasterOverlay {
  // what() → {canvas, rect: [x0, y0, width, height] in metres} or null (nothing to show).
  constructor(view, zIndex, className, what, { smooth = false } = {}) {
    this.view = view;
    this.what = what;
    this.smooth = smooth;
    this.out = document.createElement('canvas');
    this.source = new ImageCanvas({ canvasFunction: (...a) => this.paint(...a), ratio: 1 });
    this.layer = new ImageLayer({ source: this.source, zIndex, className: `ol-layer ${className}` });
    view.olMap.addLayer(this.layer);
  }

  // The canvas changed: OL draws the layer again.
  changed() {
    this.source.changed();
  }

  // OL's canvasFunction: `extent` in local metres, `resolution` metres a CSS pixel, `size` in
  // device pixels.
  paint(extent, resolution, pixelRatio, size) {
    const out = this.out;
    out.width = Math.max(1, Math.round(size[0]));
    out.height = Math.max(1, Math.round(size[1]));
    const w = this.what();
    if (!w) return out;
    const g = out.getContext('2d');
    const px = pixelRatio / resolution;
    const [x0, y0, width, height] = w.rect;
    g.imageSmoothingEnabled = this.smooth;
    g.drawImage(w.canvas, (x0 - extent[0]) * px, (extent[3] - (y0 + height)) * px, width * px, height * px);
    return out;
  }
}
