// Meshes the page tests upload, made here: boxes (whole or finely split
// into squares, so that a per-vertex reading varies over a face as it
// would on a scanned or finely exported part), tubes, and binary STL.

// The 12 triangles of a box, facing out (or in: a cavity).
export function boxTriangles([x0, y0, z0], [x1, y1, z1], inward = false) {
  const v = [[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0], [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]];
  const f = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [2, 3, 7], [2, 7, 6], [1, 2, 6], [1, 6, 5], [3, 0, 4], [3, 4, 7]];
  return f.map(([a, b, c]) => (inward ? [v[a], v[c], v[b]] : [v[a], v[b], v[c]]));
}

// A box facing out, each face split into squares of about `cell` a side.
export function splitBoxTriangles(lo, hi, cell) {
  const out = [];
  const n = [0, 1, 2].map((a) => Math.max(1, Math.round((hi[a] - lo[a]) / cell)));
  for (let axis = 0; axis < 3; ++axis) {
    const u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (const side of [0, 1]) {
      const point = (i, j) => {
        const p = [];
        p[axis] = side ? hi[axis] : lo[axis];
        p[u] = lo[u] + (hi[u] - lo[u]) * i / n[u];
        p[v] = lo[v] + (hi[v] - lo[v]) * j / n[v];
        return p;
      };
      for (let i = 0; i < n[u]; ++i) {
        for (let j = 0; j < n[v]; ++j) {
          const [a, b, c, d] = [point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)];
          // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
          if (side) out.push([a, b, c], [a, c, d]);
          else out.push([a, c, b], [a, d, c]);
        }
      }
    }
  }
  return out;
}

// A tube along z: radii `outer` and `inner`, `segments` around, `rings`
// along its length, closed by flat annuli at both ends.
export function tubeTriangles(outer, inner, length, segments = 96, rings = 10) {
  const out = [];
  // s % segments: the last segment ends on the first's vertices exactly.
  const at = (r, s, z) => {
    const a = 2 * Math.PI * (s % segments) / segments;
    return [r * Math.cos(a), r * Math.sin(a), z];
  };
  for (let s = 0; s < segments; ++s) {
    for (let k = 0; k < rings; ++k) {
      const z0 = length * k / rings, z1 = length * (k + 1) / rings;
      out.push([at(outer, s, z0), at(outer, s + 1, z0), at(outer, s + 1, z1)], [at(outer, s, z0), at(outer, s + 1, z1), at(outer, s, z1)]);
      out.push([at(inner, s, z0), at(inner, s + 1, z1), at(inner, s + 1, z0)], [at(inner, s, z0), at(inner, s, z1), at(inner, s + 1, z1)]);
    }
    out.push([at(outer, s, length), at(outer, s + 1, length), at(inner, s + 1, length)],
             [at(outer, s, length), at(inner, s + 1, length), at(inner, s, length)]);
    out.push([at(outer, s, 0), at(inner, s + 1, 0), at(outer, s + 1, 0)],
             [at(outer, s, 0), at(inner, s, 0), at(inner, s + 1, 0)]);
  }
  return out;
}

export function binaryStl(triangles) {
  const buffer = Buffer.alloc(84 + 50 * triangles.length);
  buffer.writeUInt32LE(triangles.length, 80);
  triangles.forEach((t, i) => t.forEach((p, k) => p.forEach((x, a) => buffer.writeFloatLE(x, 84 + 50 * i + 12 + 12 * k + 4 * a))));
  return buffer;
}
