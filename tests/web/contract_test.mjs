// The contract as third-party tools see it: the OpenAPI document a real
// `voxd serve` answers at /openapi.json is linted by Redocly's recommended
// rules (proto-schemas/redocly.yaml) and validated by swagger-parser, both
// from web/package-lock.json; the repository's own document (whose schemas
// live in files beside it) lints clean too; and /docs renders every
// operation in headless Chromium without asking any other host for anything.
// A palette job's glb passes the Khronos glTF validator and stands Y-up,
// and so does the thickness on a part, which three.js opens with its colours.
//   node --test tests/web/contract_test.mjs   (VOXD_BINARY=path/to/voxd)
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { after, before, test } from 'node:test';

import { launchChromium, repo, requireWebModule, startVoxd } from './voxd_server.mjs';

const work = mkdtempSync(join(tmpdir(), 'voxd-contract-'));
let server;
let served;
const servedPath = join(work, 'openapi.json');

before(async () => {
  server = await startVoxd(join(work, 'data'));
  const res = await fetch(`${server.base}/openapi.json`);
  assert.equal(res.status, 200);
  assert.match(res.headers.get('content-type'), /^application\/json/);
  served = await res.json();
  writeFileSync(servedPath, JSON.stringify(served));
});

after(() => {
  server?.child.kill('SIGTERM');
  rmSync(work, { recursive: true, force: true });
});

function redoclyLint(path) {
  const pkg = requireWebModule.resolve('@redocly/cli/package.json');
  const cli = join(dirname(pkg), JSON.parse(readFileSync(pkg)).bin.redocly);
  return spawnSync(process.execPath, [cli, 'lint', '--config', join(repo, 'proto-schemas/redocly.yaml'), '--format', 'stylish', path],
                   { encoding: 'utf8', env: { ...process.env, REDOCLY_TELEMETRY: 'off', REDOCLY_SUPPRESS_UPDATE_NOTICE: 'true' } });
}

// A binary STL of vertices `v` and triangles `f` (vertex indices).
function binaryStl(v, f) {
  const stl = Buffer.alloc(84 + 50 * f.length);
  stl.writeUInt32LE(f.length, 80);
  f.forEach((t, i) => t.forEach((k, c) => v[k].forEach((x, a) => stl.writeFloatLE(x, 84 + 50 * i + 12 + 12 * c + 4 * a))));
  return stl;
}

// Submits the mesh as a client does and waits for the job to succeed.
async function finishedJob(mesh, filename, params) {
  const form = new FormData();
  form.append('mesh', new Blob([mesh]), filename);
  form.append('params', JSON.stringify(params));
  const submitted = await (await fetch(`${server.base}/v1/jobs`, { method: 'POST', body: form })).json();
  let job = submitted;
  for (let i = 0; i < 600 && !['succeeded', 'failed', 'cancelled'].includes(job.state); ++i) {
    await new Promise((r) => setTimeout(r, 50));
    job = await (await fetch(`${server.base}/v1/jobs/${submitted.id}`)).json();
  }
  assert.equal(job.state, 'succeeded', JSON.stringify(job));
  return job;
}

const operations = (doc) => Object.entries(doc.paths).flatMap(([path, item]) =>
  Object.entries(item).filter(([method]) => method !== 'parameters').map(([method, op]) => ({ method, path, op })));

test('every operation has one tag of the document\'s list, so /docs groups them', () => {
  const names = served.tags.map((t) => t.name);
  assert.ok(names.length >= 4);
  for (const { method, path, op } of operations(served)) {
    assert.equal(op.tags?.length, 1, `${method} ${path}`);
    assert.ok(names.includes(op.tags[0]), `${method} ${path}: ${op.tags[0]}`);
  }
  for (const name of names) assert.ok(operations(served).some(({ op }) => op.tags[0] === name), `tag ${name} is unused`);
});

