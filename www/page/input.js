// Input: dropped or picked files, the sample, videos (a scrubber to pick two frames), decoding
// (JPEGs by the library in a worker, other images by the browser) and the frames' thumbnails.
// Every action here ends in a run (worker-client.js) or a message.

import { $, begin, clearAlert, fail, freeArrays, page, setState, setStatus, waitFor } from './ui.js';
import { INTRINSIC_FIELDS, fillForm, refreshIntrinsics, setIntrinsics } from './params.js';
import { cancel, resetProgress, run } from './worker-client.js';
import { dropPending, isTruthFile, resetTruth, restoreTruth, takeTruth } from './groundtruth.js';
import { clearSession, framesOf, loadSession, restoreForm } from './persist.js';
import { showPictures } from './results.js';

/** Options of createImageBitmap: pixels as stored (upright by EXIF), no colour management. */
export const DECODE = { imageOrientation: 'from-image', colorSpaceConversion: 'none', premultiplyAlpha: 'none' };
/** Long side of the thumbnails kept of each frame, in pixels. */
export const THUMBNAIL = 320;
const IMAGE_NAME = /\.(png|jpe?g|webp|gif|bmp|avif|tiff?)$/i;
const VIDEO_NAME = /\.(mp4|m4v|webm|mov|mkv|ogv)$/i;

function kindOf(file) {
  if (file.type.startsWith('image/')) return 'image';
  if (file.type.startsWith('video/')) return 'video';
  if (file.type === '' && IMAGE_NAME.test(file.name)) return 'image';
  if (file.type === '' && VIDEO_NAME.test(file.name)) return 'video';
  return 'other';
}

/** Takes dropped or picked files: two images, or one video; anything else is explained. */
export async function takeFiles(fileList) {
  let files = [...fileList];
  if (files.length === 0) {
    return;
  }
  // Ground truth (groundtruth.js): .pfm, .dpt, .flo, and a PNG named as depth when two other
  // images come with it, or alone once there is a result.
  const pngTruth = files.filter((f) => kindOf(f) === 'image' && isTruthFile(f, { withFrames: true }));
  const imageCount = files.filter((f) => kindOf(f) === 'image').length;
  const truthPngs = imageCount - pngTruth.length === 2 || (imageCount === 1 && pngTruth.length === 1 && page.points > 0);
  const truth = files.filter((f) => isTruthFile(f) || (truthPngs && pngTruth.includes(f)));
  if (truth.length === files.length) {
    await takeTruth(truth);
    return;
  }
  files = files.filter((f) => !truth.includes(f));
  if (document.body.dataset.state === 'running') {
    cancel();
  }
  const current = begin('Reading the files…');
  await takeTruth(truth); // kept until the run below has finished
  const others = files.filter((f) => kindOf(f) === 'other');
  if (others.length > 0) {
    const f = others[0];
    fail(`${f.name} is not an image or a video${f.type ? ` (${f.type})` : ''}. ` +
      'Drop two photos (PNG, JPEG, …) or one video.');
    return;
  }
  const videos = files.filter((f) => kindOf(f) === 'video');
  const images = files.filter((f) => kindOf(f) === 'image');
  if (videos.length > 0) {
    if (videos.length > 1 || images.length > 0) {
      fail('Drop one video on its own, or two photos.');
      return;
    }
    try {
      await loadVideo(videos[0]);
    } catch (e) {
      if (current()) {
        fail(`${videos[0].name}: could not take frames from the video (${e.message}).`);
      }
    }
    return;
  }
  if (images.length === 1) {
    fail(`Only one image was given (${images[0].name}). Two photos of the same scene are needed: ` +
      'pick or drop both at once.');
    return;
  }
  if (images.length > 2) {
    fail(`${images.length} images were given; pick exactly two photos of the same scene.`);
    return;
  }
  let frames;
  try {
    frames = await decodeImages(images, current);
  } catch (e) {
    if (current()) {
      fail(e.message);
    }
    return;
  }
  if (!current()) {
    frames.forEach(closeFrame);
    return;
  }
  hideVideo();
  await setFrames(frames);
  if (current()) {
    await run();
  }
}

/**
 * Decodes an image file at the working size (`decodeFile`) with its EXIF facts, read by the
 * library. `byLibrary` is the library's decode of it (`decodeByLibrary`) when already started.
 */
