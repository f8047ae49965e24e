// Results you can come back to: the last finished run is kept in IndexedDB (the two frames at
// the working size as RGBA, their names, photo sizes and EXIF facts, the parameters panel, the
// intrinsics, and the outputs shown: pictures, legend and report), so a reload of the tab, on
// purpose or by mistake, loses nothing: the page shows the kept outputs at once, and runs the
// (deterministic) reconstruction of the kept frames again for what the worker holds (the 3D
// cloud, downloads, ground-truth scores), which gives the same outputs; ground-truth files scored
// against it are kept too and scored again. "Start over" forgets it.
//
// document.body.dataset.saved: "yes" once the last result is stored, "" otherwise (tests).

import { $, freeArrays, page } from './ui.js';
import { formIntrinsics } from './params.js';

const DB_NAME = 'superpixel-soup';
const STORE = 'session';
const KEY = 'last';
/** The ground truth scored against the stored result, kept apart (it comes later). */
const TRUTH_KEY = 'truth';
/** Bumped when the record's layout changes; older records are ignored. */
const VERSION = 2;

function openDb() {
  return new Promise((resolve, reject) => {
    const request = indexedDB.open(DB_NAME, 1);
    request.onupgradeneeded = () => request.result.createObjectStore(STORE);
    request.onsuccess = () => resolve(request.result);
    request.onerror = () => reject(request.error);
  });
}

/** Runs `action(store)` in a transaction; resolves to the request's result once committed. */
async function withStore(mode, action) {
  const db = await openDb();
  try {
    return await new Promise((resolve, reject) => {
      const transaction = db.transaction(STORE, mode);
      const request = action(transaction.objectStore(STORE));
      transaction.oncomplete = () => resolve(request.result);
      transaction.onerror = () => reject(transaction.error);
      transaction.onabort = () => reject(transaction.error ?? new Error('aborted'));
    });
  } finally {
    db.close();
  }
}

/** The RGBA pixels of an ImageBitmap. */
function pixelsOf(bitmap) {
  const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
  const context = canvas.getContext('2d');
  context.drawImage(bitmap, 0, 0);
  return context.getImageData(0, 0, bitmap.width, bitmap.height);
}

/** The form's fields by name (numbers, the flow preset and the intrinsics). */
function formValues() {
  const form = $('params');
  return Object.fromEntries([...form.elements].filter((e) => e.name).map((e) => [e.name, e.value]));
}

/**
 * Stores the current frames, parameters and the outputs shown of `result` (pictures, legend,
 * report; the cloud is made again) as the last result.
 */
export async function saveSession(result) {
  document.body.dataset.saved = '';
  page.savedAt = null;
  const frames = page.frames.map((frame) => ({
    name: frame.name,
    width: frame.width,
    height: frame.height,
    exif: frame.exif,
    side: frame.side,
    decoder: frame.decoder,
    pixels: pixelsOf(frame.bitmap),
  }));
  const record = {
    version: VERSION,
    savedAt: Date.now(),
    frames,
    form: formValues(),
    intrinsics: { mode: page.intrinsicsMode, source: $('intrinsics-source').textContent, values: formIntrinsics() },
    outputs: {
      width: result.width,
      height: result.height,
      pictures: result.pictures,
      legend: result.legend,
      report: result.report,
    },
  };
  try {
    await withStore('readwrite', (store) => {
      store.delete(TRUTH_KEY); // scored against an earlier result
      return store.put(record, KEY);
    });
    page.savedAt = record.savedAt;
    document.body.dataset.saved = 'yes';
  } catch (e) {
    // Private browsing or a full disk: the page works on without it.
    console.warn(`the result could not be kept for a reload: ${e.message ?? e}`);
  } finally {
    freeArrays(...frames.map((frame) => frame.pixels.data));
  }
}

/**
 * Keeps the ground-truth files scored against the stored result (`truth`: groundtruth.js's
 * { depth, flow }) beside it, stamped with the result's time, so that a reload scores them
 * again; nothing when the result shown was not stored.
 */
export async function saveTruth(truth) {
  if (page.savedAt === null) {
    return;
  }
  try {
    await withStore('readwrite', (store) => store.put({ savedAt: page.savedAt, truth }, TRUTH_KEY));
  } catch (e) {
    console.warn(`the ground truth could not be kept for a reload: ${e.message ?? e}`);
  }
}

/** The stored last result, or null (none, unreadable, or IndexedDB unavailable). */
export async function loadSession() {
  try {
    const record = await withStore('readonly', (store) => store.get(KEY));
    if (record?.version !== VERSION || record.frames?.length !== 2) {
      return null;
    }
    const kept = await withStore('readonly', (store) => store.get(TRUTH_KEY));
    record.truth = kept?.savedAt === record.savedAt ? kept.truth : null;
    return record;
  } catch {
    return null;
  }
}

/** Forgets the stored result. */
export async function clearSession() {
  document.body.dataset.saved = '';
  page.savedAt = null;
  try {
    await withStore('readwrite', (store) => {
      store.delete(TRUTH_KEY);
      return store.delete(KEY);
    });
  } catch {
    // Nothing stored, or no IndexedDB: nothing to forget.
  }
}

/**
 * Frames of a stored record, as input.js makes them (the pixels at the working size, no file
 * to decode again), and the form's values to put back.
 */
export async function framesOf(record, thumbnailSide) {
  return Promise.all(record.frames.map(async (stored) => {
    const bitmap = await createImageBitmap(stored.pixels, { premultiplyAlpha: 'none', colorSpaceConversion: 'none' });
    const scale = Math.min(1, thumbnailSide / Math.max(bitmap.width, bitmap.height));
    const thumbnail = await createImageBitmap(bitmap, {
      resizeWidth: Math.max(1, Math.round(bitmap.width * scale)),
      resizeHeight: Math.max(1, Math.round(bitmap.height * scale)),
      resizeQuality: 'medium',
    });
    return {
      name: stored.name,
      width: stored.width,
      height: stored.height,
      exif: stored.exif,
      thumbnail,
      source: null,
      bitmap,
      side: stored.side,
      decoder: stored.decoder ?? null,
    };
  }));
}

/** Puts the stored form values back. */
export function restoreForm(values) {
  const form = $('params');
  for (const [name, value] of Object.entries(values)) {
    if (form.elements[name] !== undefined) {
      form.elements[name].value = value;
    }
  }
}
