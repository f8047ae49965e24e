// The page (index.html). Two photos (or two frames of a video) go in; the reconstruction runs in
// a Web Worker (www/worker.js, through www/pipeline.js) with the library compiled to wasm; the
// result is shown in the 3D viewer (the full wasm build, www/pkg/superpixel_soup.js) and as
// pictures, with downloads of the output files. No algorithm lives here: this file moves pixels,
// options and results between the form, the worker and the viewer.
//
// document.body.dataset.state: "loading" (worker not ready yet) → "idle" → "running" →
// "done" or "error"; a cancel goes back to "idle". Errors are shown in #alert (role="alert").
// URL options: ?backend=auto|webgpu|webgl2 picks the viewer's graphics backend; ?worker=full
// runs the pipeline with the full wasm build instead of the lean one (for measurements).
// window.soupPage exposes the viewer, the worker and the last run's timings (tests, benchmark).

import { CancelledError, Pipeline } from './pipeline.js';
import { wireViewerControls } from './viewer-controls.js';

const $ = (id) => document.getElementById(id);

const URL_OPTIONS = new URLSearchParams(location.search);
const BACKEND = URL_OPTIONS.get('backend') ?? 'auto';
const WORKER_MODULE = URL_OPTIONS.get('worker') === 'full' ? 'full' : 'lean';
const BACKEND_NAMES = { webgpu: 'WebGPU', webgl2: 'WebGL2' };
/** Share of the progress bar per stage (roughly their share of the time on a 1024 × 436 pair). */
const STAGE_WEIGHTS = { flow: 0.25, superpixels: 0.2, motion: 0.35, scales: 0.15, outputs: 0.05 };
const STAGE_LABELS = {
  flow: 'Optical flow',
  superpixels: 'Superpixels and graphs',
  motion: 'Motions and planes (unit-scale soup)',
  scales: 'Relative scales (ARAP)',
  outputs: 'Depth and point clouds',
};
/** Options of createImageBitmap: pixels as stored (upright by EXIF), no colour management. */
const DECODE = { imageOrientation: 'from-image', colorSpaceConversion: 'none', premultiplyAlpha: 'none' };
/** Long side of the thumbnails kept of each frame, in pixels. */
const THUMBNAIL = 320;
const IMAGE_NAME = /\.(png|jpe?g|webp|gif|bmp|avif|tiff?)$/i;
const VIDEO_NAME = /\.(mp4|m4v|webm|mov|mkv|ogv)$/i;

const page = {
  /** Defaults and names from the library (`pageDefaults`), once the worker is ready. */
  defaults: null,
  /**
   * The two frames: { name, width, height, exif: { focal35mm, warning }, thumbnail (a small
   * ImageBitmap), and the pixels: `source` (the file, decoded again for each run) and/or
   * `bitmap` (decoded pixels: a video frame's, or a photo's until its first run takes them) }.
   * Large photos are not kept decoded: 12 megapixels are 48 MB each.
   */
  frames: [],
  /** "auto": intrinsics from EXIF or the default (resolved by the library); "user": the form's. */
  intrinsicsMode: 'auto',
  /** Point count of the last result's (organised) cloud; the worker keeps the cloud itself. */
  points: 0,
  viewer: null,
  /** Timings of the last finished run (milliseconds), for the benchmark. */
  lastRun: null,
  /** When the current user action began (performance.now()), for lastRun.endToEndMs. */
  actionStartedAt: null,
  /** Milliseconds from navigation to the page being ready (worker loaded), and to the viewer. */
  readyMs: null,
  viewerReadyMs: null,
  /** Milliseconds from `new Worker` to its module loaded, per (re)start. */
  workerStartMs: [],
  video: null,
};
window.soupPage = page;

const pipeline = new Pipeline({
  onReady: ({ version, defaults, startMs }) => {
    page.workerStartMs.push(startMs);
    if (page.defaults === null) {
      page.readyMs = performance.now(); // since navigation start
      page.defaults = defaults;
      $('version').textContent = version;
      fillForm(defaults.options);
      buildStageList(defaults.stages);
      $('run-button').disabled = false;
      setStatus('Ready. Drop two photos, pick them, or try the sample.');
      setState('idle');
    }
  },
  onFailed: (message) => {
    setState('error');
    setStatus('');
    showAlert(`The page cannot run here: ${message}. Build the module with ./serve.sh.`);
  },
  onProgress: (stage, fraction) => showProgress(stage, fraction),
}, WORKER_MODULE);
page.pipeline = pipeline;

