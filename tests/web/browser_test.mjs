// The web page in real headless Chromium (Debian's chromium, driven by
// playwright-core from web/package-lock.json) against a real `voxd serve` on
// a loopback ephemeral port, as a person uses it: load /, upload a mesh,
// watch the progress bar reach done, see the 3D view drawn, switch the
// radiography's axis, open the report, download a volume and compare its
// bytes with the API's, and see a malformed upload's problem on the page.
// Screenshots of each step go to $VOXD_TEST_ARTIFACTS (default
// build/test-artifacts/browser).
//   node tests/web/browser_test.mjs   (VOXD_BINARY=path/to/voxd)
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { basename, join } from 'node:path';

import { binaryStl, boxTriangles } from './test_meshes.mjs';
import { repo, runPageTest, startVoxd } from './voxd_server.mjs';

const artifacts = process.env.VOXD_TEST_ARTIFACTS || join(repo, 'build/test-artifacts/browser');
rmSync(artifacts, { recursive: true, force: true });
mkdirSync(artifacts, { recursive: true });
const work = mkdtempSync(join(tmpdir(), 'voxd-browser-'));

// A hollow box, 20 x 16 x 12 with walls 2 thick: volume 3840 - 1536 = 2304.
const meshPath = join(work, 'hollow-box.stl');
writeFileSync(meshPath, binaryStl([...boxTriangles([0, 0, 0], [20, 16, 12], false), ...boxTriangles([2, 2, 2], [18, 14, 10], true)]));
// The same hollow box written inside out, with a hole in its top: the page
// says it was turned round, which inside test was chosen and why.
const outerInverted = boxTriangles([0, 0, 0], [20, 16, 12], true);
outerInverted.splice(2, 1);
const openInvertedPath = join(work, 'open-inside-out.stl');
writeFileSync(openInvertedPath, binaryStl([...outerInverted, ...boxTriangles([2, 2, 2], [18, 14, 10], false)]));
const badPath = join(work, 'broken.stl');
writeFileSync(badPath, 'solid broken\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0\n');

let step = 0;
async function shot(page, name) {
  await page.screenshot({ path: join(artifacts, `${String(++step).padStart(2, '0')}-${name}.png`), fullPage: true });
}

// Pixels of the 3D canvas unlike its clear colour (#fafbfd).
const drawnPixels = (page) => page.evaluate(() => {
  const gl = document.querySelector('#viewer canvas');
  const c = Object.assign(document.createElement('canvas'), { width: gl.width, height: gl.height });
  const ctx = c.getContext('2d');
  ctx.drawImage(gl, 0, 0);
  const d = ctx.getImageData(0, 0, c.width, c.height).data;
  let n = 0;
  for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 250) + Math.abs(d[i + 1] - 251) + Math.abs(d[i + 2] - 253) > 12) ++n;
  return { drawn: n, total: d.length / 4 };
});