export async function decodeImage(file, byLibrary = decodeByLibrary(file, maxSide())) {
  const decoded = await decodeFile(file, byLibrary);
  let { exif } = decoded;
  if (exif === null) {
    const bytes = await file.arrayBuffer();
    ({ exif } = await page.pipeline.request('exif', { bytes }, [bytes]));
  }
  return makeFrame(file.name, decoded.bitmap, file, exif, decoded.size, decoded.decoder, decoded.side);
}

/**
 * Decodes `file` upright at the working size for the bound (long side) `byLibrary` was started
 * with: a JPEG by the library's DCT-scaled decoder (`byLibrary`, the promise of
 * `decodeByLibrary`, which may have started already), anything else, and a JPEG that decoder
 * refuses (CMYK, arithmetic coding, damaged), by the browser. Resolves to { bitmap, size: the photo's upright [width, height], exif (null when not
 * read yet), decoder: 'library' | 'browser', side: the bound it was decoded for }.
 */
async function decodeFile(file, byLibrary) {
  const decoded = await byLibrary;
  if (decoded.bitmap) {
    return decoded;
  }
  try {
    const size = await imageSize(file);
    const bitmap = await decodeAt(file, size, decoded.side);
    return { bitmap, size, exif: null, decoder: 'browser', side: decoded.side };
  } catch {
    throw new Error(`${file.name} could not be decoded: the file is damaged or in a format this ` +
      `browser cannot read${decoded.refused}.`);
  }
}

/**
 * `file` decoded upright at the working size for `side` by the library's DCT-scaled JPEG decoder
 * (src/jpeg.rs: no full-size image of the photo is ever made, so two such decodes may run at
 * once): `decodeFile`'s result, or { side, refused } where the browser must decode it (not a
 * JPEG: `refused` empty; refused by the library: why, for the error message should the browser
 * fail too).
 */
async function decodeByLibrary(file, side) {
  if (!(await isJpeg(file))) {
    return { side, refused: '' };
  }
  const decoded = await decodeJpeg(file, side);
  return decoded instanceof Error ?
    { side, refused: ` (the library's JPEG decoder: ${decoded.message})` } :
    { ...decoded, side };
}

/** Whether `file` starts as a JPEG does (SOI, then another marker), whatever its name or type. */
async function isJpeg(file) {
  const head = new Uint8Array(await file.slice(0, 3).arrayBuffer());
  return head.length === 3 && head[0] === 0xff && head[1] === 0xd8 && head[2] === 0xff;
}

/**
 * `decodeFile` of a JPEG by the library (www/pipeline.js `decodeJpeg`), or the Error saying why
 * not when the decoder refuses it or its pixels cannot be made into a bitmap (the browser then
 * decodes the file).
 */
async function decodeJpeg(file, side) {
  let reply;
  try {
    reply = await page.pipeline.decodeJpeg(await file.arrayBuffer(), side);
  } catch (e) {
    console.info(`${file.name}: decoded by the browser (the library's JPEG decoder: ${e.message})`);
    return e;
  }
  const { pixels, frameWidth, frameHeight, width, height, exif } = reply;
  try {
    const image = new ImageData(new Uint8ClampedArray(pixels.buffer), frameWidth, frameHeight);
    const bitmap = await createImageBitmap(image, { premultiplyAlpha: 'none', colorSpaceConversion: 'none' });
    return { bitmap, size: [width, height], exif, decoder: 'library' };
  } catch (e) {
    console.info(`${file.name}: decoded by the browser (its pixels from the library: ${e.message})`);
    return e;
  } finally {
    freeArrays(pixels);
  }
}

/**
 * The upright size of an image file, from an <img> that is never shown (the browser reads the
 * header and the EXIF orientation without decoding the pixels).
 */
function imageSize(file) {
  const url = URL.createObjectURL(file);
  const image = new Image();
  return new Promise((resolve, reject) => {
    image.onload = () => resolve([image.naturalWidth, image.naturalHeight]);
    image.onerror = () => reject(new Error('cannot read the image'));
    image.src = url;
  }).finally(() => URL.revokeObjectURL(url));
}