// ---------------------------------------------------------------------------------------------
// State, status and errors

function setState(state) {
  document.body.dataset.state = state;
  const running = state === 'running';
  $('cancel-button').disabled = !running;
  $('run-button').disabled = running || page.defaults === null;
}

function setStatus(text) {
  $('status').textContent = text;
}

/** Shows `message` in the alert, with an optional action button { label, run }. */
function showAlert(message, action = null) {
  const alert = $('alert');
  alert.replaceChildren(document.createTextNode(message));
  if (action !== null) {
    const button = document.createElement('button');
    button.type = 'button';
    button.className = 'button';
    button.textContent = action.label;
    button.addEventListener('click', action.run);
    alert.append(' ', button);
  }
  alert.hidden = false;
}

function clearAlert() {
  $('alert').hidden = true;
  $('alert').replaceChildren();
}

/**
 * Starts a user action (reading input, a run): clears the alert and sets the state to
 * "running" until the action ends. Returns a check that turns false once a later action or a
 * cancel has taken over, so an action stops after its next await.
 */
function begin(status) {
  page.actionStartedAt ??= performance.now();
  const token = {};
  page.action = token;
  clearAlert();
  setStatus(status);
  setState('running');
  return () => page.action === token;
}

/** Shows an error and leaves the page ready for the next input. */
function fail(message, action = null) {
  page.actionStartedAt = null;
  showAlert(message, action);
  setStatus('');
  setState('error');
}

/** `text` with a capital first letter (the library's messages start in lower case). */
const sentence = (text) => text.charAt(0).toUpperCase() + text.slice(1);

// ---------------------------------------------------------------------------------------------
// Input: files, drops, the sample, videos

function kindOf(file) {
  if (file.type.startsWith('image/')) return 'image';
  if (file.type.startsWith('video/')) return 'video';
  if (file.type === '' && IMAGE_NAME.test(file.name)) return 'image';
  if (file.type === '' && VIDEO_NAME.test(file.name)) return 'video';
  return 'other';
}

/** Takes dropped or picked files: two images, or one video; anything else is explained. */
async function takeFiles(fileList) {
  const files = [...fileList];
  if (files.length === 0) {
    return;
  }
  if (document.body.dataset.state === 'running') {
    cancel();
  }
  const current = begin('Reading the files…');
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
    frames = await Promise.all(images.map(decodeImage));
  } catch (e) {
    if (current()) {
      fail(e.message);
    }
    return;
  }
  if (!current()) {
    return;
  }
  hideVideo();
  await setFrames(frames);
  if (current()) {
    await run();
  }
}

/** Decodes an image file with the browser and reads its EXIF block with the library. */
async function decodeImage(file) {
  let bitmap;
  try {
    bitmap = await createImageBitmap(file, DECODE);
  } catch {
    throw new Error(`${file.name} could not be decoded: the file is damaged or in a format this ` +
      'browser cannot read.');
  }
  const bytes = await file.arrayBuffer();
  const { exif } = await pipeline.request('exif', { bytes }, [bytes]);
  return makeFrame(file.name, bitmap, file, exif);
}

/** A frame of `bitmap` (the decoded pixels of `source`, or a video frame when `source` is null). */
async function makeFrame(name, bitmap, source, exif) {
  const scale = Math.min(1, THUMBNAIL / Math.max(bitmap.width, bitmap.height));
  const thumbnail = await createImageBitmap(bitmap, {
    resizeWidth: Math.max(1, Math.round(bitmap.width * scale)),
    resizeHeight: Math.max(1, Math.round(bitmap.height * scale)),
    resizeQuality: 'medium',
  });
  return { name, width: bitmap.width, height: bitmap.height, exif, thumbnail, source, bitmap };
}

/**
 * The frame's full pixels for one run (the worker takes and closes them): a photo's decoded
 * pixels the first time, then decoded again from its file; a copy of a video frame.
 */
async function pixelsForRun(frame) {
  if (frame.source === null) {
    return createImageBitmap(frame.bitmap);
  }
  if (frame.bitmap !== null) {
    const bitmap = frame.bitmap;
    frame.bitmap = null;
    return bitmap;
  }
  return createImageBitmap(frame.source, DECODE);
}