test('the served document has no $ref outside itself', () => {
  const refs = JSON.stringify(served).match(/"\$ref":"[^"]*"/g);
  assert.ok(refs.length > 100);
  for (const ref of refs) assert.match(ref, /^"\$ref":"#\//, ref);
});

test('redocly lint (recommended rules) passes the served document with no warning', () => {
  const r = redoclyLint(servedPath);
  assert.equal(r.status, 0, r.stdout + r.stderr);
  assert.match(r.stdout + r.stderr, /Your API description is valid/);
  assert.doesNotMatch(r.stdout + r.stderr, /warning/i);
});

test('redocly lint passes the repository document, its schema files resolved beside it', () => {
  const r = redoclyLint(join(repo, 'proto-schemas/openapi.json'));
  assert.equal(r.status, 0, r.stdout + r.stderr);
  assert.doesNotMatch(r.stdout + r.stderr, /warning/i);
});

test('swagger-parser validates the served document and resolves every operation', async () => {
  const SwaggerParser = requireWebModule('@apidevtools/swagger-parser');
  const api = await SwaggerParser.validate(servedPath);
  assert.deepEqual(Object.keys(api.paths).sort(), Object.keys(served.paths).sort());
  // Dereferenced: the job parameters inside the submit operation are the schema itself.
  const multipart = api.paths['/v1/jobs'].post.requestBody.content['multipart/form-data'].schema;
  assert.ok(multipart.properties.params.properties.grid, 'params is dereferenced to the job-params schema');
});

test('/docs renders every operation of the served document, offline', async () => {
  const browser = await launchChromium();
  try {
    const page = await browser.newPage();
    // Whatever asks another host must be refused by the browser itself (the
    // page's Content-Security-Policy), not just fail for want of a network.
    const elsewhere = [];
    const local = (url) => url.startsWith(server.base) || url.startsWith('data:') || url.startsWith('blob:');
    page.on('requestfinished', (req) => { if (!local(req.url())) elsewhere.push(`${req.url()} was fetched`); });
    page.on('requestfailed', (req) => {
      if (!local(req.url()) && !/^csp$|BLOCKED_BY_CSP/.test(req.failure()?.errorText ?? '')) elsewhere.push(`${req.url()}: ${req.failure()?.errorText}`);
    });
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    const res = await page.goto(`${server.base}/docs`);
    assert.equal(res.status(), 200);
    assert.match(res.headers()['content-security-policy'], /default-src 'self'/);
    await page.waitForSelector('h1', { timeout: 60000 });
    const text = await page.evaluate(() => document.body.innerText);
    assert.match(text, new RegExp(served.info.title));
    for (const { method, path, op } of operations(served))
      assert.ok(text.includes(op.summary), `${method.toUpperCase()} ${path}: "${op.summary}" is not on the page`);
    assert.deepEqual(elsewhere, [], 'the reference page asked another host');
    assert.deepEqual(errors, []);
  } finally {
    await browser.close();
  }
});

test('a palette job\'s glb passes the Khronos glTF validator, its model turned Y-up', async () => {
  const validator = requireWebModule('gltf-validator');
  // A 2 x 3 x 5 box, tallest along the model's z.
  const v = [[0, 0, 0], [2, 0, 0], [2, 3, 0], [0, 3, 0], [0, 0, 5], [2, 0, 5], [2, 3, 5], [0, 3, 5]];
  const f = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [2, 3, 7], [2, 7, 6], [1, 2, 6], [1, 6, 5], [3, 0, 4], [3, 4, 7]];
  const params = { mode: 'palette', grid: { resolution: 10 }, palette: { elements: 10, rays: 4, points: 2, seed: 1 } };
  const job = await finishedJob(binaryStl(v, f), 'box.stl', params);
  const res = await fetch(`${server.base}/v1/jobs/${job.id}/volume?format=glb`);
  assert.equal(res.status, 200);
  const glb = new Uint8Array(await res.arrayBuffer());
  const report = await validator.validateBytes(glb);
  assert.equal(report.issues.numErrors, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
  assert.equal(report.issues.numWarnings, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
  // The scene's root turns model +z to glTF +y: the part's height (5) is
  // along y, its depth (3) along z.
  const gltf = JSON.parse(Buffer.from(glb.subarray(20, 20 + Buffer.from(glb).readUInt32LE(12))).toString());
  const root = gltf.nodes[gltf.scenes[gltf.scene].nodes[0]];
  const [x, y, z, w] = root.rotation;
  const turn = ([px, py, pz]) => {  // q p q*, for a unit quaternion
    const tx = 2 * (y * pz - z * py), ty = 2 * (z * px - x * pz), tz = 2 * (x * py - y * px);
    return [px + w * tx + (y * tz - z * ty), py + w * ty + (z * tx - x * tz), pz + w * tz + (x * ty - y * tx)];
  };
  const extent = turn([2, 3, 5]).map((c) => Math.round(Math.abs(c) * 1e6) / 1e6);
  assert.deepEqual(extent, [2, 5, 3]);
});

test('a solid\'s voxel surface and an sdf\'s zero level set as glb pass the Khronos glTF validator', async () => {
  const validator = requireWebModule('gltf-validator');
  // A hollow box (walls 1 thick): a closed outer and inner sheet.
  const box = (lo, hi, flip) => {
    const v = [[lo, lo, lo], [hi, lo, lo], [hi, hi, lo], [lo, hi, lo], [lo, lo, hi], [hi, lo, hi], [hi, hi, hi], [lo, hi, hi]];
    const f = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [2, 3, 7], [2, 7, 6], [1, 2, 6], [1, 6, 5], [3, 0, 4], [3, 4, 7]];
    return { v, f: flip ? f.map(([a, b, c]) => [a, c, b]) : f };
  };
  const outer = box(0, 6, false), inner = box(1, 5, true);
  const mesh = binaryStl([...outer.v, ...inner.v], [...outer.f, ...inner.f.map((t) => t.map((i) => i + 8))]);
  for (const mode of ['solid', 'sdf']) {
    const job = await finishedJob(mesh, 'hollow.stl', { mode, grid: { resolution: 24 } });
    const res = await fetch(`${server.base}/v1/jobs/${job.id}/volume?format=glb`);
    assert.equal(res.status, 200, await res.clone().text());
    assert.equal(res.headers.get('content-type'), 'model/gltf-binary');
    const report = await validator.validateBytes(new Uint8Array(await res.arrayBuffer()));
    assert.equal(report.issues.numErrors, 0, `${mode}: ${JSON.stringify(report.issues.messages.slice(0, 5))}`);
    assert.equal(report.issues.numWarnings, 0, `${mode}: ${JSON.stringify(report.issues.messages.slice(0, 5))}`);
    assert.ok(Number(res.headers.get('x-voxd-mesh-triangles')) > 0);
  }
});

test('the thickness on the part passes the glTF validator and opens in three.js with the PLY\'s values and colours', async () => {
  const validator = requireWebModule('gltf-validator');
  // A plate 10 x 8 x 1 in z: every vertex bounds the 1-thick wall.
  const v = [[0, 0, 0], [10, 0, 0], [10, 8, 0], [0, 8, 0], [0, 0, 1], [10, 0, 1], [10, 8, 1], [0, 8, 1]];
  const f = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [2, 3, 7], [2, 7, 6], [1, 2, 6], [1, 6, 5], [3, 0, 4], [3, 4, 7]];
  const job = await finishedJob(binaryStl(v, f), 'plate.stl', { grid: { voxel_size: 0.1, padding: 1 } });
  const get = async (format) => {
    const res = await fetch(`${server.base}/v1/jobs/${job.id}/thickness?format=${format}&min_wall=0.8&max_wall=2`);
    assert.equal(res.status, 200, await res.clone().text());
    return res;
  };
  const glbRes = await get('glb');
  assert.equal(glbRes.headers.get('content-type'), 'model/gltf-binary');
  const glb = new Uint8Array(await glbRes.arrayBuffer());
  const report = await validator.validateBytes(glb);
  assert.equal(report.issues.numErrors, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
  assert.equal(report.issues.numWarnings, 0, JSON.stringify(report.issues.messages.slice(0, 5)));
  assert.equal(report.issues.numInfos, 0, JSON.stringify(report.issues.messages.slice(0, 5)));

  // The PLY of the same job: 8 vertices of x y z thickness (floats) and r g b.
  const ply = Buffer.from(await (await get('ply')).arrayBuffer());
  const body = ply.indexOf('end_header\n') + 11;
  const plyValues = [], plyColours = [];
  for (let i = 0; i < 8; ++i) {
    plyValues.push(ply.readFloatLE(body + 19 * i + 12));
    plyColours.push([16, 17, 18].map((o) => ply[body + 19 * i + o]));
  }
  const json = await (await get('json')).json();
  assert.deepEqual(json.thickness.map((t) => Math.fround(t)), plyValues);
  for (const t of plyValues) assert.ok(Math.abs(t - 1) <= 0.1, `vertex reads ${t}, the wall is 1 (one voxel: 0.1)`);
  assert.equal(json.vertices, 8);
  assert.equal(json.unresolved, 0);

  // three.js reads the colours and the values as its own attributes.
  const { GLTFLoader } = await import(requireWebModule.resolve('three/examples/jsm/loaders/GLTFLoader.js'));
  const gltf = await new GLTFLoader().parseAsync(glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength), '');
  let mesh;
  gltf.scene.traverse((o) => { if (o.isMesh) mesh = o; });
  assert.ok(mesh.material.vertexColors, 'the material shows vertex colours');
  assert.deepEqual(Array.from(mesh.geometry.attributes._thickness.array), plyValues);
  const linear = (c) => { const s = c / 255; return s <= 0.04045 ? s / 12.92 : ((s + 0.055) / 1.055) ** 2.4; };
  const colours = mesh.geometry.attributes.color.array;
  plyColours.forEach((rgb, i) => rgb.forEach((c, k) => assert.ok(Math.abs(colours[3 * i + k] - linear(c)) < 1e-6)));
});
