// Surface nets (web/js/surface_nets.js) against shapes with known answers:
// a sphere's distance field gives a closed, consistently oriented surface
// (Euler characteristic 2, every edge in two triangles, the enclosed volume
// outward-positive) whose vertices lie on the sphere; a torus's has genus 1.
//   node --test tests/web/surface_nets_test.mjs
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { enclosedVolume, surfaceNets } from '../../web/js/surface_nets.js';

function check(mesh) {
  const { positions, indices } = mesh;
  const edges = new Map();
  for (let t = 0; t < indices.length; t += 3) {
    const v = [indices[t], indices[t + 1], indices[t + 2]];
    for (let e = 0; e < 3; ++e) {
      const a = v[e], b = v[(e + 1) % 3];
      const key = a < b ? `${a},${b}` : `${b},${a}`;
      const directed = edges.get(key) || [0, 0];
      directed[a < b ? 0 : 1] += 1;
      edges.set(key, directed);
    }
  }
  for (const [key, [forward, backward]] of edges) assert.ok(forward === 1 && backward === 1, `edge ${key}: ${forward}/${backward}`);
  const euler = positions.length / 3 - edges.size + indices.length / 3;
  return { euler, volume: enclosedVolume(mesh) };
}

test('a sphere\'s distance field gives a closed sphere through the field\'s zeros', () => {
  const n = 24, c = 12, r = 7.3;
  const field = (i, j, k) => Math.hypot(i + 0.5 - c, j + 0.5 - c, k + 0.5 - c) - r;
  const mesh = surfaceNets([n, n, n], field);
  const { euler, volume } = check(mesh);
  assert.equal(euler, 2);
  // Outward: the enclosed volume is positive and near the sphere's.
  assert.ok(Math.abs(volume - (4 / 3) * Math.PI * r ** 3) / ((4 / 3) * Math.PI * r ** 3) < 0.03, `volume ${volume}`);
  for (let v = 0; v < mesh.positions.length; v += 3) {
    const d = Math.hypot(mesh.positions[v] - c, mesh.positions[v + 1] - c, mesh.positions[v + 2] - c);
    assert.ok(Math.abs(d - r) < 0.1, `vertex at ${d} from the centre`);
  }
});

test('a torus has genus one', () => {
  const n = 40, c = 20, R = 11, r = 5.5;
  const field = (i, j, k) => {
    const x = i + 0.5 - c, y = j + 0.5 - c, z = k + 0.5 - c;
    return Math.hypot(Math.hypot(x, y) - R, z) - r;
  };
  const { euler, volume } = check(surfaceNets([n, n, n], field));
  assert.equal(euler, 0);
  assert.ok(Math.abs(volume - 2 * Math.PI ** 2 * R * r * r) / (2 * Math.PI ** 2 * R * r * r) < 0.03, `volume ${volume}`);
});

test('a part that fills its grid to the border is closed with samples outside it', () => {
  // A box whose faces lie half a voxel beyond the outermost sample centres
  // (as a grid fitted to a part has them), negative inside.
  const [nx, ny, nz] = [10, 8, 6];
  const field = (i, j, k) => -Math.min(i + 0.5, nx - i - 0.5, j + 0.5, ny - j - 0.5, k + 0.5, nz - k - 0.5);
  const open = surfaceNets([nx, ny, nz], field);
  assert.equal(open.indices.length, 0, 'every sample is inside: nothing to join without the outside');
  const mesh = surfaceNets([nx, ny, nz], field, 0.5);
  const { euler, volume } = check(mesh);
  assert.equal(euler, 2);
  // The faces land on the grid's border: the box's bounds are the grid's.
  for (let a = 0; a < 3; ++a) {
    const coords = Array.from(mesh.positions).filter((_, v) => v % 3 === a);
    assert.ok(Math.abs(Math.min(...coords)) < 1e-6 && Math.abs(Math.max(...coords) - [nx, ny, nz][a]) < 1e-6);
  }
  // Surface nets rounds a box's edges (about a quarter voxel squared along
  // each of its 96 voxels of edges): the volume is the box's less that.
  assert.ok(volume < 480 && volume > 480 - 0.3 * 96, `volume ${volume}`);
});

test('no sign change, no surface', () => {
  const { positions, indices } = surfaceNets([5, 5, 5], () => 1);
  assert.equal(positions.length, 0);
  assert.equal(indices.length, 0);
});
