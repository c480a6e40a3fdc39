// The part painted by wall thickness, in real headless Chromium against a
// real `voxd serve`, checked on the canvas's pixels: a tube whose wall is
// 1.5 mm all round is painted only in bands that a reading of 1.5 within
// the error bound can fall in; a block with a 0.6 mm rib shows the rib in
// the thin colour, and the reading under the cursor there is the rib's.
// The pixels are told apart by their chromaticity in linear light (the
// view's lights are white, so shading scales a colour without turning it),
// each against the legend's chips. Screenshots go to $VOXD_TEST_ARTIFACTS.
//   node tests/web/wall_view_test.mjs   (VOXD_BINARY=path/to/voxd)
import assert from 'node:assert/strict';
import { mkdirSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

import { binaryStl, splitBoxTriangles, tubeTriangles } from './test_meshes.mjs';
import { repo, runPageTest } from './voxd_server.mjs';

const artifacts = process.env.VOXD_TEST_ARTIFACTS || join(repo, 'build/test-artifacts/wall-view');
rmSync(artifacts, { recursive: true, force: true });
mkdirSync(artifacts, { recursive: true });
const work = mkdtempSync(join(tmpdir(), 'voxd-wall-view-'));

const tubePath = join(work, 'tube-1.5mm.stl');
writeFileSync(tubePath, binaryStl(tubeTriangles(5, 3.5, 10)));
// A block 20 x 20 x 6 with a rib 0.6 thick and 6 tall standing on it (its
// foot 1 mm into the block: overlapping shells, voxelized by winding number).
const ribPath = join(work, 'block-with-rib.stl');
writeFileSync(ribPath, binaryStl([...splitBoxTriangles([0, 0, 0], [20, 20, 6], 1),
                                  ...splitBoxTriangles([2, 9.7, 5], [18, 10.3, 12], 0.6)]));

// Every pixel of the 3D view with the legend chip whose colour it is, by
// the angle between their linear-light RGB directions; pixels of the
// background, of lines and of blended edges match none.
const classifyPixels = (page) => page.evaluate(() => {
  const lin = (c) => (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4);
  const direction = (rgb) => {
    const l = rgb.map((c) => lin(c / 255));
    const n = Math.hypot(...l);
    return { d: l.map((x) => x / n), n };
  };
  const chips = [...document.querySelectorAll('#wall-legend .band')].map((e) => {
    const hex = e.dataset.colour;
    return { kind: e.dataset.kind, lo: Number(e.dataset.lo), hi: Number(e.dataset.hi),
             d: direction([1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16))).d };
  });
  const gl = document.querySelector('#viewer canvas');
  const c = Object.assign(document.createElement('canvas'), { width: gl.width, height: gl.height });
  const ctx = c.getContext('2d');
  ctx.drawImage(gl, 0, 0);
  const px = ctx.getImageData(0, 0, c.width, c.height).data;
  const counts = chips.map(() => 0);
  const where = chips.map(() => [0, 0]);
  let unmatched = 0, background = 0;
  for (let i = 0; i < px.length; i += 4) {
    const rgb = [px[i], px[i + 1], px[i + 2]];
    if (Math.abs(rgb[0] - 250) + Math.abs(rgb[1] - 251) + Math.abs(rgb[2] - 253) < 6) { ++background; continue; }
    const { d, n } = direction(rgb);
    if (n < 0.02) { ++unmatched; continue; }  // too dark to tell: a line
    let best = -1, cos = 0;
    chips.forEach((chip, k) => {
      const dot = chip.d[0] * d[0] + chip.d[1] * d[1] + chip.d[2] * d[2];
      if (dot > cos) { cos = dot; best = k; }
    });
    if (cos < Math.cos(3 * Math.PI / 180)) { ++unmatched; continue; }
    ++counts[best];
    where[best][0] += (i / 4) % c.width;
    where[best][1] += Math.floor(i / 4 / c.width);
  }
  const rect = gl.getBoundingClientRect();
  return {
    width: c.width, height: c.height, background, unmatched,
    bands: chips.map((chip, k) => ({ kind: chip.kind, lo: chip.lo, hi: chip.hi, pixels: counts[k],
      // the middle of the band's pixels, in the page's client coordinates
      at: counts[k] ? [rect.left + where[k][0] / counts[k] * rect.width / c.width,
                       rect.top + where[k][1] / counts[k] * rect.height / c.height] : null })),
  };
});

async function submit(page, path, { resolution, minWall, maxWall, inside }) {
  const before = await page.$eval('#job-id', (e) => e.textContent);
  await page.selectOption('#mode', 'solid');
  await page.selectOption('#inside', inside);
  await page.fill('#resolution', String(resolution));
  await page.check('#want-report');
  await page.uncheck('#want-radiography');
  await page.fill('#min-wall', minWall ? String(minWall) : '');
  await page.fill('#max-wall', maxWall ? String(maxWall) : '');
  await page.setInputFiles('#mesh-file', path);
  await page.click('#submit');
  await page.waitForFunction((b) => document.getElementById('job-id').textContent !== b, before);
  await page.waitForFunction(() => document.getElementById('job-state').textContent === 'succeeded', null, { timeout: 180000 });
  await page.waitForFunction(() => /^wall thickness on the part/.test(document.getElementById('view-info').textContent),
                             null, { timeout: 180000 });
  const id = await page.$eval('#job-id', (e) => e.textContent);
  const job = await (await fetch(`${page.base}/v1/jobs/${id}`)).json();
  const asked = job.analyses.find((a) => a.request.kind === 'analysis');
  return (await (await fetch(`${page.base}${asked.url}`)).json()).thickness;
}

