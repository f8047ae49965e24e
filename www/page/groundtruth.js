// Ground-truth scoring: the user drops or picks the true depth of frame 1 (PFM, Sintel .dpt or a
// 16-bit PNG with a scale) and optionally the true flow 1 → 2 (.flo), with the two frames or
// after the run. The worker scores them with the library's metrics (src/web/ground_truth.rs, the
// same code as `soup eval`); this module shows MRE, AbsRel, δ<1.25 (and EPE), the per-pixel
// relative-error picture with its legend, and explains bad or mismatched files in the alert
// while the result stays usable. The scores also go into the downloaded report.json. The files
// scored last are kept with the stored result (persist.js), so a reload scores them again.
//
// document.body.dataset.truth: "" (nothing scored), "scoring", "scored" or "error" (tests).

import { CancelledError } from '../pipeline.js';
import { saveTruth } from './persist.js';
import { $, page, sentence, showAlert } from './ui.js';

/** Names of ground-truth files: depth (PFM, Sintel) and flow. */
const TRUTH_NAME = /\.(pfm|dpt|flo)$/i;
/** A PNG dropped with the two frames (or alone after a run) is ground-truth depth when so named. */
const TRUTH_PNG_NAME = /(depth|disp|gt|truth)[^/]*\.png$/i;

/** Whether `file` is a ground-truth file by its name (`withFrames`: dropped with two photos). */
export function isTruthFile(file, { withFrames = false, alone = false } = {}) {
  if (TRUTH_NAME.test(file.name)) {
    return true;
  }
  return (withFrames || alone) && TRUTH_PNG_NAME.test(file.name);
}

/** Files waiting for the run to finish; the last depth PNG (scored again when its scale changes). */
const pending = [];
let lastPng = null;

function setTruthState(state) {
  document.body.dataset.truth = state;
}

/**
 * The files scored against the result shown, the last of each kind: `depth` ({ file, pngScale },
 * the scale of a 16-bit PNG) and `flow` (a File); kept with the stored result.
 */
const scoredFiles = { depth: null, flow: null };

/** Clears the scores shown (a new run starts). */
export function resetTruth() {
  scoredFiles.depth = null;
  scoredFiles.flow = null;
  rows.clear();
  $('truth-results').hidden = true;
  $('truth-figure').hidden = true;
  $('truth-metrics').replaceChildren();
  setTruthState('');
}

/**
 * Takes ground-truth files: scored now when there is a result, else kept until the run that
 * is starting (or the next one) finishes.
 */
export async function takeTruth(files) {
  if (files.length === 0) {
    return;
  }
  if (document.body.dataset.state !== 'done' || page.points === 0) {
    pending.push(...files);
    if (document.body.dataset.state !== 'running') {
      showAlert(`${files.map((f) => f.name).join(', ')}: kept as ground truth; it is scored once the ` +
        'two photos are reconstructed. Drop or pick the photos.');
    }
    return;
  }
  await scoreFiles(files);
}

/**
 * Scores what was kept waiting (called once a run has finished; `restored`: the run restoring
 * the stored result, whose kept ground truth is scored too).
 */
export async function scorePending({ restored = false } = {}) {
  const files = [...pending.splice(0), ...(restored ? restoredFiles : [])];
  restoredFiles = [];
  if (files.length > 0) {
    await scoreFiles(files);
  }
}

/** Ground truth kept with a stored result, waiting for the run that restores it. */
let restoredFiles = [];

/**
 * Ground truth kept with a restored result (`saveTruth`'s { depth, flow }): scored again once
 * the run restoring that result finishes (and forgotten by any other run), with the PNG scale
 * it had.
 */
export function restoreTruth({ depth, flow }) {
  restoredFiles = [];
  if (depth !== null) {
    if (depth.pngScale !== null) {
      $('truth-scale').value = String(depth.pngScale);
    }
    restoredFiles.push(depth.file);
  }
  if (flow !== null) {
    restoredFiles.push(flow);
  }
}

/** Forgets files kept waiting (the user started over). */
export function dropPending() {
  pending.length = 0;
  restoredFiles = [];
  lastPng = null;
}

