// Liao's interaction in real headless Chromium against a real `voxd serve`:
// a solid job at 512^3 opened in the page, its "Slice function" tab shows a
// section and a view coloured by a marble function; dragging the period's
// slider updates them (the test measures and prints the updates a second,
// the "at least 10 times a second"); the pictures left after the
// drag are the last options' (no stale update wins); and "Make the coloured
// volume" makes a slice job whose volume has the CLI's bytes for the same
// options, and whose own section shows the editor's last section pixel for
// pixel. Screenshots go to $VOXD_TEST_ARTIFACTS.
//   node tests/web/slice_editor_test.mjs   (VOXD_BINARY=path/to/voxd)
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

import { binaryStl, tubeTriangles } from './test_meshes.mjs';
import { repo, runPageTest, voxdBinary } from './voxd_server.mjs';

const artifacts = process.env.VOXD_TEST_ARTIFACTS || join(repo, 'build/test-artifacts/slice-editor');
rmSync(artifacts, { recursive: true, force: true });
mkdirSync(artifacts, { recursive: true });
const work = mkdtempSync(join(tmpdir(), 'voxd-slice-editor-'));
const meshPath = join(work, 'ring.stl');
writeFileSync(meshPath, binaryStl(tubeTriangles(20, 13, 24, 160, 6)));

// The pixels of an <img> of the page, or of a URL loaded into one.
const pixelsOf = (page, selectorOrUrl) => page.evaluate(async (s) => {
  let img;
  if (s.startsWith('#')) {
    img = document.querySelector(s);
  } else {
    img = new Image();
    img.src = s;
  }
  await img.decode();
  const c = Object.assign(document.createElement('canvas'), { width: img.naturalWidth, height: img.naturalHeight });
  const ctx = c.getContext('2d');
  ctx.drawImage(img, 0, 0);
  return { width: c.width, height: c.height, data: Array.from(ctx.getImageData(0, 0, c.width, c.height).data) };
}, selectorOrUrl);