// The reading the page shows under the cursor at client (x, y).
async function readingAt(page, [x, y]) {
  await page.mouse.move(x, y);
  const v = await page.$eval('#view-readout', (e) => e.dataset.value);
  assert.ok(v !== '', `no reading under the cursor at (${x}, ${y})`);
  return Number(v);
}

await runPageTest(work, async (browser, base) => {
  const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
  page.base = base;
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(`${base}/`);
  await page.waitForFunction(() => document.querySelectorAll('#mode option').length > 0);

  // 1. The tube: every painted pixel is in a band that 1.5 within the
  // error bound reaches, and the thin and thick marks show nowhere.
  const tube = await submit(page, tubePath, { resolution: 100, minWall: 1, maxWall: 2.4, inside: 'parity' });
  assert.equal(await page.$$eval('#job-warnings li', (l) => l.length), 0, 'the tube is a closed mesh');
  const bound = tube.reading_bound;
  const [low, high] = [1.5 - bound.below, 1.5 + bound.above];
  const seen = await classifyPixels(page);
  await page.screenshot({ path: join(artifacts, '01-tube-painted.png') });
  const painted = seen.bands.reduce((n, b) => n + b.pixels, 0);
  assert.ok(painted > 0.05 * seen.width * seen.height, `the tube covers ${painted} of ${seen.width * seen.height} pixels`);
  const outside = seen.bands.filter((b) => b.pixels > 0 && (b.hi <= low || b.lo > high));
  assert.deepEqual(outside.map((b) => `${b.kind} ${b.lo.toFixed(3)}-${b.hi.toFixed(3)}: ${b.pixels} px`), [],
                   `bands beyond 1.5 in [${low}, ${high}] are painted (${painted} painted pixels)`);
  assert.ok(seen.unmatched < 0.1 * painted, `${seen.unmatched} pixels match no legend colour (${painted} do)`);
  // The legend says the limits; the view frames the part (no band of
  // empty margin: the tube spans most of the view's height).
  const legend = await page.$eval('#wall-legend', (e) => e.textContent);
  assert.match(legend, /thin/);
  assert.match(legend, /thick/);
  assert.match(await page.$eval('#view-info', (e) => e.textContent), /min wall 1(\.00)?, max wall 2\.4/);
  const rows = await page.evaluate(() => {
    const gl = document.querySelector('#viewer canvas');
    const c = Object.assign(document.createElement('canvas'), { width: gl.width, height: gl.height });
    c.getContext('2d').drawImage(gl, 0, 0);
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let top = c.height, bottom = -1;
    for (let y = 0; y < c.height; ++y)
      for (let x = 0; x < c.width; ++x) {
        const i = 4 * (y * c.width + x);
        if (Math.abs(d[i] - 250) + Math.abs(d[i + 1] - 251) + Math.abs(d[i + 2] - 253) > 12) { top = Math.min(top, y); bottom = y; break; }
      }
    return (bottom - top) / c.height;
  });
  assert.ok(rows > 0.6, `the part spans ${rows} of the view's height: not framed`);
  // The cursor on the tube reads its wall.
  const middle = seen.bands.filter((b) => b.pixels).sort((a, b) => b.pixels - a.pixels)[0].at;
  const onTube = await readingAt(page, middle);
  assert.ok(onTube >= low - 1e-6 && onTube <= high + 1e-6, `the cursor reads ${onTube} on the 1.5 tube`);

  // 2. The rib: painted in the thin colour, and read as the rib under the cursor.
  const rib = await submit(page, ribPath, { resolution: 160, minWall: 1, inside: 'winding' });
  const ribSeen = await classifyPixels(page);
  await page.screenshot({ path: join(artifacts, '02-rib-painted.png') });
  const thin = ribSeen.bands.find((b) => b.kind === 'thin');
  assert.ok(thin && thin.pixels > 500, `the rib shows ${thin?.pixels} thin pixels: ${JSON.stringify(ribSeen.bands)}`);
  const onRib = await readingAt(page, thin.at);
  const rb = rib.reading_bound;
  assert.ok(onRib >= 0.6 - rb.below - rb.tolerance && onRib <= 0.6 + rb.above + rb.tolerance, `the cursor reads ${onRib} on the 0.6 rib`);
  assert.match(await page.$eval('#view-readout', (e) => e.textContent), /· thin$/);
  // The block around it is within the limits, and reads so.
  const block = ribSeen.bands.filter((b) => b.kind === 'within').sort((a, b) => b.pixels - a.pixels)[0];
  assert.ok(block.pixels > thin.pixels, JSON.stringify(ribSeen.bands));
  assert.ok(await readingAt(page, block.at) > 1, 'the block reads under min wall');

  // 3. The toggle back to the voxels.
  await page.selectOption('#view-source', 'voxels');
  await page.waitForFunction(() => /filled voxels/.test(document.getElementById('view-info').textContent));
  assert.equal(await page.isVisible('#wall-legend'), false);
  await page.screenshot({ path: join(artifacts, '03-rib-voxels.png') });
  assert.deepEqual(errors, []);
  console.log(`wall view test passed: tube ${painted} px in 1.5's bands (${seen.unmatched} unmatched), rib ${thin.pixels} thin px reading ${onRib}`);
});
