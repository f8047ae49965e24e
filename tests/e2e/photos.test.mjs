// End-to-end test of phone-sized photos: a 12-megapixel JPEG pair (4032 × 3024, the sample
// upscaled in the browser) runs through the page. The page decodes each photo straight to the
// working size (the library's DCT-scaled JPEG decoder, in a worker; no full-size pixels are ever
// made); the report still tells the photos' size, and the depth download is at that size. Peak
// memory is measured by benches/page.mjs, not here.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { browserSession } from './browser.mjs';
import { SAMPLE, alertText, convertImage, download, openPage, waitForRunEnd } from './page-helpers.mjs';

const session = browserSession();

test('a 12-megapixel JPEG pair runs at the working size, with outputs at the photos\' size', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  const jpegs = [];
  for (const frame of SAMPLE) {
    const buffer = await convertImage(page, frame.buffer, { type: 'image/jpeg', width: 4032, height: 3024, quality: 0.92 });
    jpegs.push({ name: frame.name.replace('.png', '.jpg'), mimeType: 'image/jpeg', buffer });
  }
  await page.setInputFiles('#file-input', jpegs);
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  assert.match(await page.textContent('#thumb1-info'), /frame1\.jpg · 4032 × 3024/);
  const summary = await page.textContent('#summary');
  assert.match(summary, /Input size4032 × 3024/);
  assert.match(summary, /Working size1024 × 768/);
  assert.match(summary, /downscaled from 4032×3024 to 1024×768 \(as the page decoded/);
  // The library decoded the photos straight to the working size (src/jpeg.rs), and the frames
  // reached the worker at that size: its pixel buffers are small.
  assert.deepEqual(await page.evaluate(() => window.soupPage.frames.map((f) => f.decoder)), ['library', 'library']);
  assert.deepEqual(await page.evaluate(() => window.soupPage.frames.map((f) => [f.bitmap.width, f.bitmap.height])), [[1024, 768], [1024, 768]]);
  // Default intrinsics of the photo (f = long side), at the working size in the report.
  const report = JSON.parse(await download(page, 'report.json'));
  assert.deepEqual(report.input_size, [4032, 3024]);
  assert.ok(Math.abs(report.camera.intrinsics.fx - 1024) < 1e-9, `fx ${report.camera.intrinsics.fx}`);
  const pfm = await download(page, 'depth.pfm');
  assert.equal(pfm.toString('latin1', 0, 13), 'Pf\n4032 3024\n');
  assert.ok((await page.evaluate(() => window.soupPage.points)) > 0.8 * 1024 * 768);
  assert.deepEqual(errors, []);
  await page.context().close();
});
