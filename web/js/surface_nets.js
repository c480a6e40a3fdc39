// The zero level set of a field sampled at voxel centres, as a quad mesh by
// naive surface nets (Gibson 1998): one vertex in every cell (the cube
// between eight neighbouring samples) whose corners change sign, at the mean
// of the points where its edges cross zero (linear interpolation), and one
// quad around every edge between two samples of opposite sign, joining the
// four cells around it. Smooth where the field is a distance, closed where
// the level set does not reach the grid's border. No three.js here, so it
// can be tested on its own.

// field(i, j, k) for 0 <= i < nx...; returns { positions: Float32Array
// (x, y, z in voxel units, sample (i, j, k) at (i + 0.5, j + 0.5, k + 0.5)),
// indices: Uint32Array of triangles, outward (towards positive values) }.
// With `outside` (a positive value), the samples one voxel beyond the grid
// take it, so a level set that reaches the grid's outermost samples (a part
// filling its grid to the border) is still closed.
export function surfaceNets(dims, field, outside) {
  if (outside !== undefined) {
    const [gx, gy, gz] = dims;
    const padded = (i, j, k) => (i > 0 && j > 0 && k > 0 && i <= gx && j <= gy && k <= gz ? field(i - 1, j - 1, k - 1) : outside);
    const mesh = surfaceNets([gx + 2, gy + 2, gz + 2], padded);
    for (let v = 0; v < mesh.positions.length; ++v) mesh.positions[v] -= 1;
    return mesh;
  }
  const [nx, ny, nz] = dims;
  const cx = nx - 1, cy = ny - 1, cz = nz - 1;  // cells per axis
  const cellVertex = new Int32Array(Math.max(cx * cy * cz, 0)).fill(-1);
  const positions = [];
  const corner = new Float64Array(8);
  const EDGES = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];
  for (let k = 0; k < cz; ++k)
    for (let j = 0; j < cy; ++j)
      for (let i = 0; i < cx; ++i) {
        let negative = 0;
        for (let c = 0; c < 8; ++c) {
          corner[c] = field(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
          if (corner[c] < 0) ++negative;
        }
        if (negative === 0 || negative === 8) continue;
        let sx = 0, sy = 0, sz = 0, n = 0;
        for (const [a, b] of EDGES) {
          const fa = corner[a], fb = corner[b];
          if ((fa < 0) === (fb < 0)) continue;
          const t = fa / (fa - fb);
          sx += (a & 1) + t * ((b & 1) - (a & 1));
          sy += ((a >> 1) & 1) + t * (((b >> 1) & 1) - ((a >> 1) & 1));
          sz += ((a >> 2) & 1) + t * (((b >> 2) & 1) - ((a >> 2) & 1));
          ++n;
        }
        cellVertex[i + cx * (j + cy * k)] = positions.length / 3;
        positions.push(i + 0.5 + sx / n, j + 0.5 + sy / n, k + 0.5 + sz / n);
      }
  const indices = [];
  const cell = (i, j, k) => cellVertex[i + cx * (j + cy * k)];
  const quad = (a, b, c, d, flip) => {
    if (flip) indices.push(a, c, b, a, d, c);
    else indices.push(a, b, c, a, c, d);
  };
  // Edges along x from sample (i, j, k): the cells around it share j-1..j, k-1..k.
  for (let k = 1; k < cz; ++k)
    for (let j = 1; j < cy; ++j)
      for (let i = 0; i < cx; ++i) {
        const f0 = field(i, j, k), f1 = field(i + 1, j, k);
        if ((f0 < 0) === (f1 < 0)) continue;
        quad(cell(i, j - 1, k - 1), cell(i, j, k - 1), cell(i, j, k), cell(i, j - 1, k), f0 >= 0);
      }
  for (let k = 1; k < cz; ++k)
    for (let j = 0; j < cy; ++j)
      for (let i = 1; i < cx; ++i) {
        const f0 = field(i, j, k), f1 = field(i, j + 1, k);
        if ((f0 < 0) === (f1 < 0)) continue;
        quad(cell(i - 1, j, k - 1), cell(i - 1, j, k), cell(i, j, k), cell(i, j, k - 1), f0 >= 0);
      }
  for (let k = 0; k < cz; ++k)
    for (let j = 1; j < cy; ++j)
      for (let i = 1; i < cx; ++i) {
        const f0 = field(i, j, k), f1 = field(i, j, k + 1);
        if ((f0 < 0) === (f1 < 0)) continue;
        quad(cell(i - 1, j - 1, k), cell(i, j - 1, k), cell(i, j, k), cell(i - 1, j, k), f0 >= 0);
      }
  return { positions: new Float32Array(positions), indices: new Uint32Array(indices) };
}

// The volume a closed, outward surface encloses (the divergence theorem over
// its triangles), in the cube of its coordinates' unit; negative when it is
// turned inside out.
export function enclosedVolume({ positions: p, indices }) {
  let six = 0;
  for (let t = 0; t < indices.length; t += 3) {
    const a = 3 * indices[t], b = 3 * indices[t + 1], c = 3 * indices[t + 2];
    six += p[a] * (p[b + 1] * p[c + 2] - p[b + 2] * p[c + 1]) - p[a + 1] * (p[b] * p[c + 2] - p[b + 2] * p[c]) +
           p[a + 2] * (p[b] * p[c + 1] - p[b + 1] * p[c]);
  }
  return six / 6;
}
