// End-to-end test of the page: served by scripts/serve.py, driven in headless Chromium.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { ROOT, launchBrowser, startServer } from './browser.mjs';
import { makePng } from './png.mjs';

const cargoVersion = readFileSync(path.join(ROOT, 'Cargo.toml'), 'utf8').match(
  /^version\s*=\s*"([^"]+)"/m,
)[1];

let server;
let browser;
let page;
const consoleErrors = [];

before(async () => {
  server = await startServer();
  browser = await launchBrowser();
  page = await browser.newPage();
  page.on('console', (msg) => msg.type() === 'error' && consoleErrors.push(msg.text()));
  page.on('pageerror', (err) => consoleErrors.push(err.message));
  await page.goto(server.url);
});

after(async () => {
  await browser?.close();
  await server?.close();
});

const waitForState = (state) =>
  page.waitForFunction((s) => document.body.dataset.state === s, state, { timeout: 30_000 });

test('page loads the wasm module and shows the crate version', async () => {
  await waitForState('idle');
  assert.equal(await page.title(), 'Superpixel Soup');
  assert.equal(await page.textContent('#version'), cargoVersion);
  assert.match(await page.textContent('main'), /pipeline is not there yet/);
  assert.equal(await page.isDisabled('#file-input'), false);
  assert.deepEqual(consoleErrors, []);
});

test('page is cross-origin isolated (ready for wasm threads)', async () => {
  assert.equal(await page.evaluate(() => globalThis.crossOriginIsolated), true);
});

test('a file that is not an image gives a readable error', async () => {
  await waitForState('idle');
  await page.setInputFiles('#file-input', {
    name: 'notes.txt',
    mimeType: 'text/plain',
    buffer: Buffer.from('these are notes, not pixels'),
  });
  const alert = page.getByRole('alert');
  await alert.waitFor({ state: 'visible' });
  await waitForState('idle');
  assert.equal(await alert.textContent(), 'notes.txt: cannot decode image: not a PNG or JPEG file');
  assert.equal(await page.isHidden('#image-info'), true);
});

test('a PNG reports its size and no EXIF focal length', async () => {
  await waitForState('idle');
  const png = makePng(37, 21, (x, y) => [x * 6, y * 12, 128]);
  await page.setInputFiles('#file-input', { name: 'tiny.png', mimeType: 'image/png', buffer: png });
  await page.locator('#image-info').waitFor({ state: 'visible' });
  await waitForState('idle');
  assert.equal(await page.textContent('#info-name'), 'tiny.png');
  assert.equal(await page.textContent('#info-size'), '37 × 21 pixels');
  assert.equal(await page.textContent('#info-focal'), 'not in the file');
  // The earlier error is gone once a good file is read.
  assert.equal(await page.isHidden('[role="alert"]'), true);
});

test('a truncated PNG gives a readable error', async () => {
  await waitForState('idle');
  const png = makePng(37, 21, () => [200, 100, 50]);
  await page.setInputFiles('#file-input', {
    name: 'cut.png',
    mimeType: 'image/png',
    buffer: png.subarray(0, 60),
  });
  const alert = page.getByRole('alert');
  await alert.waitFor({ state: 'visible' });
  assert.match(await alert.textContent(), /^cut\.png: cannot decode image: /);
});