/** Decodes `file` (upright size `size`) straight to the working size for `side`, by the browser. */
function decodeAt(file, [width, height], side) {
  const [w, h] = workingSize(width, height, side);
  if (w === width && h === height) {
    return createImageBitmap(file, DECODE);
  }
  return createImageBitmap(file, { ...DECODE, resizeWidth: w, resizeHeight: h, resizeQuality: 'high' });
}

/**
 * Decodes image files: the library's JPEG decodes all at once, each in a worker of its own (they
 * hold no full-size image), the browser's one after the other (only one photo is ever held at
 * full size). With `wanted` (a function), stops before the next photo once it returns false (a
 * newer drop or a cancel) and rejects, closing what it decoded.
 */
export async function decodeImages(files, wanted = () => true) {
  const side = maxSide();
  const byLibrary = files.map((file) => decodeByLibrary(file, side));
  // Awaited in order below; a later photo's failure must not go unhandled meanwhile.
  byLibrary.forEach((decode) => decode.catch(() => {}));
  const frames = [];
  try {
    for (const [i, file] of files.entries()) {
      if (!wanted()) {
        throw new Error('the photos were replaced before they were decoded');
      }
      frames.push(await decodeImage(file, byLibrary[i]));
    }
  } catch (e) {
    frames.forEach(closeFrame);
    // The library's decodes of the photos not made into frames: their bitmaps closed as they come.
    byLibrary.slice(frames.length).forEach((decode) => decode.then((d) => d.bitmap?.close(), () => {}));
    throw e;
  }
  return frames;
}

/** The working size's bound on the long side: the form's, else the library's default. */
function maxSide() {
  const value = Number($('params').elements.maxSide.value);
  return Number.isInteger(value) && value >= 32 ? value : page.defaults.options.maxSide;
}

/** `width × height` scaled so the long side is at most `side` (as the library's working_size). */
function workingSize(width, height, side) {
  const long = Math.max(width, height);
  if (long <= side) {
    return [width, height];
  }
  const s = side / long;
  const clamp = (v) => Math.min(side, Math.max(1, Math.round(v * s)));
  return [clamp(width), clamp(height)];
}

/**
 * `full` (decoded pixels, closed here) at the working size for `side`: a photo is kept only at
 * the size the pipeline works at (12 megapixels are 48 MB decoded; 1024 × 768 are 3 MB).
 */
async function shrink(full, side) {
  const [w, h] = workingSize(full.width, full.height, side);
  if (w === full.width && h === full.height) {
    return full;
  }
  try {
    return await createImageBitmap(full, { resizeWidth: w, resizeHeight: h, resizeQuality: 'high' });
  } finally {
    full.close();
  }
}

/**
 * A frame of `full` (the decoded pixels of `source`, or a video frame when `source` is null;
 * closed here unless already at the working size) whose own size is `width × height`: a
 * thumbnail and its pixels at the working size (`bitmap`, for `side`, the long side it was made
 * for: the bound a photo was decoded for, else the form's); `decoder` tells who decoded it
 * ('library', 'browser', or null for a video frame).
 */
async function makeFrame(name, full, source, exif, [width, height] = [full.width, full.height], decoder = null,
  side = maxSide()) {
  const bitmap = await shrink(full, side);
  const scale = Math.min(1, THUMBNAIL / Math.max(bitmap.width, bitmap.height));
  const thumbnail = await createImageBitmap(bitmap, {
    resizeWidth: Math.max(1, Math.round(bitmap.width * scale)),
    resizeHeight: Math.max(1, Math.round(bitmap.height * scale)),
    resizeQuality: 'medium',
  });
  return { name, width, height, exif, thumbnail, source, bitmap, side, decoder };
}

/**
 * The frame's pixels at the working size for one run (a copy; the worker takes and closes it).
 * When the working size was changed in the form, a photo is decoded again from its file.
 */
export async function pixelsForRun(frame) {
  const side = maxSide();
  if (frame.side !== side && frame.source !== null) {
    const [w, h] = workingSize(frame.width, frame.height, side);
    if (w !== frame.bitmap.width || h !== frame.bitmap.height) {
      const { bitmap, decoder } = await decodeFile(frame.source, decodeByLibrary(frame.source, side));
      frame.bitmap.close();
      frame.bitmap = bitmap;
      frame.decoder = decoder;
    }
    frame.side = side;
  }
  return createImageBitmap(frame.bitmap);
}

