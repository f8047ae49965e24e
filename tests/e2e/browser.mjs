// Shared helpers for the end-to-end tests: the one place that launches Chromium and starts the
// page server. Chromium's flags come from webdriver.json at the repository root (the file
// wasm-bindgen-test-runner reads), so the wasm tests and these tests run the same browser setup.

import { spawn } from 'node:child_process';
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import path from 'node:path';
import { after, before } from 'node:test';
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

/**
 * Registers node:test hooks that start the page server and a browser before a test file's tests
 * and close both after them. Returns the session; its `server` and `browser` are set once started.
 */
export function browserSession() {
  const session = { server: null, browser: null };
  before(async () => {
    session.server = await startServer();
    session.browser = await launchBrowser();
  });
  after(async () => {
    await session.browser?.close();
    await session.server?.close();
  });
  return session;
}

/**
 * Share of pixels of a PNG that differ from the viewer's background (#1d2330), decoded by the
 * browser, and a coarse signature (summed colour per block of an 8 × 8 grid) to tell pictures
 * apart. `source` names the PNG: 'page' for the screenshot of index.html's viewer, 'viewer' for
 * viewer.html's, else the PNG's bytes in base64. Screenshots are taken and analysed in the page
 * (moving their bytes through Playwright would take seconds).
 */
export function analysePicture(page, source) {
  return page.evaluate(async (source) => {
    let bytes;
    if (source === 'page') {
      await window.soupPage.viewerReady;
      bytes = await window.soupPage.viewer.screenshot(); // the viewer in use (replaced after a GPU loss)
    } else if (source === 'viewer') {
      bytes = await window.viewerDemo.viewer.screenshot();
    } else {
      bytes = Uint8Array.from(atob(source), (c) => c.charCodeAt(0));
    }
    const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
    const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
    const ctx = canvas.getContext('2d');
    ctx.drawImage(bitmap, 0, 0);
    const { data, width, height } = ctx.getImageData(0, 0, bitmap.width, bitmap.height);
    let drawn = 0;
    const blocks = new Array(64).fill(0);
    for (let y = 0; y < height; y++) {
      for (let x = 0; x < width; x++) {
        const i = 4 * (y * width + x);
        const [r, g, b] = [data[i], data[i + 1], data[i + 2]];
        if (Math.abs(r - 0x1d) + Math.abs(g - 0x23) + Math.abs(b - 0x30) > 12) {
          drawn += 1;
        }
        blocks[Math.floor((8 * y) / height) * 8 + Math.floor((8 * x) / width)] += r + g + b;
      }
    }
    return { width, height, drawn: drawn / (width * height), blocks };
  }, source);
}

/** Largest relative difference between two block signatures of analysePicture. */
export function difference(a, b) {
  return Math.max(...a.blocks.map((v, i) => Math.abs(v - b.blocks[i]) / Math.max(1, v, b.blocks[i])));
}
