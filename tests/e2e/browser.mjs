// Shared helpers for the end-to-end tests: the one place that launches Chromium and starts the
// page server. Chromium's flags come from webdriver.json at the repository root (the file
// wasm-bindgen-test-runner reads), so the wasm tests and these tests run the same browser setup.

import { spawn } from 'node:child_process';
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import path from 'node:path';
import { chromium } from 'playwright-core';

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');

/** The Chromium binary: Debian's, unless env CHROMIUM overrides it. */
export const CHROMIUM = process.env.CHROMIUM ?? '/usr/bin/chromium';

/**
 * Chromium's command-line flags from webdriver.json, minus the ones Playwright sets itself
 * (headless mode, and a fresh temporary --user-data-dir per launch).
 */
export function chromiumArgs() {
  const config = JSON.parse(readFileSync(path.join(ROOT, 'webdriver.json'), 'utf8'));
  const args = config['goog:chromeOptions']?.args ?? [];
  return args.filter((a) => !/^--?(headless|user-data-dir)\b/.test(a));
}

/** Launches headless Chromium with the project's flags. */
export function launchBrowser() {
  return chromium.launch({ executablePath: CHROMIUM, headless: true, args: chromiumArgs() });
}

/**
 * Starts scripts/serve.py on a free port of 127.0.0.1, serving the repository root.
 * Resolves to { url, close } once the server listens.
 */
export function startServer() {
  const server = spawn('python3', [path.join(ROOT, 'scripts/serve.py'), '--port', '0'], {
    env: { ...process.env, SERVE_QUIET: '1' },
    stdio: ['ignore', 'pipe', 'inherit'],
  });
  return new Promise((resolve, reject) => {
    let out = '';
    server.on('error', reject);
    server.on('exit', (code) => reject(new Error(`serve.py exited early (code ${code})`)));
    server.stdout.on('data', (chunk) => {
      out += chunk;
      const match = out.match(/serving (http:\/\/\S+?\/)/);
      if (match) {
        const url = match[1].replace('localhost', '127.0.0.1');
        resolve({
          url,
          close: () =>
            new Promise((done) => {
              server.removeAllListeners('exit');
              server.once('exit', done);
              server.kill();
            }),
        });
      }
    });
  });
}
