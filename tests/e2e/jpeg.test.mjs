// End-to-end test of the page's JPEG decoding (www/page/input.js): JPEG photos are decoded by the
// library in a worker (src/jpeg.rs, a DCT-scaled decode straight to the working size), upright
// by their EXIF orientation as the browser's `imageOrientation: 'from-image'` gives them; a
// JPEG the library refuses (CMYK, tests/e2e/cmyk.jpg) is decoded by the browser as before.
// The 12-megapixel pair through the whole page is in photos.test.mjs.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { ROOT, browserSession } from './browser.mjs';
import { SAMPLE, openPage, withExifOrientation } from './page-helpers.mjs';

const session = browserSession();

/**
 * The sample's frame 1 scaled ×3 (2304 × 984, so the library decodes it at 1/2 and resizes to
 * 1024 × 437) and stored turned so that EXIF orientation `o` (3 or 6) shows it upright, as a
 * JPEG (quality 0.92) with that orientation.
 */
async function turnedJpeg(page, o) {
  const base64 = await page.evaluate(
    async ({ png, o }) => {
      const bytes = Uint8Array.from(atob(png), (c) => c.charCodeAt(0));
      const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
      const [w, h] = [bitmap.width * 3, bitmap.height * 3];
      const canvas = o === 6 ? new OffscreenCanvas(h, w) : new OffscreenCanvas(w, h);
      const ctx = canvas.getContext('2d');
      ctx.imageSmoothingQuality = 'high';
      if (o === 6) {
        // Stored turned a quarter anticlockwise: orientation 6 turns it clockwise to show it.
        ctx.translate(0, w);
        ctx.rotate(-Math.PI / 2);
      } else {
        ctx.translate(w, h);
        ctx.rotate(Math.PI);
      }
      ctx.drawImage(bitmap, 0, 0, w, h);
      const blob = await canvas.convertToBlob({ type: 'image/jpeg', quality: 0.92 });
      const out = new Uint8Array(await blob.arrayBuffer());
      let text = '';
      for (let i = 0; i < out.length; i += 0x8000) {
        text += String.fromCharCode(...out.subarray(i, i + 0x8000));
      }
      return btoa(text);
    },
    { png: SAMPLE[0].buffer.toString('base64'), o },
  );
  return withExifOrientation(Buffer.from(base64, 'base64'), o);
}

/**
 * Decodes `buffer` as a file named `name` with the page's own decodeImage (the module the page
 * loaded), and with the browser (createImageBitmap, EXIF orientation, resized to the frame's
 * size, resizeQuality 'high'). Resolves to the frame's facts and the mean absolute difference
 * between the two decodes (per channel, in 1/255) and the same for the frame turned the other
 * way round (a wrong orientation gives a large difference).
 */
function decodeInPage(page, buffer, name) {
  return page.evaluate(
    async ({ data, name }) => {
      const { decodeImage } = await import(new URL('www/page/input.js', document.baseURI).href);
      const bytes = Uint8Array.from(atob(data), (c) => c.charCodeAt(0));
      const file = new File([bytes], name, { type: 'image/jpeg' });
      const frame = await decodeImage(file);
      const { width: w, height: h } = frame.bitmap;
      const browser = await createImageBitmap(file, {
        imageOrientation: 'from-image',
        colorSpaceConversion: 'none',
        premultiplyAlpha: 'none',
        resizeWidth: w,
        resizeHeight: h,
        resizeQuality: 'high',
      });
      const pixels = (bitmap, turn = false) => {
        const canvas = new OffscreenCanvas(w, h);
        const ctx = canvas.getContext('2d');
        if (turn) {
          ctx.translate(w, h);
          ctx.rotate(Math.PI);
        }
        ctx.drawImage(bitmap, 0, 0);
        return ctx.getImageData(0, 0, w, h).data;
      };
      const ours = pixels(frame.bitmap);
      const mad = (other) => {
        let sum = 0;
        for (let i = 0; i < ours.length; i += 4) {
          sum += Math.abs(ours[i] - other[i]) + Math.abs(ours[i + 1] - other[i + 1]) + Math.abs(ours[i + 2] - other[i + 2]);
        }
        return sum / (3 * w * h);
      };
      const result = {
        decoder: frame.decoder,
        size: [frame.width, frame.height],
        frameSize: [w, h],
        mad: mad(pixels(browser)),
        madTurned: mad(pixels(browser, true)),
      };
      browser.close();
      frame.bitmap.close();
      frame.thumbnail.close();
      return result;
    },
    { data: buffer.toString('base64'), name },
  );
}

test('JPEGs are decoded by the library, upright at the working size, as the browser decodes them', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  for (const o of [6, 3]) {
    const decoded = await decodeInPage(page, await turnedJpeg(page, o), `turned${o}.jpg`);
    assert.equal(decoded.decoder, 'library', `orientation ${o}`);
    assert.deepEqual(decoded.size, [2304, 984], `orientation ${o}`);
    assert.deepEqual(decoded.frameSize, [1024, 437], `orientation ${o}`);
    // 1.45/255 measured (the browser resizes with another filter than the library).
    assert.ok(decoded.mad < 2.5, `orientation ${o}: mean |Δ| against the browser ${decoded.mad.toFixed(2)}/255`);
    assert.ok(decoded.madTurned > 10, `orientation ${o}: turned round ${decoded.madTurned.toFixed(2)}/255`);
  }
  assert.deepEqual(errors, []);
  await page.context().close();
});

test('a JPEG the library refuses (CMYK) is decoded by the browser', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  const cmyk = readFileSync(path.join(ROOT, 'tests/e2e/cmyk.jpg'));
  const decoded = await decodeInPage(page, cmyk, 'cmyk.jpg');
  assert.equal(decoded.decoder, 'browser');
  assert.deepEqual(decoded.size, [192, 82]);
  assert.deepEqual(decoded.frameSize, [192, 82]);
  assert.equal(decoded.mad, 0);
  assert.deepEqual(errors, []);
  await page.context().close();
});
