// Starts a real `voxd serve` on a loopback ephemeral port for the Node tests
// (the browser page, the contract linters, the README examples), finds the
// repository's npm modules (web/package-lock.json), and launches Debian's
// headless Chromium for the tests that drive the page.
import { spawn } from 'node:child_process';
import { rmSync } from 'node:fs';
import { createRequire } from 'node:module';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

export const repo = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
export const voxdBinary = process.env.VOXD_BINARY || join(repo, 'build/server/voxd');
export const requireWebModule = createRequire(join(repo, 'web/package.json'));

// Resolves to { child, base } once voxd prints its address; extraArgs go
// after the defaults (a later flag wins).
export function startVoxd(dataDir, extraArgs = []) {
  return new Promise((resolveStart, reject) => {
    const child = spawn(voxdBinary, ['serve', '--host', '127.0.0.1', '--port', '0', '--data-dir', dataDir, '--workers', '2', ...extraArgs],
                        { stdio: ['ignore', 'pipe', 'pipe'] });
    let log = '';
    const timer = setTimeout(() => reject(new Error(`voxd serve did not listen within 30 s:\n${log}`)), 30000);
    const look = (chunk) => {
      log += chunk;
      const m = /listening on (http:\/\/127\.0\.0\.1:\d+)/.exec(log);
      if (m) { clearTimeout(timer); resolveStart({ child, base: m[1] }); }
    };
    child.stdout.on('data', look);
    child.stderr.on('data', look);
    child.on('exit', (code) => reject(new Error(`voxd serve exited (${code}):\n${log}`)));
  });
}

// Debian's Chromium, headless, with WebGL by SwiftShader (no GPU here).
export function launchChromium() {
  const { chromium } = requireWebModule('playwright-core');
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
}

// A page test's whole life: a `voxd serve` whose data lives in `work`, and
// Chromium; `body(browser, base)` runs against them. Both are stopped and
// `work` removed whatever happens, then the process exits 1 if body threw
// (printing why), else 0.
export async function runPageTest(work, body) {
  const { child, base } = await startVoxd(join(work, 'data'));
  const browser = await launchChromium();
  let failed = false;
  try {
    await body(browser, base);
  } catch (e) {
    failed = true;
    console.error(e);
  } finally {
    await browser.close();
    child.kill('SIGTERM');
    rmSync(work, { recursive: true, force: true });
  }
  process.exit(failed ? 1 : 0);
}
