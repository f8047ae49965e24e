// The 3D view: loads the full wasm module (with the viewer) once the worker is ready, so that on
// a slow network the worker's smaller module comes first and the page is usable sooner; shows
// the result's cloud, switches between the soups of the stages (unorganised, scaled,
// organised), and connects the viewer's controls (www/viewer-controls.js). The page works
// without the viewer.
//
// GPU loss: when the WebGPU device is lost (the viewer's `viewerlost` event on window) or the
// WebGL2 context is lost (`webglcontextlost` on the canvas: a driver reset, a phone putting the
// tab in the background, too many contexts), the view comes back by itself on a fresh canvas with
// a new viewer, the same cloud (asked again of the worker, which keeps the result) and the same
// camera, morph, point size and colours. If that fails, #viewer-message says what happened and
// offers a button that tries again. document.body.dataset.viewer: "ready", "lost" (recovering),
// "failed" (the button is shown); page.viewerRestores counts recoveries (tests).

import { CancelledError } from '../pipeline.js';
import { wireViewerControls } from '../viewer-controls.js';
import { $, BACKEND, freeArrays, page, showAlert } from './ui.js';

const BACKEND_NAMES = { webgpu: 'WebGPU', webgl2: 'WebGL2' };

/** The wasm module with the viewer, once loaded. */
let wasm = null;
/** The soup shown ('organised', 'scaled' or 'unorganised'), asked of the worker again after a loss. */
let soupShown = 'organised';
/** A recovery in progress (one at a time). */
let restoring = null;
page.viewerRestores = 0;

/** Opens a viewer on `canvas` with `backend` and listens for its loss. */
async function openViewer(canvas, backend) {
  const viewer = await wasm.Viewer.create(canvas, { backend });
  canvas.addEventListener('webglcontextlost', (event) => {
    event.preventDefault();
    lose(viewer, 'the WebGL2 context was lost');
  });
  return viewer;
}

/** Loads the viewer; resolves to it, or to null when the 3D view cannot run here. */
export function loadViewer() {
  window.addEventListener('viewerlost', () => {
    if (page.viewer?.lost) {
      lose(page.viewer, 'the WebGPU device was lost');
    }
  });
  page.viewerReady = (async () => {
    try {
      await page.pipeline.ready.catch(() => {});
      wasm = await import('../pkg/superpixel_soup.js');
      await wasm.default();
      const viewer = await openViewer($('view'), BACKEND);
      viewer.setFlagged(page.unconfident, $('unknown-scale').value);
      page.viewer = viewer;
      page.viewerReadyMs = performance.now();
      document.body.dataset.backend = viewer.backend;
      document.body.dataset.viewer = 'ready';
      $('backend-name').textContent = `Drawn with ${BACKEND_NAMES[viewer.backend] ?? viewer.backend}.`;
      wireViewerControls(() => page.viewer);
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
  return page.viewerReady;
}

/** `viewer` lost its GPU (`what` happened): replace it, unless that is under way already. */
function lose(viewer, what) {
  if (viewer !== page.viewer || viewer === null || restoring !== null) {
    return;
  }
  const state = { backend: viewer.backend, camera: viewer.camera };
  page.viewer = null;
  try {
    viewer.free(); // its listeners and GPU objects
  } catch {
    // A lost device may refuse; the old viewer is dropped either way.
  }
  restart(what, state);
}

function restart(what, state) {
  restoring = restore(what, state).finally(() => {
    restoring = null;
  });
}

/**
 * Replaces the lost viewer: a fresh canvas (a lost context cannot be drawn on again), a new
 * viewer on the same backend, the same cloud and view. On failure, a message and a button.
 */
async function restore(what, { backend, camera }) {
  document.body.dataset.viewer = 'lost';
  const message = $('viewer-message');
  message.textContent = `The 3D view was interrupted (${what}); restoring it…`;
  message.hidden = false;
  // A phone that put the tab in the background gives no GPU until it is shown again.
  while (document.hidden) {
    await new Promise((resolve) => document.addEventListener('visibilitychange', resolve, { once: true }));
  }
  const canvas = $('view');
  const fresh = canvas.cloneNode(false);
  canvas.replaceWith(fresh);
  try {
    const viewer = await openViewer(fresh, backend);
    viewer.setFlagged(page.unconfident, $('unknown-scale').value);
    if (page.points > 0) {
      // A new run or a cancel may end the wait for the cloud: then there is none to show
      // yet, and the new result brings its own.
      const reply = await page.pipeline.request('cloud', { soup: soupShown }).catch((e) => {
        if (e instanceof CancelledError) {
          return null;
        }
        throw e;
      });
      if (reply !== null) {
        const { cloud } = reply;
        viewer.setCloud(cloud.positions1, cloud.positions2, cloud.colours, cloud.labels);
        freeCloud(cloud);
        viewer.setCamera(camera);
      }
    }
    viewer.setMorph(Number($('morph').value));
    viewer.setPointSize(Number($('point-size').value));
    viewer.setColourMode($('colour-mode').value);
    viewer.render();
    page.viewer = viewer;
    page.viewerRestores += 1;
    message.hidden = true;
    document.body.dataset.viewer = 'ready';
  } catch (e) {
    document.body.dataset.viewer = 'failed';
    message.textContent = `The 3D view was interrupted (${what}) and could not be restored ` +
      `(${e.message ?? e}). The pictures and downloads still work. `;
    const button = document.createElement('button');
    button.type = 'button';
    button.className = 'button';
    button.id = 'viewer-restore';
    button.textContent = 'Restore the 3D view';
    button.addEventListener('click', () => restart(what, { backend, camera }));
    message.append(button);
  }
}

/**
 * Shows `cloud` (positions in both frames, colours, labels) in the 3D view, if there is one.
 * The cloud's arrays are freed (the viewer has its own copy; the worker gives it again).
 */
export async function showCloud(cloud, soup = 'organised') {
  const viewer = await page.viewerReady;
  soupShown = soup;
  await restoring;
  if (viewer !== null && page.viewer !== null) {
    showUnknownScale();
    page.viewer.setCloud(cloud.positions1, cloud.positions2, cloud.colours, cloud.labels);
    page.viewer.render();
  }
  freeCloud(cloud);
}

function freeCloud(cloud) {
  freeArrays(cloud.positions1, cloud.positions2, cloud.colours, cloud.labels);
}

/**
 * Flags the superpixels of the last result whose depth is a guess (`page.unconfident`) in
 * the 3D view, shown as #unknown-scale says: like the others, marked magenta, or hidden.
 */
export function showUnknownScale() {
  page.viewer?.setFlagged(page.unconfident, $('unknown-scale').value);
}

/** Shows the soup chosen in #soup-mode: organised (the result), scaled (before the refinement) or unorganised (λ = 1). */
export async function switchSoup() {
  const viewer = await page.viewerReady;
  const soup = $('soup-mode').value;
  if (viewer === null || page.points === 0) {
    return;
  }
  try {
    const { cloud } = await page.pipeline.request('cloud', { soup });
    await showCloud(cloud, soup);
  } catch (e) {
    if (!(e instanceof CancelledError)) {
      showAlert(e.message);
    }
  }
}
