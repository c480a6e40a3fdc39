// The radiography tab: the thickness map along an axis (min, max or total
// material met by rays along it), drawn with a colour scale, and the value
// under the cursor in model units. The map is read as the service's 16-bit
// PNG, whose pixels are voxel counts, with X-Voxd-Scale giving model units
// per count.
import { call } from './api.js';
import { decodeGreyPng } from './png16.js';

// A perceptual ramp (dark blue -> teal -> yellow), 0 for empty pixels.
function colour(t) {
  const stops = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  const x = Math.min(Math.max(t, 0), 1) * (stops.length - 1), i = Math.min(Math.floor(x), stops.length - 2), f = x - i;
  return stops[i].map((c, k) => Math.round(c + (stops[i + 1][k] - c) * f));
}

export class RadiographyView {
  constructor(elements) {
    this.el = elements;
    this.map = null;
    this.el.canvas.addEventListener('mousemove', (e) => this.readout(e));
    this.el.canvas.addEventListener('mouseleave', () => { this.el.readout.textContent = 'move over the image'; });
  }

  async show(jobId, axis, measure) {
    const res = await call(`/v1/jobs/${jobId}/radiography?axis=${axis}&measure=${measure}&format=png16&unit=model`);
    // "1 pixel value = 0.1 mm" (or "... model units")
    const scale = /=\s*([0-9.eE+-]+)\s*(.*)$/.exec(res.headers.get('X-Voxd-Scale') || '');
    const map = await decodeGreyPng(await res.arrayBuffer());
    map.perValue = scale ? Number(scale[1]) : 1;
    map.unit = scale ? scale[2] : 'voxels';
    map.axis = axis;
    map.measure = measure;
    map.max = map.values.reduce((m, v) => Math.max(m, v), 0);
    this.map = map;
    this.draw();
    return map;
  }

  draw() {
    const { width, height, values, max } = this.map;
    const canvas = this.el.canvas;
    canvas.width = width;
    canvas.height = height;
    // Shown at least 320 px wide, pixels kept square and sharp.
    canvas.style.width = `${Math.max(320, width)}px`;
    const ctx = canvas.getContext('2d');
    const image = ctx.createImageData(width, height);
    for (let i = 0; i < values.length; ++i) {
      const [r, g, b] = values[i] ? colour(values[i] / (max || 1)) : [255, 255, 255];
      image.data.set([r, g, b, 255], 4 * i);
    }
    ctx.putImageData(image, 0, 0);
    const bar = this.el.scale.getContext('2d');
    for (let x = 0; x < this.el.scale.width; ++x) {
      const [r, g, b] = colour(x / (this.el.scale.width - 1));
      bar.fillStyle = `rgb(${r},${g},${b})`;
      bar.fillRect(x, 0, 1, this.el.scale.height);
    }
    this.el.lo.textContent = `0 ${this.map.unit}`;
    this.el.hi.textContent = `${(max * this.map.perValue).toPrecision(4)} ${this.map.unit}`;
  }

  // The value under the cursor, in model units.
  valueAt(px, py) {
    const { width, values, perValue } = this.map;
    return values[py * width + px] * perValue;
  }

  readout(e) {
    if (!this.map) return;
    const rect = this.el.canvas.getBoundingClientRect();
    const px = Math.floor(((e.clientX - rect.left) / rect.width) * this.map.width);
    const py = Math.floor(((e.clientY - rect.top) / rect.height) * this.map.height);
    if (px < 0 || py < 0 || px >= this.map.width || py >= this.map.height) return;
    this.el.readout.textContent =
      `pixel (${px}, ${py}): ${this.map.measure} ${this.valueAt(px, py).toPrecision(4)} ${this.map.unit}`;
  }
}