async function scoreFiles(files) {
  setTruthState('scoring');
  let failed = false;
  // Depth first, so that the flow's EPE joins the depth rows.
  const ordered = [...files].sort((a, b) => /\.flo$/i.test(a.name) - /\.flo$/i.test(b.name));
  for (const file of ordered) {
    try {
      await scoreFile(file);
    } catch (e) {
      if (e instanceof CancelledError) {
        return;
      }
      failed = true;
      const message = sentence(e.message.replace(/^invalid parameter: /, ''));
      showAlert(`${file.name}: ${message}${message.endsWith('.') ? '' : '.'}`);
    }
  }
  await saveTruth({ ...scoredFiles });
  setTruthState(failed ? 'error' : 'scored');
}

async function scoreFile(file) {
  const bytes = await file.arrayBuffer();
  if (/\.flo$/i.test(file.name)) {
    const { score } = await page.pipeline.request('score-flow', { name: file.name, bytes }, [bytes]);
    showFlowScore(score);
    scoredFiles.flow = file;
    return;
  }
  const head = new Uint8Array(bytes, 0, Math.min(4, bytes.byteLength));
  const isPng = head[0] === 0x89 && head[1] === 0x50; // \x89PNG
  if (isPng) {
    lastPng = file;
  }
  const scale = $('truth-scale').value === '' ? null : Number($('truth-scale').value);
  const { score, picture } = await page.pipeline.request(
    'score-depth',
    { name: file.name, bytes, pngScale: isPng ? scale : null },
    [bytes],
  );
  showDepthScore(score, picture);
  scoredFiles.depth = { file, pngScale: isPng ? scale : null };
}

/** Scores the last depth PNG again with the scale just entered. */
export async function rescorePng() {
  if (lastPng !== null && document.body.dataset.state === 'done') {
    await scoreFiles([lastPng]);
  }
}

const rows = new Map();

function showRows() {
  $('truth-metrics').replaceChildren(...[...rows].flatMap(([term, value]) => {
    const dt = document.createElement('dt');
    dt.textContent = term;
    const dd = document.createElement('dd');
    dd.textContent = value;
    dd.dataset.metric = term;
    return [dt, dd];
  }));
  $('truth-results').hidden = false;
}

function showDepthScore({ file, metrics, legend }, picture) {
  for (const key of [...rows.keys()]) {
    if (!key.startsWith('Flow')) {
      rows.delete(key);
    }
  }
  const depthRows = [
    ['Depth ground truth', file],
    ['MRE', metrics.mre.toFixed(4)],
    ['AbsRel', metrics.abs_rel.toFixed(4)],
    ['δ<1.25', metrics.delta_125.toFixed(3)],
    ['Coverage', `${(100 * metrics.coverage).toFixed(1)} % of the true depths (${metrics.pixels.toLocaleString('en')} pixels)`],
    ['Scale s (median alignment)', metrics.scale.toPrecision(4)],
  ];
  const flowRows = [...rows].filter(([key]) => key.startsWith('Flow'));
  rows.clear();
  for (const [k, v] of [...depthRows, ...flowRows]) {
    rows.set(k, v);
  }
  showRows();
  $('truth-results').dataset.mre = String(metrics.mre);
  const canvas = $('picture-error');
  canvas.width = page.workingSize[0];
  canvas.height = page.workingSize[1];
  canvas.getContext('2d').putImageData(
    new ImageData(new Uint8ClampedArray(picture.buffer), canvas.width, canvas.height), 0, 0);
  const key = $('error-legend');
  key.width = legend.colours.length;
  const pixels = new Uint8ClampedArray(legend.colours.flatMap(([r, g, b]) => [r, g, b, 255]));
  key.getContext('2d').putImageData(new ImageData(pixels, legend.colours.length, 1), 0, 0);
  $('error-legend-low').textContent = '0 % (exact)';
  $('error-legend-high').textContent = `≥ ${Math.round(100 * legend.max)} %`;
  $('truth-figure').hidden = false;
}

function showFlowScore({ file, metrics }) {
  rows.set('Flow ground truth', file);
  rows.set('Flow EPE', `${metrics.epe.toFixed(3)} px (${(100 * metrics.over_3px).toFixed(1)} % over 3 px)`);
  showRows();
  $('truth-results').dataset.epe = String(metrics.epe);
}
