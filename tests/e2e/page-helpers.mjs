// Helpers of the page's end-to-end tests (page.test.mjs, page-errors.test.mjs): opening the
// page, waiting for its state, the sample files, checking the 3D view and reading the
// downloaded files' headers.

import { readFileSync } from 'node:fs';
import path from 'node:path';
import { ROOT, analysePicture, difference } from './browser.mjs';

/** The built-in sample pair (www/sample/) as files for `setInputFiles`. */
export const SAMPLE = ['frame1.png', 'frame2.png'].map((name) => ({
  name,
  mimeType: 'image/png',
  buffer: readFileSync(path.join(ROOT, 'www/sample', name)),
}));
export const SAMPLE_SIZE = [768, 328];

/**
 * Opens the page (index.html) with `query` in a new context of `browser` and waits until its
 * worker is ready. Resolves to { page, errors } (errors collects console errors and exceptions).
 * `initScript` (a function) runs in the page before its own scripts.
 */
export async function openPage(browser, url, query = '', contextOptions = {}, initScript = null) {
  const context = await browser.newContext({ viewport: { width: 1100, height: 900 }, ...contextOptions });
  if (initScript !== null) {
    await context.addInitScript(initScript);
  }
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (err) => errors.push(err.message));
  page.on('console', (msg) => msg.type() === 'error' && errors.push(msg.text()));
  page.on('console', (msg) => process.env.SHOW_CONSOLE && console.log('console:', msg.text()));
  await page.goto(`${url}${query}`);
  await waitForState(page, 'idle');
  return { page, errors };
}

/** Waits until document.body.dataset.state is one of `states` (a string or an array). */
export async function waitForState(page, states, timeout = 120_000) {
  const wanted = [states].flat();
  await page.waitForFunction((s) => s.includes(document.body.dataset.state), wanted, { timeout });
  return page.evaluate(() => document.body.dataset.state);
}

/** Waits for a run to end; asserts nothing. Resolves to the final state. */
export function waitForRunEnd(page) {
  return waitForState(page, ['done', 'error', 'idle']);
}

/** Text of the alert, or null when it is hidden. */
export function alertText(page) {
  return page.evaluate(() => {
    const alert = document.querySelector('[role="alert"]');
    return alert.hidden ? null : alert.textContent;
  });
}

/** Share of the 3D view's drawn pixels and block signature (analysePicture) of its screenshot. */
export function analyseView(page) {
  return analysePicture(page, 'page');
}

export { difference };

/** Clicks the download button of `file` and resolves to the downloaded bytes (a Buffer). */
export async function download(page, file) {
  const [event] = await Promise.all([
    page.waitForEvent('download'),
    page.click(`#downloads button[data-file="${file}"]`),
  ]);
  assertEqual(event.suggestedFilename(), file);
  return readFileSync(await event.path());
}

function assertEqual(a, b) {
  if (a !== b) {
    throw new Error(`expected ${b}, got ${a}`);
  }
}

/** PLY: the header's lines, the vertex count and the body's length. */
export function readPlyHeader(bytes) {
  const end = bytes.indexOf('end_header\n');
  if (end < 0) {
    throw new Error('no PLY header');
  }
  const header = bytes.subarray(0, end).toString('latin1').split('\n');
  const vertices = Number(header.find((l) => l.startsWith('element vertex '))?.split(' ')[2]);
  return { header, vertices, bodyLength: bytes.length - end - 'end_header\n'.length };
}

/** PNG: width, height, bit depth and colour type from the IHDR chunk. */
export function readPngHeader(bytes) {
  if (bytes.subarray(0, 8).toString('hex') !== '89504e470d0a1a0a' || bytes.toString('latin1', 12, 16) !== 'IHDR') {
    throw new Error('not a PNG');
  }
  return {
    width: bytes.readUInt32BE(16),
    height: bytes.readUInt32BE(20),
    bitDepth: bytes[24],
    colourType: bytes[25],
  };
}

