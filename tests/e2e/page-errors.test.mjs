// End-to-end test of the page's bad inputs: each gives a readable message in the alert
// (role="alert"), the state "error", and the page stays usable: a good run works afterwards.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { browserSession } from './browser.mjs';
import { makePng } from './png.mjs';
import { SAMPLE, alertText, convertImage, openPage, waitForRunEnd } from './page-helpers.mjs';

const session = browserSession();

test('bad inputs give readable messages and the page stays usable', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  const [one, two] = SAMPLE;

  /** Picks `files`, waits for the error and returns the alert's text. */
  const expectError = async (files) => {
    await page.setInputFiles('#file-input', files);
    assert.equal(await waitForRunEnd(page), 'error', 'no error');
    return alertText(page);
  };

  assert.equal(
    await expectError([{ name: 'notes.txt', mimeType: 'text/plain', buffer: Buffer.from('not pixels') }, one]),
    'notes.txt is not an image or a video (text/plain). Drop two photos (PNG, JPEG, …) or one video.',
  );

  assert.equal(
    await expectError([one]),
    'Only one image was given (frame1.png). Two photos of the same scene are needed: pick or drop both at once.',
  );

  const undecodable = 'could not be decoded: the file is damaged or in a format this browser cannot read.';
  assert.equal(
    await expectError([{ name: 'noise.png', mimeType: 'image/png', buffer: Buffer.from('these are not pixels') }, two]),
    `noise.png ${undecodable}`,
  );
  assert.equal(
    await expectError([{ name: 'cut.png', mimeType: 'image/png', buffer: one.buffer.subarray(0, one.buffer.length / 2) }, two]),
    `cut.png ${undecodable}`,
  );
  // A JPEG header with nothing after it: both decoders refuse it, and the library's reason is told.
  assert.equal(
    await expectError([{ name: 'broken.jpg', mimeType: 'image/jpeg', buffer: Buffer.from([0xff, 0xd8, 0xff, 0xe0, 1, 2, 3]) }, two]),
    'broken.jpg could not be decoded: the file is damaged or in a format this browser cannot read ' +
      '(the library\'s JPEG decoder: cannot decode image: truncated JPEG (no end-of-image marker)).',
  );

  const tiny = makePng(16, 16, (x, y) => [x * 16, y * 16, 99]);
  assert.equal(
    await expectError([
      { name: 'a.png', mimeType: 'image/png', buffer: tiny },
      { name: 'b.png', mimeType: 'image/png', buffer: tiny },
    ]),
    'Image is too small: 16×16 pixels (at least 32×32 needed)',
  );

  assert.equal(
    await expectError([one, { ...one, name: 'copy.png' }]),
    'No parallax: depth cannot be recovered (the flow is zero everywhere (identical frames?)). ' +
      'The two photos must be taken from different positions, or show motion.',
  );

  // Different sizes: the alert offers to resize frame 2, which then runs.
  const half = await convertImage(page, two.buffer, { width: 384, height: 164 });
  assert.equal(
    await expectError([one, { name: 'half.png', mimeType: 'image/png', buffer: half }]),
    'The two frames differ in size: frame 1 is 768×328, frame 2 is 384×164; both must be the same size ' +
      'Resize frame 2 to 768 × 328 and reconstruct',
  );
  await page.getByRole('alert').getByRole('button').click();
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  assert.equal(await alertText(page), null);
  assert.match(await page.textContent('#summary'), /Input size768 × 328/);

  assert.deepEqual(errors, []);
  await page.context().close();
});

test('out of memory is told apart from a crash, and the next run works', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  // The fresh worker's wasm memory is grown to 8 MB below the browser's limit for wasm32 (4 GiB)
  // first, so the reconstruction runs out of memory part way, as on a device without memory to
  // spare (growing reserves address space; it does not use the memory).
  const [worker] = page.workers();
  const build = await page.evaluate(() => document.body.dataset.workerBuild);
  const free = await worker.evaluate(async (build) => {
    const soup = await import(new URL(`pkg/${build}.js`, self.location.href).href);
    const { memory } = await soup.default(); // the worker's instance, already loaded
    const page = 65536;
    memory.grow(2 ** 32 / page - 128 - memory.buffer.byteLength / page);
    let more = 0;
    try {
      memory.grow(129);
      more = 129;
    } catch {
      // the limit is where this test expects it
    }
    return { left: 2 ** 32 - memory.buffer.byteLength, more };
  }, build);
  assert.deepEqual(free, { left: 128 * 65536, more: 0 });
  await page.click('#sample-button');
  assert.equal(await waitForRunEnd(page), 'error');
  assert.match(
    await alertText(page),
    /^Out of memory: the browser would not give the reconstruction another \d+ [kM]B \(it already uses \d+ MB\)\. Try a smaller working size or smaller photos\.$/,
  );

  // The worker was replaced: a good run works.
  await page.setInputFiles('#file-input', SAMPLE);
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  assert.equal(await alertText(page), null);
  assert.deepEqual(errors, []);
  await page.context().close();
});