function closeFrame(frame) {
  frame.thumbnail.close();
  frame.bitmap?.close();
}

/** Makes `frames` the input pair: thumbnails, sizes, intrinsics. */
export async function setFrames(frames, { intrinsics = null, source = '' } = {}) {
  for (const frame of page.frames) {
    if (!frames.includes(frame)) {
      closeFrame(frame);
    }
  }
  page.frames = frames;
  $('frames').hidden = false;
  $('start-over').hidden = false;
  drawThumbnails();
  if (intrinsics !== null) {
    setIntrinsics(intrinsics, 'user', source);
  } else {
    page.intrinsicsMode = 'auto';
    await refreshIntrinsics();
  }
}

function drawThumbnails() {
  page.frames.forEach((frame, i) => {
    const canvas = $(`thumb${i + 1}`);
    const scale = Math.min(canvas.width / frame.width, canvas.height / frame.height);
    const [w, h] = [frame.width * scale, frame.height * scale];
    const context = canvas.getContext('2d');
    context.clearRect(0, 0, canvas.width, canvas.height);
    context.drawImage(frame.thumbnail, (canvas.width - w) / 2, (canvas.height - h) / 2, w, h);
    const focal = frame.exif.focal35mm ? `, ${frame.exif.focal35mm} mm (35 mm equiv.)` : '';
    $(`thumb${i + 1}-info`).textContent = `${frame.name} · ${frame.width} × ${frame.height}${focal}`;
  });
}

export async function swapFrames() {
  if (page.frames.length !== 2) {
    return;
  }
  if (document.body.dataset.state === 'running') {
    cancel();
  }
  const current = begin('Swapping the frames…');
  page.frames = [page.frames[1], page.frames[0]];
  drawThumbnails();
  if (page.intrinsicsMode === 'auto') {
    await refreshIntrinsics(); // frame 1's EXIF decides
  }
  if (current()) {
    await run();
  }
}

export async function loadSample() {
  if (document.body.dataset.state === 'running') {
    cancel();
  }
  const current = begin('Loading the sample…');
  try {
    const fetchFile = async (name) => {
      const response = await fetch(new URL(`../sample/${name}`, import.meta.url));
      if (!response.ok) {
        throw new Error(`sample/${name}: HTTP ${response.status}`);
      }
      return new File([await response.blob()], `sample-${name}`, { type: response.headers.get('content-type') ?? '' });
    };
    const [one, two, intrinsics] = await Promise.all(
      ['frame1.png', 'frame2.png', 'intrinsics.txt'].map(fetchFile),
    );
    const [fx, fy, cx, cy] = (await intrinsics.text()).trim().split(/\s+/).map(Number);
    const frames = await decodeImages([one, two], current);
    if (!current()) {
      frames.forEach(closeFrame);
      return;
    }
    hideVideo();
    await setFrames(frames, { intrinsics: { fx, fy, cx, cy }, source: 'the sample’s exact intrinsics' });
  } catch (e) {
    if (current()) {
      fail(e.name === 'OutOfMemoryError' ? e.message : `Could not load the sample: ${e.message}`);
    }
    return;
  }
  if (current()) {
    await run();
  }
}

/** A dropped video: shows the scrubber and takes two frames (0 s and 0.5 s to start with). */
async function loadVideo(file) {
  const video = $('video');
  if (page.video !== null) {
    URL.revokeObjectURL(page.video.url);
  }
  page.video = { name: file.name, url: URL.createObjectURL(file) };
  video.src = page.video.url;
  setStatus(`Opening ${file.name}…`);
  const token = page.action;
  try {
    await waitFor(video, 'loadeddata');
    // Recorded WebM files often have no duration until their end has been read: seek far
    // beyond it, wait for the duration to become known, and come back.
    while (!Number.isFinite(video.duration)) {
      video.currentTime = Number.MAX_SAFE_INTEGER;
      await waitFor(video, 'durationchange');
    }
  } catch {
    if (page.action !== token) {
      return;
    }
    fail(`${file.name} could not be played: the file is damaged or in a format this browser cannot read.`);
    hideVideo();
    return;
  }
  const duration = Number.isFinite(video.duration) ? video.duration : 0;
  const scrubber = $('video-scrubber');
  scrubber.max = String(duration);
  scrubber.step = String(Math.max(duration / 1000, 0.001));
  $('video-panel').hidden = false;
  const frames = [await videoFrame(0), await videoFrame(Math.min(0.5, duration))];
  await showVideoTime(0);
  if (page.action !== token) {
    return;
  }
  await setFrames(frames);
  setStatus('Pick two frames of the video with the scrubber (“Use as frame 1 / 2”), then press Reconstruct.');
  page.actionStartedAt = null;
  setState('idle');
}