/** Middlebury .flo: the tag check, width and height. */
export function readFloHeader(bytes) {
  return {
    tag: bytes.readFloatLE(0),
    width: bytes.readInt32LE(4),
    height: bytes.readInt32LE(8),
  };
}

/**
 * Converts the PNG `buffer` in the page to another image (OffscreenCanvas.convertToBlob), e.g.
 * { type: 'image/jpeg' } or a new size { width, height }; resolves to a Buffer.
 */
export async function convertImage(page, buffer, { type = 'image/png', width, height, quality } = {}) {
  const base64 = await page.evaluate(
    async ({ png, type, width, height, quality }) => {
      const bytes = Uint8Array.from(atob(png), (c) => c.charCodeAt(0));
      const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
      const canvas = new OffscreenCanvas(width ?? bitmap.width, height ?? bitmap.height);
      const ctx = canvas.getContext('2d');
      ctx.imageSmoothingQuality = 'high';
      ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
      const blob = await canvas.convertToBlob({ type, quality });
      const out = new Uint8Array(await blob.arrayBuffer());
      let text = '';
      for (let i = 0; i < out.length; i += 0x8000) {
        text += String.fromCharCode(...out.subarray(i, i + 0x8000));
      }
      return btoa(text);
    },
    { png: buffer.toString('base64'), type, width, height, quality },
  );
  return Buffer.from(base64, 'base64');
}

/** `jpeg` with an EXIF block (APP1, right after SOI) holding the TIFF structure `tiff`. */
function withExif(jpeg, tiff) {
  const payload = Buffer.concat([Buffer.from('Exif\0\0', 'latin1'), tiff]);
  const marker = Buffer.from([0xff, 0xe1, (payload.length + 2) >> 8, (payload.length + 2) & 0xff]);
  return Buffer.concat([jpeg.subarray(0, 2), marker, payload, jpeg.subarray(2)]);
}

/**
 * A JPEG with an EXIF block (APP1) holding a 35 mm-equivalent focal length: IFD0 points to an
 * Exif IFD with FocalLengthIn35mmFilm (tag 0xA405, SHORT), little-endian TIFF.
 */
export function withExifFocal(jpeg, focal35mm) {
  const tiff = Buffer.alloc(44);
  tiff.write('II', 0, 'latin1');
  tiff.writeUInt16LE(42, 2);
  tiff.writeUInt32LE(8, 4); // IFD0 offset
  tiff.writeUInt16LE(1, 8); // one entry
  tiff.writeUInt16LE(0x8769, 10); // ExifIFDPointer
  tiff.writeUInt16LE(4, 12); // LONG
  tiff.writeUInt32LE(1, 14);
  tiff.writeUInt32LE(26, 18); // the Exif IFD follows at 26
  tiff.writeUInt32LE(0, 22); // no next IFD
  tiff.writeUInt16LE(1, 26);
  tiff.writeUInt16LE(0xa405, 28); // FocalLengthIn35mmFilm
  tiff.writeUInt16LE(3, 30); // SHORT
  tiff.writeUInt32LE(1, 32);
  tiff.writeUInt16LE(focal35mm, 36);
  tiff.writeUInt32LE(0, 40);
  return withExif(jpeg, tiff);
}

/**
 * A JPEG with an EXIF block (APP1) holding orientation `o` (1–8; tag 0x0112, SHORT, in IFD0),
 * little-endian TIFF.
 */
export function withExifOrientation(jpeg, o) {
  const tiff = Buffer.alloc(26);
  tiff.write('II', 0, 'latin1');
  tiff.writeUInt16LE(42, 2);
  tiff.writeUInt32LE(8, 4); // IFD0 offset
  tiff.writeUInt16LE(1, 8); // one entry
  tiff.writeUInt16LE(0x0112, 10); // Orientation
  tiff.writeUInt16LE(3, 12); // SHORT
  tiff.writeUInt32LE(1, 14);
  tiff.writeUInt16LE(o, 18);
  tiff.writeUInt32LE(0, 22); // no next IFD
  return withExif(jpeg, tiff);
}