await runPageTest(work, async (browser, base) => {
  const page = await (await browser.newContext({ viewport: { width: 1400, height: 1100 } })).newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`${base}/`);
  await page.waitForFunction(() => document.querySelectorAll('#mode option').length > 0);
  await page.selectOption('#mode', 'solid');
  await page.fill('#resolution', '512');
  await page.uncheck('#want-report');
  await page.uncheck('#want-radiography');
  await page.setInputFiles('#mesh-file', meshPath);
  await page.click('#submit');
  await page.waitForFunction(() => document.getElementById('job-state').textContent === 'succeeded', null, { timeout: 300000 });
  const solidId = await page.$eval('#job-id', (e) => e.textContent);
  const solid = await (await fetch(`${base}/v1/jobs/${solidId}`)).json();
  assert.equal(Math.max(...solid.grid.dims), 512);

  // The tab opens with marble on the part: a first update.
  await page.click('button[data-tab=slice]');
  await page.waitForFunction(() => Number(document.getElementById('slice-timing').dataset.updates) >= 1 ||
                                   !document.getElementById('problem').hidden, null, { timeout: 60000 });
  assert.ok(await page.$eval('#problem', (e) => e.hidden), await page.$eval('#problem', (e) => e.textContent));
  assert.equal(await page.$eval('[data-option=function]', (e) => e.value), 'marble');
  await page.screenshot({ path: join(artifacts, '01-marble.png'), fullPage: true });

  // The other tabs' pictures (six previews, the 3D view) are made by now.
  await page.waitForLoadState('networkidle');
  // Drag the period's slider across, for about three seconds.
  const slider = page.locator('input.drag[data-drags=period]');
  const box = await slider.boundingBox();
  const before = Number(await page.$eval('#slice-timing', (e) => e.dataset.updates));
  const started = Date.now();
  await page.mouse.move(box.x + 2, box.y + box.height / 2);
  await page.mouse.down();
  const moves = 60;
  for (let i = 1; i <= moves; ++i) {
    await page.mouse.move(box.x + 2 + (box.width - 4) * i / moves, box.y + box.height / 2);
    await page.waitForTimeout(50);
  }
  await page.mouse.up();
  const seconds = (Date.now() - started) / 1000;
  const during = Number(await page.$eval('#slice-timing', (e) => e.dataset.updates)) - before;
  const views = Number(await page.$eval('#slice-view-timing', (e) => e.dataset.updates));
  console.log(`dragging the period over ${seconds.toFixed(1)} s: ${during} section updates, ${(during / seconds).toFixed(1)} a ` +
              `second (the last took ${await page.$eval('#slice-timing', (e) => e.dataset.lastMs)} ms); ${views} views in all`);
  // The requests' own times, as the browser saw them (the rest of an update
  // is the page decoding and drawing the pictures).
  const requests = await page.evaluate(() => performance.getEntriesByType('resource')
    .filter((e) => /\/section\?.*colour=slice/.test(e.name)).map((e) => ({ url: e.name, ms: e.duration })));
  const fetched = requests.map((r) => r.ms).sort((a, b) => a - b);
  console.log(`the section requests took ${fetched[Math.floor(fetched.length / 2)].toFixed(0)} ms (median of ${fetched.length})`);
  assert.ok(during >= 3, `only ${during} updates while dragging`);
  assert.ok(during <= moves + 1, `updates are not coalesced: ${during} for ${moves} slider moves`);
  // A drag step reaches the editor more than once (the slider's input, the
  // form's input and change); a section already shown is not asked for
  // again, however slow the service (CI's 2 cores are).
  const repeated = requests.filter((r, i) => i > 0 && r.url === requests[i - 1].url).length;
  assert.equal(repeated, 0, `${repeated} section requests repeat the one before`);

  // Settled: the pictures are the last options', as the API gives them,
  // and no value the slider reached was refused.
  await page.waitForTimeout(1500);
  assert.ok(await page.$eval('#problem', (e) => e.hidden), await page.$eval('#problem', (e) => e.textContent));
  const period = Number(await page.$eval('[data-option=period]', (e) => e.value));
  assert.ok(period > 0.4 * 0.5 * 512 * solid.grid.voxel_size, `period ${period}: the slider did not reach its far end`);
  const last = await page.evaluate(() => ({
    options: JSON.parse(decodeURIComponent(document.getElementById('slice-section').dataset.slice)),
    index: Number(document.getElementById('slice-index').value) }));
  assert.equal(last.options.period, period);
  const shown = await pixelsOf(page, '#slice-section');
  const query = `axis=z&index=${last.index}&colour=slice&slice=${encodeURIComponent(JSON.stringify(last.options))}`;
  const direct = await pixelsOf(page, `${base}/v1/jobs/${solidId}/section?${query}`);
  assert.equal(shown.width, solid.grid.dims[0]);
  assert.ok(shown.data.every((v, i) => v === direct.data[i]), 'the section shown is not the last options\'');
  // One more function, asked alone (no drag, no pictures being drawn): the
  // request's time when the browser is idle.
  const alone = await page.evaluate(async (url) => {
    const t0 = performance.now();
    await (await fetch(url)).blob();
    return performance.now() - t0;
  }, `${base}/v1/jobs/${solidId}/section?axis=z&index=${last.index}&colour=slice&slice=` +
     encodeURIComponent(JSON.stringify({ ...last.options, period: last.options.period / 3 })));
  console.log(`a section asked alone took ${alone.toFixed(0)} ms`);
  await page.screenshot({ path: join(artifacts, '02-dragged.png'), fullPage: true });

  // The coloured volume: a slice job of the same mesh and grid, the CLI's bytes.
  await page.click('#slice-make');
  await page.waitForFunction((s) => document.getElementById('job-id').textContent !== s, solidId);
  await page.waitForFunction(() => document.getElementById('job-state').textContent === 'succeeded', null, { timeout: 300000 });
  const madeId = await page.$eval('#job-id', (e) => e.textContent);
  const made = await (await fetch(`${base}/v1/jobs/${madeId}`)).json();
  assert.equal(made.params.mode, 'slice');
  assert.deepEqual(made.params.slice, last.options);
  assert.deepEqual(made.grid, solid.grid);
  const volume = Buffer.from(await (await fetch(`${base}/v1/jobs/${madeId}/volume?format=rle`)).arrayBuffer());
  const cliOut = join(work, 'cli.rle');
  execFileSync(voxdBinary, ['voxelize', meshPath, '-o', cliOut, '--resolution', '512', '--mode', 'slice',
                            '--params', JSON.stringify({ slice: last.options })]);
  assert.ok(volume.equals(readFileSync(cliOut)), `the slice job's ${volume.length} bytes differ from the CLI's`);
  const itsSection = await pixelsOf(page, `${base}/v1/jobs/${madeId}/section?axis=z&index=${last.index}`);
  assert.ok(shown.data.every((v, i) => v === itsSection.data[i]), 'the slice job\'s section differs from the editor\'s');
  await page.screenshot({ path: join(artifacts, '03-made.png'), fullPage: true });

  assert.ok(await page.$eval('#problem', (e) => e.hidden), await page.$eval('#problem', (e) => e.textContent));
  assert.deepEqual(errors, []);
  console.log(`slice editor test passed; screenshots in ${artifacts}`);
});
