// The page (index.html), entry module. Two photos (or two frames of a video) go in; the
// reconstruction runs in a Web Worker with the library compiled to wasm; the result is shown in
// the 3D viewer and as pictures, with downloads of the output files. No algorithm lives in the
// page's scripts: they move pixels, options and results between the form, the worker and the
// viewer. One module per concern, under www/page/:
//
//   ui.js             shared state (window.soupPage), status, alert, the body's data-state
//   input.js          files, drops, the sample, videos, decoding, thumbnails
//   params.js         the parameters panel and the intrinsics
//   worker-client.js  the worker (www/pipeline.js), progress, run, cancel
//   results.js        stage pictures, legend, report summary, timings
//   downloads.js      the output files
//   groundtruth.js    scores against the user's ground-truth depth (and flow)
//   view3d.js         the 3D view: loading, the cloud, the soup switch, GPU loss recovery
//   persist.js        the last result kept across a reload (IndexedDB), start over
//
// URL options: ?backend=auto|webgpu|webgl2 picks the viewer's graphics backend; ?threads=1
// makes the fusion's members in the pipeline's worker alone (www/worker.js); ?worker=full
// runs the pipeline with the full wasm build instead of the lean one, ?worker=scalar with the
// lean build without wasm SIMD (for measurements and tests).

import { $, page } from './page/ui.js';
import { INTRINSIC_FIELDS, fillForm, refreshIntrinsics } from './page/params.js';
import {
  loadSample, restoreLast, showVideoTime, startOver, swapFrames, takeFiles, takeVideoFrame,
} from './page/input.js';
import { cancel, run, startPipeline } from './page/worker-client.js';
import { download } from './page/downloads.js';
import { loadViewer, showUnknownScale, switchSoup } from './page/view3d.js';
import { rescorePng, takeTruth } from './page/groundtruth.js';

startPipeline(restoreLast);
loadViewer();

function wire() {
  const input = $('file-input');
  input.addEventListener('change', () => {
    const files = [...input.files];
    input.value = ''; // the same files can be picked again
    takeFiles(files);
  });
  $('sample-button').addEventListener('click', loadSample);
  const truthInput = $('truth-input');
  truthInput.addEventListener('change', () => {
    const files = [...truthInput.files];
    truthInput.value = '';
    takeTruth(files);
  });
  $('truth-scale').addEventListener('change', rescorePng);
  $('swap-button').addEventListener('click', swapFrames);
  $('start-over').addEventListener('click', startOver);
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
  $('unknown-scale').addEventListener('change', showUnknownScale);
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
