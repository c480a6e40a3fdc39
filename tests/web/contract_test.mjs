// The contract as third-party tools see it: the OpenAPI document a real
// `voxd serve` answers at /openapi.json is linted by Redocly's recommended
// rules (proto-schemas/redocly.yaml) and validated by swagger-parser, both
// from web/package-lock.json; the repository's own document (whose schemas
// live in files beside it) lints clean too; and /docs renders every
// operation in headless Chromium without asking any other host for anything.
//   node --test tests/web/contract_test.mjs   (VOXD_BINARY=path/to/voxd)
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { after, before, test } from 'node:test';

import { repo, requireWebModule, startVoxd } from './voxd_server.mjs';

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

const operations = (doc) => Object.entries(doc.paths).flatMap(([path, item]) =>
  Object.entries(item).filter(([method]) => method !== 'parameters').map(([method, op]) => ({ method, path, op })));

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
  const { chromium } = requireWebModule('playwright-core');
  const browser = await chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
                                          args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader'] });
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
