// The colours of the part painted by wall thickness: what each reading
// means against the job's limits, as a list of bands (the legend) and as a
// lookup texture for the surface. A reading r of a wall w has
// w - below <= r <= w + above (the report's thickness.reading_bound), and
// the verdict adds a tolerance for the reading's noise, so the bands are the
// verdict's own: thin where the wall is certainly under min_wall, marginal
// where it may be on either side, then a ramp of the walls within the
// limits, marginal again near max_wall and thick beyond it.

export const THIN = '#d7301f', MARGINAL = '#f5a300', THICK = '#7b3294', NO_VALUE = '#9aa0a8';
// The ramp inside the limits: green to blue, none of it near the marks'
// hues (red, amber, purple).
const RAMP = ['#1a9850', '#3fae74', '#47b39e', '#3b9fbf', '#2c7bb6'];

// Bands { lo, hi, colour, kind, label } covering [0, top) in the report's
// unit. `t`: the report's thickness (min, max, min_wall, max_wall,
// reading_bound).
export function wallBands(t) {
  const rb = t.reading_bound || { below: 0, above: 0, tolerance: 0 };
  const bands = [];
  let from = 0;
  const add = (hi, colour, kind, label) => {
    if (hi > from) bands.push({ lo: from, hi, colour, kind, label });
    from = Math.max(from, hi);
  };
  let okFrom = t.min ?? 0, okTo = t.max ?? 1;
  if (t.min_wall) {
    const at = t.min_wall - rb.tolerance;
    add(at - rb.above, THIN, 'thin', 'thin: certainly under min wall');
    add(at + rb.below, MARGINAL, 'marginal', `within the error bound of min wall ${fmt(t.min_wall)}`);
    okFrom = from;
  }
  let thickFrom = Infinity;
  if (t.max_wall) {
    const at = t.max_wall + rb.tolerance;
    okTo = at - rb.above;
    thickFrom = at + rb.below;
  }
  if (!(okTo > okFrom)) okTo = okFrom + Math.max(1e-6, Math.abs(okFrom) * 1e-3);
  const step = (okTo - okFrom) / RAMP.length;
  RAMP.forEach((colour, i) => add(i === RAMP.length - 1 ? okTo : okFrom + step * (i + 1), colour, 'within',
                                  'within the limits'));
  if (t.max_wall) {
    add(thickFrom, MARGINAL, 'marginal', `within the error bound of max wall ${fmt(t.max_wall)}`);
    add(Math.max(thickFrom, t.max ?? thickFrom) * 1.25 + 1e-6, THICK, 'thick', 'thick: certainly over max wall');
  } else {
    bands[bands.length - 1].hi = Math.max(okTo, t.max ?? okTo) * 1.25 + 1e-6;
  }
  return bands;
}

export const fmt = (x) => Number(x).toPrecision(3);

// The band a reading falls in (a reading of 0: no filled voxel under it).
export function bandOf(bands, value) {
  if (!(value > 0)) return null;
  return bands.find((b) => value < b.hi) || bands[bands.length - 1];
}

// A lookup of `texels` colours over [0, top): the surface takes the colour
// at its interpolated reading (u = reading / top), so bands stay sharp
// across a triangle instead of blending their colours.
export function lookupTexels(bands, texels = 2048) {
  const top = bands[bands.length - 1].hi;
  const rgba = new Uint8Array(4 * texels);
  for (let i = 0; i < texels; ++i) {
    const value = (i + 0.5) / texels * top;
    const hex = i === 0 ? NO_VALUE : bandOf(bands, value).colour;
    for (let c = 0; c < 3; ++c) rgba[4 * i + c] = parseInt(hex.slice(1 + 2 * c, 3 + 2 * c), 16);
    rgba[4 * i + 3] = 255;
  }
  return { rgba, texels, top };
}

// The legend: one chip a band, the limits' marks in their labels.
export function renderLegend(container, bands, unit) {
  container.replaceChildren(...bands.map((b, i) => {
    const chip = Object.assign(document.createElement('span'), { className: `band ${b.kind}`, title: b.label });
    chip.dataset.lo = b.lo;
    chip.dataset.hi = b.hi;
    chip.dataset.colour = b.colour;
    chip.dataset.kind = b.kind;
    const swatch = Object.assign(document.createElement('i'), { className: 'swatch' });
    swatch.style.background = b.colour;
    const range = i === 0 ? `< ${fmt(b.hi)}` : i === bands.length - 1 ? `≥ ${fmt(b.lo)}` : `${fmt(b.lo)}–${fmt(b.hi)}`;
    const word = b.kind === 'within' ? '' : ` ${b.kind}`;
    chip.append(swatch, `${range}${word}`);
    return chip;
  }), Object.assign(document.createElement('span'), { className: 'muted', textContent: unit }));
}