export function hideVideo() {
  $('video-panel').hidden = true;
}

/** Seeks the video to `seconds` and waits until that frame can be drawn. */
export async function showVideoTime(seconds) {
  const video = $('video');
  video.currentTime = seconds;
  await videoSettled(video);
  $('video-time').textContent = `${video.currentTime.toFixed(2)} s`;
  $('video-scrubber').value = String(video.currentTime);
}

/** Resolves once the video is not seeking and has its current frame (events may come late). */
async function videoSettled(video) {
  while (video.seeking || video.readyState < HTMLMediaElement.HAVE_CURRENT_DATA) {
    await waitFor(video, ['seeked', 'canplay']);
  }
}

async function videoFrame(seconds) {
  await showVideoTime(seconds);
  const video = $('video');
  const bitmap = await captureVideo(video);
  const name = `${page.video.name} at ${video.currentTime.toFixed(2)} s`;
  return makeFrame(name, bitmap, null, { focal35mm: null, warning: null });
}

/**
 * The video's current frame as an ImageBitmap. Right after a seek the frame may not be ready to
 * draw yet even when the element says so (Chromium, recorded WebM): try again for a while.
 */
async function captureVideo(video) {
  for (let attempt = 0; ; attempt++) {
    try {
      return await createImageBitmap(video);
    } catch (e) {
      if (attempt === 40) {
        throw e;
      }
      await new Promise((resolve) => setTimeout(resolve, 50));
    }
  }
}

export async function takeVideoFrame(index) {
  try {
    const frame = await videoFrame(Number($('video-scrubber').value));
    const frames = [...page.frames];
    frames[index] = frame;
    await setFrames(frames);
  } catch (e) {
    fail(`Could not take that frame of ${page.video.name}: ${e.message}`);
  }
}

/**
 * Restores the last result kept across a reload (persist.js): its frames and parameters, then
 * runs the reconstruction again (deterministic: the same outputs). Does nothing when none is kept.
 */
export async function restoreLast() {
  const record = await loadSession();
  if (record === null || page.frames.length > 0 || document.body.dataset.state !== 'idle') {
    return;
  }
  const current = begin('Restoring your last result…');
  try {
    restoreForm(record.form);
    const frames = await framesOf(record, THUMBNAIL);
    if (!current()) {
      frames.forEach(closeFrame);
      return;
    }
    showPictures(record.outputs);
    if (record.truth) {
      restoreTruth(record.truth);
    }
    document.body.dataset.restored = 'shown';
    if (record.intrinsics.mode === 'user') {
      await setFrames(frames, { intrinsics: record.intrinsics.values, source: record.intrinsics.source });
    } else {
      await setFrames(frames);
    }
  } catch (e) {
    if (current()) {
      fail(`Could not restore the last result (${e.message}); it was forgotten.`);
    }
    await clearSession();
    return;
  }
  if (current()) {
    await run({ restored: true });
  }
}

/** Forgets everything: the frames, the result (and the worker's memory), the stored session. */
export async function startOver() {
  if (document.body.dataset.state === 'running') {
    cancel();
  }
  page.action = null;
  page.actionStartedAt = null;
  await clearSession();
  dropPending();
  page.frames.forEach(closeFrame);
  page.frames = [];
  page.points = 0;
  page.pipeline.restart(); // a fresh worker: the last result's memory is released
  hideVideo();
  $('frames').hidden = true;
  $('results').hidden = true;
  $('start-over').hidden = true;
  resetTruth();
  resetProgress();
  fillForm(page.defaults.options);
  page.intrinsicsMode = 'auto';
  for (const name of INTRINSIC_FIELDS) {
    $('params').elements[name].value = '';
  }
  $('intrinsics-source').textContent = 'none yet';
  $('intrinsics-reset').hidden = true;
  clearAlert();
  setStatus('Ready. Drop two photos, pick them, or try the sample.');
  setState('idle');
}
