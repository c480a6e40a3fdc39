// Starts a real `voxd serve` on a loopback ephemeral port for the Node tests
// (the browser page, the contract linters, the README examples), and finds
// the repository's npm modules (web/package-lock.json).
import { spawn } from 'node:child_process';
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