function closeFrame(frame) {
  frame.thumbnail.close();
  frame.bitmap?.close();
}

/** Makes `frames` the input pair: thumbnails, sizes, intrinsics. */
async function setFrames(frames, { intrinsics = null, source = '' } = {}) {
  for (const frame of page.frames) {
    if (!frames.includes(frame)) {
      closeFrame(frame);
    }
  }
  page.frames = frames;
  $('frames').hidden = false;
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

async function swapFrames() {
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

async function loadSample() {
  if (document.body.dataset.state === 'running') {
    cancel();
  }
  const current = begin('Loading the sample…');
  try {
    const fetchFile = async (name) => {
      const response = await fetch(new URL(`sample/${name}`, import.meta.url));
      if (!response.ok) {
        throw new Error(`sample/${name}: HTTP ${response.status}`);
      }
      return new File([await response.blob()], `sample-${name}`, { type: response.headers.get('content-type') ?? '' });
    };
    const [one, two, intrinsics] = await Promise.all(
      ['frame1.png', 'frame2.png', 'intrinsics.txt'].map(fetchFile),
    );
    const [fx, fy, cx, cy] = (await intrinsics.text()).trim().split(/\s+/).map(Number);
    const frames = await Promise.all([one, two].map(decodeImage));
    if (!current()) {
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

function hideVideo() {
  $('video-panel').hidden = true;
}

/** Seeks the video to `seconds` and waits until that frame can be drawn. */
async function showVideoTime(seconds) {
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

async function takeVideoFrame(index) {
  try {
    const frame = await videoFrame(Number($('video-scrubber').value));
    const frames = [...page.frames];
    frames[index] = frame;
    await setFrames(frames);
  } catch (e) {
    fail(`Could not take that frame of ${page.video.name}: ${e.message}`);
  }
}

/** Resolves on the first of `events` (a name or a list) from `target`; rejects on its `error`. */
function waitFor(target, events) {
  const names = [events].flat();
  return new Promise((resolve, reject) => {
    const finish = (settle) => (event) => {
      for (const name of names) {
        target.removeEventListener(name, ok);
      }
      target.removeEventListener('error', bad);
      settle(event);
    };
    const ok = finish(resolve);
    const bad = finish(() => reject(new Error(`${names.join(' or ')} failed`)));
    for (const name of names) {
      target.addEventListener(name, ok);
    }
    target.addEventListener('error', bad);
  });
}

// ---------------------------------------------------------------------------------------------
// Parameters

function fillForm(options) {
  const form = $('params');
  const select = form.elements.flowPreset;
  if (select.options.length === 0) {
    for (const name of page.defaults.flowPresets) {
      select.add(new Option(name, name));
    }
  }
  form.elements.maxSide.value = options.maxSide;
  select.value = options.flowPreset;
  form.elements.count.value = options.params.superpixels.count;
  form.elements.compactness.value = options.params.superpixels.compactness;
  form.elements.k.value = options.params.k;
  form.elements.beta.value = options.params.beta;
}

const INTRINSIC_FIELDS = ['fx', 'fy', 'cx', 'cy'];

/** Fills the intrinsics from the library's resolution (EXIF of frame 1, else the default). */
async function refreshIntrinsics() {
  const [frame] = page.frames;
  if (frame === undefined) {
    return;
  }
  const { camera } = await pipeline.request('intrinsics', {
    width: frame.width,
    height: frame.height,
    focal35mm: frame.exif.focal35mm,
  });
  const source = camera.source === 'exif'
    ? `EXIF of frame 1 (${frame.exif.focal35mm} mm, 35 mm equivalent)`
    : 'default guess (no EXIF focal length): f = long side, centre of the image';
  setIntrinsics(camera.intrinsics, 'auto', source);
}

function setIntrinsics(intrinsics, mode, source) {
  page.intrinsicsMode = mode;
  const form = $('params');
  for (const name of INTRINSIC_FIELDS) {
    form.elements[name].value = String(Math.round(intrinsics[name] * 1000) / 1000);
  }
  $('intrinsics-source').textContent = source;
  $('intrinsics-reset').hidden = mode !== 'user';
}

/** The run's options from the form (library defaults for what the form does not show). */
function readOptions(resizeSecond) {
  const form = $('params');
  for (const input of form.querySelectorAll('input')) {
    if (!input.checkValidity()) {
      const label = input.closest('label')?.firstChild?.textContent?.trim() ?? input.name;
      throw new Error(`${label}: ${input.validationMessage}`);
    }
  }
  const number = (name) => Number(form.elements[name].value);
  const options = structuredClone(page.defaults.options);
  options.maxSide = number('maxSide');
  options.flowPreset = form.elements.flowPreset.value;
  options.params.superpixels.count = number('count');
  options.params.superpixels.compactness = number('compactness');
  options.params.k = number('k');
  options.params.beta = number('beta');
  if (page.intrinsicsMode === 'user') {
    options.intrinsics = Object.fromEntries(INTRINSIC_FIELDS.map((n) => [n, number(n)]));
  }
  options.exif1 = page.frames[0].exif;
  options.exif2 = page.frames[1].exif;
  options.resizeSecond = resizeSecond;
  return options;
}

// ---------------------------------------------------------------------------------------------
// Running, progress, cancel

function buildStageList(stages) {
  $('stages').replaceChildren(...stages.map((stage) => {
    const item = document.createElement('li');
    item.dataset.stage = stage;
    item.innerHTML = '<span class="name"></span><span class="time"></span>';
    item.querySelector('.name').textContent = STAGE_LABELS[stage] ?? stage;
    return item;
  }));
}

function resetProgress() {
  $('progress').value = 0;
  for (const item of $('stages').children) {
    item.className = '';
    item.querySelector('.time').textContent = '';
  }
}

function showProgress(stage, fraction) {
  const items = [...$('stages').children];
  const index = items.findIndex((item) => item.dataset.stage === stage);
  const weight = (s) => STAGE_WEIGHTS[s] ?? 1 / items.length;
  let done = 0;
  items.forEach((item, i) => {
    item.className = i < index ? 'done' : i === index ? 'active' : '';
    if (i < index) {
      done += weight(item.dataset.stage);
    }
  });
  const total = items.reduce((sum, item) => sum + weight(item.dataset.stage), 0);
  $('progress').value = Math.min(1, (done + weight(stage) * fraction) / total);
  setStatus(`${STAGE_LABELS[stage] ?? stage}…`);
}

/** Runs the reconstruction on the current frames with the form's options. */
async function run({ resizeSecond = false } = {}) {
  if (page.frames.length !== 2) {
    fail('Two images are needed: drop or pick two photos of the same scene (or a video).');
    return;
  }
  let options;
  try {
    options = readOptions(resizeSecond);
  } catch (e) {
    fail(e.message);
    return;
  }
  const current = begin('Starting…');
  resetProgress();
  $('results').hidden = true;
  const started = performance.now();
  try {
    const bitmaps = await Promise.all(page.frames.map(pixelsForRun));
    const { result } = await pipeline.request('run', { frames: bitmaps, options }, bitmaps);
    const received = performance.now();
    if (!current()) {
      return;
    }
    await showResult(result);
    const finished = performance.now();
    page.lastRun = {
      // From the user's action (files picked, sample clicked, Reconstruct) to the result shown.
      endToEndMs: finished - page.actionStartedAt,
      totalMs: finished - started,
      workerMs: received - started,
      showMs: finished - received,
      worker: result.timings,
      stagesMs: Object.fromEntries(result.report.timings_ms),
      memoryBytes: result.memoryBytes,
    };
    page.actionStartedAt = null;
    fillTimings(result.report, page.lastRun);
    $('progress').value = 1;
    for (const item of $('stages').children) {
      item.className = 'done';
    }
    setStatus(`Done in ${(page.lastRun.totalMs / 1000).toFixed(1)} s: ` +
      `${result.cloud.count.toLocaleString('en')} points.`);
    setState('done');
  } catch (e) {
    if (e instanceof CancelledError || !current()) {
      return;
    }
    failRun(e);
  }
}

/** Explains a failed run (the library's message); a size mismatch offers to resize frame 2. */
function failRun(error) {
  const [one] = page.frames;
  const message = sentence(error.message);
  switch (error.name) {
    case 'SizeMismatchError':
      fail(message, {
        label: `Resize frame 2 to ${one.width} × ${one.height} and reconstruct`,
        run: () => run({ resizeSecond: true }),
      });
      break;
    case 'NoParallaxError':
      fail(`${message}. The two photos must be taken from different positions, or show motion.`);
      break;
    default:
      fail(message);
  }
}

function cancel() {
  page.action = null;
  page.actionStartedAt = null;
  pipeline.restart();
  resetProgress();
  setStatus('Cancelled.');
  setState('idle');
}

// ---------------------------------------------------------------------------------------------
// Results

async function showResult(result) {
  const { width, height } = result;
  const draw = (id, rgba) => {
    const canvas = $(id);
    canvas.width = width;
    canvas.height = height;
    canvas.getContext('2d').putImageData(new ImageData(new Uint8ClampedArray(rgba.buffer), width, height), 0, 0);
  };
  draw('picture-depth', result.pictures.depth);
  draw('picture-organised', result.pictures.depth);
  draw('picture-unorganised', result.pictures.unorganised);
  draw('picture-superpixels', result.pictures.superpixels);
  draw('picture-flow', result.pictures.flow);
  drawLegend(result.legend);
  $('superpixel-count').textContent = result.report.superpixels.toLocaleString('en');
  fillSummary(result.report);
  page.points = result.cloud.count;
  $('soup-mode').value = 'organised';
  $('results').hidden = false;
  const viewer = await viewerReady;
  if (viewer !== null) {
    showCloud(viewer, result.cloud);
  }
}

function showCloud(viewer, cloud) {
  viewer.setCloud(cloud.positions1, cloud.positions2, cloud.colours, cloud.labels);
  viewer.render();
}

function drawLegend(legend) {
  const canvas = $('legend');
  if (legend === null) {
    $('legend-near').textContent = 'no depth known';
    $('legend-far').textContent = '';
    return;
  }
  canvas.width = legend.colours.length;
  const pixels = new Uint8ClampedArray(legend.colours.flatMap(([r, g, b]) => [r, g, b, 255]));
  canvas.getContext('2d').putImageData(new ImageData(pixels, legend.colours.length, 1), 0, 0);
  const depths = legend.depths;
  const format = (z) => (z >= 100 ? z.toFixed(0) : z.toPrecision(2));
  $('legend-near').textContent = `near ${format(depths[0])}`;
  $('legend-far').textContent = `far ${format(depths[depths.length - 1])} (relative units)`;
}

function fillSummary(report) {
  const k = report.camera.intrinsics;
  const rows = [
    ['Input size', `${report.input_size[0]} × ${report.input_size[1]}`],
    ['Working size', `${report.working_size[0]} × ${report.working_size[1]}`],
    ['Intrinsics (working size)', `fx ${k.fx.toFixed(1)}, fy ${k.fy.toFixed(1)}, cx ${k.cx.toFixed(1)}, cy ${k.cy.toFixed(1)}`],
    ['Intrinsics from', { user: 'you (or the sample)', exif: 'EXIF focal length', default: 'default guess' }[report.camera.source] ?? report.camera.source],
    ['Superpixels', `${report.superpixels} (${report.degenerate} without a plane of their own)`],
    ['Motion hypotheses', String(report.hypotheses)],
    ['Trusted flow', `${(100 * report.reliable_flow).toFixed(1)} % of pixels`],
    ['ARAP energy', `${report.arap.energy_start.toPrecision(4)} → ${report.arap.energy_end.toPrecision(4)}`],
  ];
  for (const note of report.notes) {
    rows.push(['Note', note]);
  }
  $('summary').replaceChildren(...rows.flatMap(([term, value]) => {
    const dt = document.createElement('dt');
    dt.textContent = term;
    const dd = document.createElement('dd');
    dd.textContent = value;
    return [dt, dd];
  }));
}

function fillTimings(report, run) {
  const rows = report.timings_ms.map(([stage, ms]) => [STAGE_LABELS[stage] ?? stage, ms]);
  rows.unshift(['Reading the pixels (worker)', run.worker.pixelsMs]);
  rows.push(['Pictures and clouds (worker)', run.worker.collectMs]);
  rows.push(['Display (viewer, pictures)', run.showMs]);
  rows.push(['Total', run.totalMs]);
  for (const item of $('stages').children) {
    const ms = run.stagesMs[item.dataset.stage];
    item.querySelector('.time').textContent = ms === undefined ? '' : `${Math.round(ms)} ms`;
  }
  $('timings').tBodies[0].replaceChildren(...rows.map(([name, ms]) => {
    const row = document.createElement('tr');
    row.innerHTML = '<th scope="row"></th><td></td>';
    row.cells[0].textContent = name;
    row.cells[1].textContent = `${Math.round(ms)} ms`;
    return row;
  }));
}

async function switchSoup() {
  const viewer = await viewerReady;
  const soup = $('soup-mode').value;
  if (viewer === null || page.points === 0) {
    return;
  }
  try {
    const { cloud } = await pipeline.request('cloud', { soup });
    showCloud(viewer, cloud);
  } catch (e) {
    if (!(e instanceof CancelledError)) {
      showAlert(e.message);
    }
  }
}

async function download(name) {
  try {
    const { bytes, mediaType } = await pipeline.request('export', { name });
    const url = URL.createObjectURL(new Blob([bytes], { type: mediaType }));
    const link = document.createElement('a');
    link.href = url;
    link.download = name;
    document.body.append(link);
    link.click();
    link.remove();
    setTimeout(() => URL.revokeObjectURL(url), 10_000);
  } catch (e) {
    if (!(e instanceof CancelledError)) {
      showAlert(`Could not make ${name}: ${e.message}`);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The 3D viewer (loaded once the worker is, so that on a slow network the worker's smaller
// module comes first and the page is usable sooner; the page works without the viewer)

const viewerReady = (async () => {
  try {
    await pipeline.ready.catch(() => {});
    const wasm = await import('./pkg/superpixel_soup.js');
    await wasm.default();
    const viewer = await wasm.Viewer.create($('view'), { backend: BACKEND });
    page.viewer = viewer;
    page.viewerReadyMs = performance.now();
    document.body.dataset.backend = viewer.backend;
    $('backend-name').textContent = `Drawn with ${BACKEND_NAMES[viewer.backend] ?? viewer.backend}.`;
    wireViewerControls(viewer);
    return viewer;
  } catch (e) {
    const message = $('viewer-message');
    message.textContent = `The 3D view cannot run in this browser: ${e.message ?? e}. ` +
      'The pictures and downloads below still work.';
    message.hidden = false;
    $('view').hidden = true;
    $('controls').hidden = true;
    return null;
  }
})();
page.viewerReady = viewerReady;

// ---------------------------------------------------------------------------------------------
// Wiring

function wire() {
  const input = $('file-input');
  input.addEventListener('change', () => {
    const files = [...input.files];
    input.value = ''; // the same files can be picked again
    takeFiles(files);
  });
  $('sample-button').addEventListener('click', loadSample);
  $('swap-button').addEventListener('click', swapFrames);
  $('cancel-button').addEventListener('click', cancel);
  $('params').addEventListener('submit', (event) => {
    event.preventDefault();
    run();
  });
  $('defaults-button').addEventListener('click', () => fillForm(page.defaults.options));
  for (const name of INTRINSIC_FIELDS) {
    $('params').elements[name].addEventListener('input', () => {
      page.intrinsicsMode = 'user';
      $('intrinsics-source').textContent = 'yours (edited)';
      $('intrinsics-reset').hidden = false;
    });
  }
  $('intrinsics-reset').addEventListener('click', refreshIntrinsics);
  $('soup-mode').addEventListener('change', switchSoup);
  for (const button of $('downloads').querySelectorAll('button[data-file]')) {
    button.addEventListener('click', () => download(button.dataset.file));
  }
  $('video-scrubber').addEventListener('input', () => showVideoTime(Number($('video-scrubber').value)));
  $('take-frame1').addEventListener('click', () => takeVideoFrame(0));
  $('take-frame2').addEventListener('click', () => takeVideoFrame(1));

  // Drops anywhere on the page.
  let depth = 0;
  const overlay = $('drop-overlay');
  const carriesFiles = (event) => [...(event.dataTransfer?.types ?? [])].includes('Files');
  document.addEventListener('dragenter', (event) => {
    if (carriesFiles(event)) {
      depth += 1;
      overlay.hidden = false;
    }
  });
  document.addEventListener('dragleave', () => {
    depth = Math.max(0, depth - 1);
    overlay.hidden = depth === 0;
  });
  document.addEventListener('dragover', (event) => {
    if (carriesFiles(event)) {
      event.preventDefault();
      event.dataTransfer.dropEffect = 'copy';
    }
  });
  document.addEventListener('drop', (event) => {
    event.preventDefault();
    depth = 0;
    overlay.hidden = true;
    if (page.defaults !== null) {
      takeFiles(event.dataTransfer.files);
    }
  });
}

wire();
