// The worker client and progress: starts the pipeline's Web Worker (www/pipeline.js, which runs
// www/worker.js with the lean wasm module), shows the progress of a run per stage, runs the
// reconstruction on the current frames and cancels it (by restarting the worker).

import { CancelledError, Pipeline } from '../pipeline.js';
import {
  $, WORKER_MODULE, WORKER_THREADS, begin, fail, freeArrays, page, sentence, setState, setStatus, showAlert,
} from './ui.js';
import { fillForm, readOptions } from './params.js';
import { pixelsForRun } from './input.js';
import { fillTimings, showResult } from './results.js';
import { resetTruth, scorePending } from './groundtruth.js';
import { saveSession } from './persist.js';

/**
 * Share of the progress bar per stage (roughly their share of the time on a 1024 × 436 pair,
 * with the fusion's members made by two workers).
 */
const STAGE_WEIGHTS = {
  flow: 0.1, superpixels: 0.06, motion: 0.15, scales: 0.03, refine: 0.08, outputs: 0.02, ensemble: 0.56,
};
export const STAGE_LABELS = {
  flow: 'Optical flow',
  superpixels: 'Superpixels and graphs',
  motion: 'Motions and planes (unit-scale soup)',
  scales: 'Relative scales (contacts)',
  refine: 'Refinement (particle BP, TRW-S)',
  outputs: 'Depth and point clouds',
  ensemble: 'Fusion with other superpixel counts',
};

/** Starts the worker; `onFirstReady` runs once, when the page has the library's defaults. */
export function startPipeline(onFirstReady) {
  page.pipeline = new Pipeline({
    onReady: ({ version, defaults, build, startMs }) => {
      page.workerStartMs.push(startMs);
      document.body.dataset.workerBuild = build; // which wasm build the worker runs (tests)
      if (page.defaults === null) {
        page.readyMs = performance.now(); // since navigation start
        page.defaults = defaults;
        $('version').textContent = version;
        fillForm(defaults.options);
        buildStageList(defaults.stages);
        $('run-button').disabled = false;
        setStatus('Ready. Drop two photos, pick them, or try the sample.');
        setState('idle');
        onFirstReady?.();
      }
    },
    onFailed: (message) => {
      setState('error');
      setStatus('');
      showAlert(`The page cannot run here: ${message}. Build the module with ./serve.sh.`);
    },
    onProgress: (stage, fraction) => showProgress(stage, fraction),
  }, WORKER_MODULE, WORKER_THREADS);
  return page.pipeline;
}

function buildStageList(stages) {
  $('stages').replaceChildren(...stages.map((stage) => {
    const item = document.createElement('li');
    item.dataset.stage = stage;
    item.innerHTML = '<span class="name"></span><span class="time"></span>';
    item.querySelector('.name').textContent = STAGE_LABELS[stage] ?? stage;
    return item;
  }));
}

/** Index of the furthest stage reached in this run: a later stage start before it is a new pass. */
let furthestStage = -1;
/** Passes of the pipeline in this run (a second one is made from finer flow; see showProgress). */
let passes = 1;

export function resetProgress() {
  furthestStage = -1;
  passes = 1;
  $('progress').value = 0;
  for (const item of $('stages').children) {
    item.className = '';
    item.querySelector('.time').textContent = '';
  }
}

function showProgress(stage, fraction) {
  const items = [...$('stages').children];
  const index = items.findIndex((item) => item.dataset.stage === stage);
  // The pipeline starts over from the flow when too few of the depths were pinned: say so
  // rather than let the bar run back without a word.
  if (index < furthestStage) {
    passes += 1;
  }
  furthestStage = index;
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
  const again = passes > 1 ? ` (pass ${passes}, finer flow: the last pass pinned too few of the scales, left the camera's motion ambiguous or found no ground)` : '';
  setStatus(`${STAGE_LABELS[stage] ?? stage}${again}…`);
}

/** Runs the reconstruction on the current frames with the form's options. */
export async function run({ resizeSecond = false, restored = false } = {}) {
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
  const current = begin(restored ? 'Restoring your last result…' : 'Starting…');
  resetProgress();
  if (!restored) {
    $('results').hidden = true; // a restored result shows its kept outputs meanwhile
  }
  resetTruth();
  const started = performance.now();
  try {
    const bitmaps = await Promise.all(page.frames.map(pixelsForRun));
    const { result } = await page.pipeline.request('run', { frames: bitmaps, options }, bitmaps);
    const received = performance.now();
    if (!current()) {
      return;
    }
    // The worker's memory goes before the 3D view takes its own (www/pipeline.js, Memory); the
    // worker computes the same result again from the same frames and options when shown. The
    // frames are copied now (working size, a few MiB): the user may replace the page's frames
    // before that second computation starts, and the shown result must still be computable.
    const kept = await Promise.all(page.frames.map((frame) => createImageBitmap(frame.bitmap)));
    if (!current()) {
      kept.forEach((frame) => frame.close());
      return;
    }
    page.pipeline.release({ frames: kept, options, flow: result.flow });
    await showResult(result);
    if (!current()) {
      return; // another action (new photos, start over) came while the result was shown
    }
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
    setStatus(`${restored ? 'Restored your last result (computed again)' : 'Done'} in ` +
      `${(page.lastRun.totalMs / 1000).toFixed(1)} s: ${result.cloud.count.toLocaleString('en')} points.`);
    setState('done');
    await saveSession(result);
    freeArrays(...Object.values(result.pictures)); // drawn and kept: not needed any more
    if (current()) {
      await scorePending({ restored });
    }
    if (current()) {
      // Clouds, downloads and scores need the result in the worker: computed again now.
      page.pipeline.recompute().catch(() => {});
    }
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

export function cancel() {
  page.action = null;
  page.actionStartedAt = null;
  page.pipeline.restart();
  resetProgress();
  setStatus('Cancelled.');
  setState('idle');
}
