// End-to-end test of the viewer test page (viewer.html): it loads, picks a backend and says
// which, draws the synthetic scene on the canvas, reacts to its controls, downloads a PNG
// screenshot, and shows a readable message when no backend works.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { analysePicture, browserSession, difference } from './browser.mjs';

const session = browserSession();

/** Opens viewer.html with `query` and waits until it is ready or failed. */
async function open(query, { init, deviceScaleFactor = 1 } = {}) {
  const page = await session.browser.newPage({ viewport: { width: 900, height: 800 }, deviceScaleFactor });
  const errors = [];
  page.on('pageerror', (err) => errors.push(err.message));
  page.on('console', (msg) => msg.type() === 'error' && errors.push(msg.text()));
  if (init) {
    await page.addInitScript(init);
  }
  await page.goto(`${session.server.url}viewer.html${query}`);
  await page.waitForFunction(() => document.body.dataset.state !== 'loading', null, {
    timeout: 60_000,
  });
  return { page, errors };
}

// 30 000 points keep the software-rendered frames quick; the benchmark draws 500 000.
for (const [query, backend, label] of [
  ['?points=30000', 'webgpu', 'WebGPU'],
  ['?points=30000&backend=webgl2', 'webgl2', 'WebGL2'],
]) {
  test(`viewer page draws the scene with ${label}`, async () => {
    const { page, errors } = await open(query);
    try {
      assert.equal(await page.evaluate(() => document.body.dataset.state), 'ready');
      assert.equal(await page.evaluate(() => document.body.dataset.backend), backend);
      assert.match(await page.textContent('#status'), new RegExp(`^${label} · 30,000 points`));
      assert.equal(await page.isHidden('[role="alert"]'), true);

      // What the page shows on screen (the composited canvas), not only the off-screen copy.
      const onScreen = await analysePicture(page, (await page.locator('#view').screenshot()).toString('base64'));
      assert.ok(onScreen.drawn > 0.1, `canvas on screen mostly background (${onScreen.drawn})`);

      const frame1 = await analysePicture(page, 'viewer');
      const box = await page.locator('#view').boundingBox();
      assert.equal(frame1.width, Math.round(box.width), 'drawing buffer = CSS size × DPR (1)');
      assert.ok(frame1.drawn > 0.1, `screenshot mostly background (${frame1.drawn})`);

      await page.check('input[name="frame"][value="2"]');
      const frame2 = await analysePicture(page, 'viewer');
      assert.ok(difference(frame1, frame2) > 0.1, 'frame 2 looks like frame 1');
      assert.equal(await page.evaluate(() => window.viewerDemo.viewer.morph), 1);

      await page.selectOption('#colour-mode', 'depth');
      const depth = await analysePicture(page, 'viewer');
      assert.ok(difference(frame2, depth) > 0.1, 'depth colours look like photo colours');

      // A drag orbits the camera; reset brings the same picture back.
      await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
      await page.mouse.down();
      await page.mouse.move(box.x + box.width / 2 + 150, box.y + box.height / 2 + 40, { steps: 5 });
      await page.mouse.up();
      const orbited = await analysePicture(page, 'viewer');
      assert.ok(difference(depth, orbited) > 0.1, 'dragging did not move the view');
      await page.click('#reset');
      const reset = await analysePicture(page, 'viewer');
      assert.ok(difference(depth, reset) < 0.02, 'reset did not return to the home view');

      const [download] = await Promise.all([page.waitForEvent('download'), page.click('#screenshot')]);
      assert.equal(download.suggestedFilename(), 'superpixel-soup-view.png');
      const saved = await import('node:fs/promises').then((fs) => download.path().then((p) => fs.readFile(p)));
      assert.deepEqual([...saved.subarray(0, 8)], [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]);
      assert.equal(saved.readUInt32BE(16), frame1.width);

      assert.deepEqual(errors, []);
    } finally {
      await page.close();
    }
  });
}

test('the drawing buffer follows the canvas size and the device pixel ratio', async () => {
  const { page, errors } = await open('?points=30000', { deviceScaleFactor: 2 });
  const size = () =>
    page.evaluate(() => {
      const c = document.getElementById('view');
      return { width: c.width, height: c.height, css: [c.clientWidth, c.clientHeight] };
    });
  try {
    await page.waitForFunction(() => document.getElementById('view').width > 300);
    let s = await size();
    assert.deepEqual([s.width, s.height], [2 * s.css[0], 2 * s.css[1]]);
    await page.setViewportSize({ width: 500, height: 800 });
    await page.waitForFunction((w) => document.getElementById('view').width !== w, s.width);
    s = await size();
    assert.deepEqual([s.width, s.height], [2 * s.css[0], 2 * s.css[1]]);
    assert.ok(s.css[0] < 500, `canvas ${s.css[0]} CSS px wide in a 500 px window`);
    const drawn = await analysePicture(page, 'viewer');
    assert.equal(drawn.width, s.width, 'the screenshot has the drawing buffer size');
    assert.deepEqual(errors, []);
  } finally {
    await page.close();
  }
});

test('viewer page explains when neither WebGPU nor WebGL2 works', async () => {
  const { page } = await open('', {
    init: () => {
      Object.defineProperty(Navigator.prototype, 'gpu', { get: () => undefined });
      const getContext = HTMLCanvasElement.prototype.getContext;
      HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
        return kind === 'webgl2' || kind === 'webgpu' ? null : getContext.call(this, kind, ...rest);
      };
    },
  });
  try {
    assert.equal(await page.evaluate(() => document.body.dataset.state), 'error');
    const alert = await page.textContent('[role="alert"]');
    assert.match(alert, /^The 3D view cannot run in this browser\./);
    assert.match(alert, /WebGPU: navigator\.gpu is missing/);
    assert.match(alert, /WebGL2: .*getContext\(\) returned null/);
    assert.equal(await page.isHidden('#view'), true);
  } finally {
    await page.close();
  }
});
