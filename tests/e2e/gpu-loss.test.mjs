// End-to-end test of the 3D view surviving the loss of its GPU: the sample is reconstructed,
// the view orbited, then the GPU is taken away (WebGL2: the WEBGL_lose_context extension, as a
// driver reset or too many contexts would; WebGPU: device.destroy(), as a lost device). The view
// must come back by itself with the same cloud and camera, and an orbit afterwards must draw.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { browserSession } from './browser.mjs';
import { alertText, analyseView, difference, openPage, waitForRunEnd } from './page-helpers.mjs';

const session = browserSession();

/**
 * Records every WebGPU device the page asks for (window.gpuDevices), so the test can destroy one;
 * window.blockGpu makes WebGPU refuse.
 */
function recordDevices() {
  window.gpuDevices = [];
  // While window.blockGpu is true, WebGPU hands out no adapter (a GPU that does not come back).
  if (globalThis.GPU) {
    const requestAdapter = GPU.prototype.requestAdapter;
    GPU.prototype.requestAdapter = function (...args) {
      return window.blockGpu ? Promise.resolve(null) : requestAdapter.apply(this, args);
    };
  }
  if (globalThis.GPUAdapter) {
    const request = GPUAdapter.prototype.requestDevice;
    GPUAdapter.prototype.requestDevice = async function (...args) {
      const device = await request.apply(this, args);
      window.gpuDevices.push(device);
      return device;
    };
  }
}

const LOSE = {
  webgl2: () => document.querySelector('#view').getContext('webgl2').getExtension('WEBGL_lose_context').loseContext(),
  webgpu: () => window.gpuDevices.at(-1).destroy(),
};

/** Drags across the middle of the 3D view with the mouse (an orbit). */
async function orbit(page, from, to) {
  const box = await page.locator('#view').boundingBox();
  const y = box.y + box.height / 2;
  await page.mouse.move(box.x + box.width * from, y);
  await page.mouse.down();
  for (let step = 1; step <= 8; step++) {
    await page.mouse.move(box.x + box.width * (from + ((to - from) * step) / 8), y);
  }
  await page.mouse.up();
}

for (const backend of ['webgl2', 'webgpu']) {
  test(`${backend}: a lost GPU is restored with the same cloud and camera, and an orbit draws`, async () => {
    const { page, errors } = await openPage(session.browser, session.server.url, `?backend=${backend}`, {}, recordDevices);
    await page.click('#sample-button');
    assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
    assert.equal(await page.evaluate(() => document.body.dataset.backend), backend);
    await page.locator('#view').scrollIntoViewIfNeeded();
    await orbit(page, 0.4, 0.5); // away from the home view, so that the camera is checked
    await page.selectOption('#colour-mode', 'depth');
    await page.selectOption('#unknown-scale', 'hide');
    const hidden = () => page.evaluate(() => window.soupPage.viewer.pointCount - window.soupPage.viewer.shownPointCount);
    await page.waitForFunction(() => window.soupPage.viewer.shownPointCount < window.soupPage.viewer.pointCount);
    const hiddenBefore = await hidden();
    const before = await analyseView(page);
    assert.ok(before.drawn > 0.2, `only ${before.drawn} of the view is drawn`);
    const camera = await page.evaluate(() => Array.from(window.soupPage.viewer.camera));

    await page.evaluate(LOSE[backend]);
    await page.waitForFunction(() => window.soupPage.viewerRestores === 1 && document.body.dataset.viewer === 'ready', null, { timeout: 60_000 });
    assert.equal(await page.isHidden('#viewer-message'), true);
    assert.equal(await page.evaluate(() => document.body.dataset.backend), backend);
    const restoredCamera = await page.evaluate(() => Array.from(window.soupPage.viewer.camera));
    restoredCamera.forEach((v, i) => assert.ok(Math.abs(v - camera[i]) < 1e-5, `camera ${restoredCamera} vs ${camera}`));
    assert.equal(await hidden(), hiddenBefore, 'the unknown-scale pieces stay hidden');
    const restored = await analyseView(page);
    assert.ok(restored.drawn > 0.2, `only ${restored.drawn} of the restored view is drawn`);
    assert.ok(difference(before, restored) < 0.02, `the restored view differs by ${difference(before, restored)}`);

    // The controls drive the new viewer: an orbit changes what is drawn.
    await orbit(page, 0.5, 0.7);
    const moved = await analyseView(page);
    assert.ok(moved.drawn > 0.1, `only ${moved.drawn} of the orbited view is drawn`);
    assert.ok(difference(restored, moved) > 0.05, 'the orbit did not move the view');
    assert.equal(await alertText(page), null);
    assert.deepEqual(errors, []);
    await page.context().close();
  });
}

test('webgpu: when the GPU does not come back, the page says so and its button restores the view', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url, '?backend=webgpu', {}, recordDevices);
  await page.click('#sample-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  await page.locator('#view').scrollIntoViewIfNeeded();
  const before = await analyseView(page);

  await page.evaluate(() => {
    window.blockGpu = true;
    window.gpuDevices.at(-1).destroy();
  });
  await page.waitForFunction(() => document.body.dataset.viewer === 'failed', null, { timeout: 60_000 });
  assert.match(await page.textContent('#viewer-message'),
    /^The 3D view was interrupted \(the WebGPU device was lost\) and could not be restored \(.+\)\. The pictures and downloads still work\./);
  assert.equal(await page.isVisible('#viewer-restore'), true);
  // The rest of the page works meanwhile.
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'done');

  await page.evaluate(() => { window.blockGpu = false; });
  await page.click('#viewer-restore');
  await page.waitForFunction(() => document.body.dataset.viewer === 'ready', null, { timeout: 60_000 });
  assert.equal(await page.isHidden('#viewer-message'), true);
  const restored = await analyseView(page);
  assert.ok(difference(before, restored) < 0.02, `the restored view differs by ${difference(before, restored)}`);
  assert.deepEqual(errors, []);
  await page.context().close();
});