await runPageTest(work, async (browser, base) => {
  const context = await browser.newContext({ viewport: { width: 1400, height: 1000 }, acceptDownloads: true });
  const page = await context.newPage();
  const consoleErrors = [];
  page.on('pageerror', (e) => consoleErrors.push(String(e)));

  // 1. The page loads, with the form made from the job schema.
  await page.goto(`${base}/`);
  await page.waitForFunction(() => document.querySelectorAll('#mode option').length > 0);
  const modes = await page.$$eval('#mode option', (o) => o.map((x) => x.value));
  assert.deepEqual(modes, JSON.parse(readFileSync(join(repo, 'proto-schemas/job-params.schema.json'))).properties.mode.enum);
  await shot(page, 'loaded');
  // What the page moved over the wire, by the browser's own timings: the
  // first load compressed, a second load only revalidations (304s).
  const transferred = () => page.evaluate(() => [...performance.getEntriesByType('navigation'),
    ...performance.getEntriesByType('resource')].reduce((sum, e) => sum + e.transferSize, 0));
  const firstLoad = await transferred();
  // Reported, not asserted (times are for benchmarks): docs/benchmarks.md.
  const firstReady = await page.evaluate(() => performance.getEntriesByType('navigation')[0].domContentLoadedEventEnd);
  const failedRequests = [];
  page.on('requestfailed', (r) => failedRequests.push(r.url()));
  page.on('response', (r) => { if (r.status() >= 400) failedRequests.push(`${r.status()} ${r.url()}`); });
  await page.reload();
  await page.waitForFunction(() => document.querySelectorAll('#mode option').length > 0);
  await page.waitForLoadState('networkidle');
  const secondLoad = await transferred();
  assert.ok(secondLoad < 50 * 1024, `the second load moved ${secondLoad} bytes (the first ${firstLoad})`);
  assert.ok(firstLoad < 1024 * 1024, `the first load moved ${firstLoad} bytes: are the files compressed?`);
  const secondReady = await page.evaluate(() => performance.getEntriesByType('navigation')[0].domContentLoadedEventEnd);
  console.log(`page loads: the first moved ${firstLoad} bytes (DOMContentLoaded at ${firstReady.toFixed(0)} ms), ` +
              `the second ${secondLoad} (${secondReady.toFixed(0)} ms)`);

  // 2. Upload the mesh with a job, and follow its progress bar to done.
  await page.setInputFiles('#mesh-file', meshPath);
  await page.fill('#resolution', '80');
  await page.fill('#min-wall', '1');
  await page.evaluate(() => {
    window.progressSeen = [];
    new MutationObserver(() => window.progressSeen.push(parseFloat(document.getElementById('progress-bar').style.width)))
      .observe(document.getElementById('progress-bar'), { attributes: true });
  });
  await page.click('#submit');
  await page.waitForFunction(() => document.getElementById('job-state').textContent === 'succeeded', null, { timeout: 120000 });
  assert.equal(await page.$eval('#progress-bar', (e) => e.style.width), '100%');
  const seen = await page.evaluate(() => window.progressSeen);
  for (let i = 1; i < seen.length; ++i) assert.ok(seen[i] >= seen[i - 1], `progress went back: ${seen.join(', ')}`);
  assert.equal(await page.isVisible('#problem'), false, 'a problem box is shown for a job that succeeded');
  // Both analyses the job asked for were announced by the event stream.
  assert.equal(await page.$eval('#analyses-ready', (e) => e.textContent), 'analysis ready · radiography ready · ');
  const jobId = await page.$eval('#job-id', (e) => e.textContent);
  assert.match(jobId, /^[0-9a-f]{32}$/);
  await shot(page, 'done');

  // 3. The 3D view shows the part painted by wall thickness (the job asked
  // for the report; wall_view_test.mjs checks the colours), and the voxels
  // on request (a real picture, not a blank canvas).
  await page.waitForFunction(() => /^wall thickness on the part/.test(document.getElementById('view-info').textContent),
                             null, { timeout: 60000 });
  const paintedPixels = await drawnPixels(page);
  assert.ok(paintedPixels.drawn > paintedPixels.total * 0.02, `painted part nearly blank: ${paintedPixels.drawn} drawn`);
  await shot(page, 'view3d-wall-thickness');
  await page.selectOption('#view-source', 'voxels');
  await page.waitForFunction(() => /filled voxels/.test(document.getElementById('view-info').textContent), null, { timeout: 60000 });
  const pixels = await drawnPixels(page);
  assert.ok(pixels.drawn > pixels.total * 0.02, `3D view nearly blank: ${pixels.drawn} of ${pixels.total} pixels drawn`);
  await shot(page, 'view3d');

  // 4. Radiography: switching the axis changes the map; the readout is in model units.
  await page.click('button[data-tab=radiography]');
  await page.waitForFunction(() => document.getElementById('rad-canvas').width > 0);
  const image = () => page.$eval('#rad-canvas', (c) => ({ w: c.width, h: c.height, url: c.toDataURL() }));
  const alongZ = await image();
  const box = await page.locator('#rad-canvas').boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  const readout = await page.$eval('#rad-readout', (e) => e.textContent);
  // Through the middle, along z, the thickest run of material is a 2-thick wall.
  const value = Number(/max ([0-9.]+)/.exec(readout)[1]);
  assert.ok(Math.abs(value - 2) <= 0.5, `readout ${readout}`);
  await shot(page, 'radiography-z');
  await page.selectOption('#rad-axis', 'x');
  await page.waitForFunction((before) => document.getElementById('rad-canvas').toDataURL() !== before, alongZ.url);
  const alongX = await image();
  assert.notEqual(alongX.url, alongZ.url);
  const job = await (await fetch(`${base}/v1/jobs/${jobId}`)).json();
  const [nx, ny, nz] = job.grid.dims;
  assert.deepEqual([alongZ.w, alongZ.h], [nx, ny]);
  assert.deepEqual([alongX.w, alongX.h], [ny, nz]);
  await shot(page, 'radiography-x');

  // 5. The report: the voxel volume is the box's, within a voxel layer.
  await page.click('button[data-tab=report]');
  await page.waitForSelector('#report table');
  const volumeText = await page.$eval('#report table tbody tr td:nth-child(2)', (e) => e.textContent);
  assert.ok(Math.abs(Number(volumeText) - 2304) / 2304 < 0.05, `volume ${volumeText}`);
  assert.match(await page.$eval('#report', (e) => e.textContent), /Wall thickness/);
  // The mesh is watertight, in words; the void (8192 voxels) hides under a
  // larger size and shows again.
  assert.match(await page.$eval('#report .mesh-status', (e) => e.textContent), /^the mesh is watertight/);
  const voidRows = () => page.$$eval('#report tr.region', (rows) => rows.filter((r) => !r.hidden).length);
  const allRows = await voidRows();
  await page.fill('#void-min-voxels', '100000');
  assert.equal(await voidRows(), allRows - 1, 'the void is not hidden by the size filter');
  assert.match(await page.$eval('#voids-shown', (e) => e.textContent), /^0 of 1 listed shown/);
  await page.fill('#void-min-voxels', '0');
  assert.equal(await voidRows(), allRows);
  // A solid's sections and previews are coloured by thickness, never by
  // distance (which only an sdf job has).
  assert.deepEqual(await page.$$eval('#sec-colour option', (o) => o.map((x) => x.value)), ['none', 'thickness']);
  assert.deepEqual(await page.$$eval('#prev-colour option', (o) => o.map((x) => x.value)), ['none', 'thickness']);
  await shot(page, 'report');
  // The report to send: one HTML file (the verdict, the inputs, the
  // pictures inline), printed to PDF by Chromium: pages, and the verdict in
  // the PDF's text (poppler's pdfinfo and pdftotext read it).
  const [reportDownload] = await Promise.all([page.waitForEvent('download'), page.click('#download-report')]);
  assert.equal(reportDownload.suggestedFilename(), 'hollow-box-report.html');
  const reportHtml = readFileSync(await reportDownload.path(), 'utf8');
  const apiReport = await (await fetch(`${base}/v1/jobs/${jobId}/analysis?min_wall=1`)).json();
  const verdictWord = apiReport.thickness.verdict;
  assert.match(reportHtml, new RegExp(`<span class="verdict ${verdictWord}">${verdictWord}</span>`));
  assert.ok((reportHtml.match(/src="data:image\/png;base64,/g) || []).length >= 3, 'the report has its pictures inline');
  assert.ok(!/src="(https?:)?\/\//.test(reportHtml) && !/<script/.test(reportHtml), 'the report needs nothing else');
  const printed = await context.newPage();
  await printed.setContent(reportHtml);
  await printed.screenshot({ path: join(artifacts, `${String(++step).padStart(2, '0')}-report-html.png`), fullPage: true });
  const pdfPath = join(artifacts, 'report.pdf');
  await printed.pdf({ path: pdfPath, format: 'A4' });
  await printed.close();
  const pdfPages = Number(/Pages:\s+(\d+)/.exec(execFileSync('pdfinfo', [pdfPath], { encoding: 'utf8' }))[1]);
  assert.ok(pdfPages >= 1, `the PDF has ${pdfPages} pages`);
  const pdfText = execFileSync('pdftotext', [pdfPath, '-'], { encoding: 'utf8' });
  assert.match(pdfText, /Wall thickness verdict/);
  assert.match(pdfText, new RegExp(`\\b${verdictWord}\\b`));
  assert.match(pdfText, /hollow-box\.stl/);
  // A region's row shows its box in the 3D view.
  const before3d = await page.$eval('#viewer canvas', (c) => c.toDataURL());
  await page.click('#report tr.region >> nth=1');  // the void inside the box
  await page.waitForSelector('#tab-view3d:not([hidden])');
  assert.notEqual(await page.$eval('#viewer canvas', (c) => c.toDataURL()), before3d, 'the region box was not drawn');
  await shot(page, 'region-in-3d');

  assert.equal(await page.isVisible('#slice-tab'), true, 'a solid job offers no slice function tab');
  // 6. Sections: the slider moves through the part.
  await page.click('button[data-tab=sections]');
  await page.waitForFunction(() => document.getElementById('sec-image').complete && document.getElementById('sec-image').naturalWidth > 0);
  await shot(page, 'section');

  // 7. A download has the API's bytes.
  await page.click('button[data-tab=downloads]');
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#downloads a[data-format=rle]')]);
  const downloaded = readFileSync(await download.path());
  const fromApi = Buffer.from(await (await fetch(`${base}/v1/jobs/${jobId}/volume?format=rle`)).arrayBuffer());
  assert.ok(downloaded.length > 0);
  assert.ok(downloaded.equals(fromApi), `downloaded ${downloaded.length} bytes differ from the API's ${fromApi.length}`);
  await shot(page, 'downloads');

  // 8. A distance field's job shows its zero level set (surface nets), and
  // says where its band was computed: on the CPU asked for (the form sends
  // the device chosen).
  await page.selectOption('#mode', 'sdf');
  assert.ok(await page.isVisible('#device'), 'no device offered for sdf');
  await page.selectOption('#device', 'cpu');
  await page.fill('#resolution', '48');
  await page.uncheck('#want-report');
  await page.uncheck('#want-radiography');
  await page.setInputFiles('#mesh-file', meshPath);
  await page.click('#submit');
  await page.waitForFunction((before) => document.getElementById('job-id').textContent !== before, jobId);
  await page.waitForFunction(() => document.getElementById('job-state').textContent === 'succeeded', null, { timeout: 120000 });
  const sdfStatus = await (await fetch(`${base}/v1/jobs/${await page.$eval('#job-id', (e) => e.textContent)}`)).json();
  assert.equal(sdfStatus.params.device, 'cpu');
  await page.waitForFunction(() => document.getElementById('job-device').textContent === 'computed on: cpu');
  await page.click('button[data-tab=view3d]');
  await page.waitForFunction(() => /zero level set: \d+ triangles/.test(document.getElementById('view-info').textContent),
                             null, { timeout: 60000 });
  // Closed and facing out: it encloses the box's 2304 (its edges rounded).
  const enclosed = Number(/enclosing ([0-9.e+]+)/.exec(await page.$eval('#view-info', (e) => e.textContent))[1]);
  assert.ok(Math.abs(enclosed - 2304) / 2304 < 0.05, `the zero level set encloses ${enclosed}`);
  const sdfPixels = await drawnPixels(page);
  assert.ok(sdfPixels.drawn > sdfPixels.total * 0.02, `zero level set nearly blank: ${sdfPixels.drawn} drawn`);
  await shot(page, 'sdf-zero-level-set');
  assert.deepEqual(await page.$$eval('#sec-colour option', (o) => o.map((x) => x.value)), ['none', 'distance']);
  // A distance field has no solid to colour by a slice function (a solid's can: slice_editor_test.mjs).
  assert.equal(await page.isVisible('#slice-tab'), false, 'the slice function tab is offered for an sdf job');
  // ... and its sections open coloured by distance, with a legend.
  assert.equal(await page.$eval('#sec-colour', (e) => e.value), 'distance');

  // 8b. Every mode the form offers submits as the form fills it in and
  // succeeds (palette and coverage take no inside test; slice's options
  // offer no function the form cannot give).
  await page.uncheck('#want-report');
  await page.uncheck('#want-radiography');
  await page.fill('#resolution', '16');
  for (const mode of modes) {
    await page.selectOption('#mode', mode);
    assert.equal(await page.$eval('#inside', (e) => e.disabled), mode === 'coverage' || mode === 'palette', mode);
    // A device only where a GPU could do the work (JobMode::runs_on_gpu).
    assert.equal(await page.isVisible('#device'), ['coverage', 'sdf', 'slice'].includes(mode), mode);
    if (mode === 'slice')  // custom takes its lookup from an uploaded image
      assert.ok((await page.$$eval('#mode-options select option', (o) => o.map((x) => x.value))).includes('custom'));
    await page.setInputFiles('#mesh-file', meshPath);
    const before = await page.$eval('#job-id', (e) => e.textContent);
    await page.click('#submit');
    await page.waitForFunction((b) => document.getElementById('job-id').textContent !== b ||
                                      !document.getElementById('problem').hidden, before);
    assert.ok(await page.$eval('#problem', (e) => e.hidden),
              `${mode}: ${await page.$eval('#problem-detail', (e) => e.textContent)}`);
    await page.waitForFunction(() => document.getElementById('job-state').textContent === 'succeeded', null, { timeout: 120000 });
  }
  await shot(page, 'every-mode');
  // 8c. Options beyond enums and numbers: a slice's colour ramp from two
  // colour inputs, a custom lookup from an uploaded image (its pixels are
  // the part's only colours), an sdf's band as a word.
  const submitted = async () => {
    const before = await page.$eval('#job-id', (e) => e.textContent);
    await page.click('#submit');
    await page.waitForFunction((b) => document.getElementById('job-id').textContent !== b ||
                                      !document.getElementById('problem').hidden, before);
    assert.ok(await page.$eval('#problem', (e) => e.hidden), await page.$eval('#problem-detail', (e) => e.textContent));
    await page.waitForFunction(() => document.getElementById('job-state').textContent === 'succeeded', null, { timeout: 120000 });
    const id = await page.$eval('#job-id', (e) => e.textContent);
    return (await fetch(`${base}/v1/jobs/${id}`)).json();
  };
  await page.selectOption('#mode', 'slice');
  await page.selectOption('[data-option=function]', 'color_ramp');
  assert.equal(await page.isVisible('[data-option=color]'), false, 'single_color\'s colour shown for a ramp');
  const stops = page.locator('[data-option=ramp] input');
  await stops.nth(0).fill('#00ff00');
  await stops.nth(1).fill('#ff00ff');
  await page.setInputFiles('#mesh-file', meshPath);
  const ramp = await submitted();
  assert.deepEqual(ramp.params.slice.ramp.map((r) => r.color), [[0, 255, 0, 255], [255, 0, 255, 255]]);
  await page.selectOption('[data-option=function]', 'custom');
  const lookupPng = join(work, 'lookup.png');
  writeFileSync(lookupPng, Buffer.from(await page.evaluate(() => {
    const c = Object.assign(document.createElement('canvas'), { width: 2, height: 1 });
    const ctx = c.getContext('2d');
    ctx.fillStyle = '#ff0000'; ctx.fillRect(0, 0, 1, 1);
    ctx.fillStyle = '#0000ff'; ctx.fillRect(1, 0, 1, 1);
    return c.toDataURL('image/png').split(',')[1];
  }), 'base64'));
  await page.setInputFiles('[data-option=lookup]', lookupPng);
  await page.waitForFunction(() => document.querySelector('[data-option=lookup]').lookup !== undefined);
  await page.setInputFiles('#mesh-file', meshPath);
  const custom = await submitted();
  assert.deepEqual(custom.params.slice.lookup, { dims: [2, 1, 1], colors: [[255, 0, 0, 255], [0, 0, 255, 255]] });
  const rgba = new Uint8Array(await (await fetch(`${base}/v1/jobs/${custom.id}/volume?format=raw`)).arrayBuffer());
  const colours = new Set();
  for (let i = 0; i < rgba.length; i += 4) if (rgba[i + 3]) colours.add(`${rgba[i]},${rgba[i + 1]},${rgba[i + 2]}`);
  assert.deepEqual([...colours].sort(), ['0,0,255', '255,0,0']);
  await page.selectOption('#mode', 'sdf');
  await page.fill('[data-option=band]', 'full');
  await page.setInputFiles('#mesh-file', meshPath);
  assert.equal((await submitted()).params.sdf.band, 'full');
  await shot(page, 'options-beyond-enums');
  // Recent jobs: each by its file's name and its mode (a job submitted
  // without one is solid, never "undefined").
  const noMode = new FormData();
  noMode.append('mesh', new Blob([readFileSync(meshPath)]), 'no-mode.stl');
  assert.equal((await fetch(`${base}/v1/jobs`, { method: 'POST', body: noMode })).status, 202);
  await page.waitForFunction(() => [...document.querySelectorAll('#jobs li')].some((li) => li.textContent.includes('no-mode.stl')),
                             null, { timeout: 15000 });
  const listed = await page.$$eval('#jobs li', (l) => l.map((x) => x.textContent));
  assert.ok(listed.every((t) => !t.includes('undefined')), listed.join(' | '));
  assert.ok(listed.some((t) => t.includes('no-mode.stl') && t.includes(' solid ')), listed.join(' | '));
  assert.ok(listed.some((t) => t.includes(basename(meshPath)) && t.includes(' palette ')), listed.join(' | '));

  // 9. An open mesh written inside out: the warnings and the inside test
  // chosen from the mesh, from the job's status; the report's verdict with
  // a wall 0.1 over the limit (under a voxel of 0.25): inconclusive.
  await page.selectOption('#mode', 'solid');
  await page.fill('#resolution', '80');
  await page.check('#want-report');
  await page.fill('#min-wall', '1.9');
  await page.setInputFiles('#mesh-file', openInvertedPath);
  const sdfJob = await page.$eval('#job-id', (e) => e.textContent);
  await page.click('#submit');
  await page.waitForFunction((before) => document.getElementById('job-id').textContent !== before, sdfJob);
  await page.waitForFunction(() => document.getElementById('job-state').textContent === 'succeeded', null, { timeout: 120000 });
  const openJobId = await page.$eval('#job-id', (e) => e.textContent);
  const openStatus = await (await fetch(`${base}/v1/jobs/${openJobId}`)).json();
  assert.equal(openStatus.inside.test, 'winding');
  assert.equal(await page.$eval('#job-inside', (e) => e.textContent),
               `inside test: winding, chosen from the mesh: ${openStatus.inside.reason}`);
  const shown = await page.$$eval('#job-warnings li', (l) => l.map((x) => ({ code: x.dataset.code, message: x.textContent })));
  assert.deepEqual(shown, openStatus.warnings.map((w) => ({ code: w.code, message: w.message })));
  assert.ok(shown.some((w) => w.code === 'mesh-inverted'), JSON.stringify(shown));
  await page.click('button[data-tab=report]');
  await page.waitForSelector('#report .verdict.inconclusive');
  assert.match(await page.$eval('#report .decide', (e) => e.textContent), /^voxel size to decide: [0-9.]+ mm or smaller$/);
  // The cavity stayed a cavity: the box's 2304, within a voxel layer.
  const openVolume = Number(await page.$eval('#report table tbody tr td:nth-child(2)', (e) => e.textContent));
  assert.ok(Math.abs(openVolume - 2304) / 2304 < 0.05, `volume ${openVolume}`);
  await shot(page, 'open-inside-out');

  // 10. A malformed STL: the page shows the API's problem, title and detail.
  const form = new FormData();
  form.append('mesh', new Blob([readFileSync(badPath)]), 'broken.stl');
  form.append('params', new Blob([JSON.stringify({ grid: { resolution: 80 } })], { type: 'application/json' }));
  const refusal = await fetch(`${base}/v1/jobs`, { method: 'POST', body: form });
  assert.equal(refusal.status, 422);
  const problem = await refusal.json();
  await page.setInputFiles('#mesh-file', badPath);
  await page.click('#submit');
  await page.waitForSelector('#problem:not([hidden])');
  assert.equal(await page.$eval('#problem-title', (e) => e.textContent), problem.title);
  assert.equal(await page.$eval('#problem-detail', (e) => e.textContent), problem.detail);
  await shot(page, 'malformed-stl');

  // 11. A phone's width: the page, a job open in it, scrolls only down.
  await page.setViewportSize({ width: 390, height: 844 });
  await page.click('button[data-tab=report]');
  const width = await page.evaluate(() => document.documentElement.scrollWidth);
  assert.ok(width <= 390, `the page is ${width} px wide at a 390 px viewport`);
  await shot(page, 'phone-width');

  // 12. A service with API keys, opened without one: the page says where
  // the key goes, not the API's words; with a wrong key, that it is wrong.
  const keyed = await startVoxd(join(work, 'keyed'), ['--api-keys', 'right-key']);
  try {
    const visitor = await context.newPage();
    await visitor.goto(`${keyed.base}/`);
    await visitor.waitForSelector('#problem:not([hidden])');
    assert.equal(await visitor.$eval('#problem-title', (e) => e.textContent), 'This service needs an API key');
    assert.match(await visitor.$eval('#problem-detail', (e) => e.textContent), /API key box at the top right/);
    await visitor.fill('#api-key', 'wrong-key');
    await visitor.press('#api-key', 'Enter');
    await visitor.dispatchEvent('#api-key', 'change');
    await visitor.waitForFunction(() => document.getElementById('problem-title').textContent === 'This API key is not accepted');
    await visitor.screenshot({ path: join(artifacts, `${String(++step).padStart(2, '0')}-wrong-key.png`) });
    await visitor.evaluate(() => localStorage.clear());
    await visitor.close();
  } finally {
    keyed.child.kill('SIGTERM');
  }

  assert.deepEqual(consoleErrors, []);
  assert.deepEqual(failedRequests.filter((u) => !u.includes('broken') && !/\/v1\//.test(u)), [],
                   'no file of the page failed to load');
  console.log(`browser test passed; screenshots in ${artifacts}`);
});
