// The page's shared state and its status line, alert box and state machine (index.html).
//
// document.body.dataset.state: "loading" (worker not ready yet) → "idle" → "running" →
// "done" or "error"; a cancel goes back to "idle". Errors are shown in #alert (role="alert").
// window.soupPage (= `page` below) exposes the viewer, the worker and the last run's timings
// (tests, benchmark).

export const $ = (id) => document.getElementById(id);

const URL_OPTIONS = new URLSearchParams(location.search);
/** ?backend=auto|webgpu|webgl2 picks the viewer's graphics backend. */
export const BACKEND = URL_OPTIONS.get('backend') ?? 'auto';
const ASKED_WORKER = URL_OPTIONS.get('worker');
/**
 * ?worker=full runs the pipeline with the full wasm build instead of the lean one; ?worker=scalar
 * with the lean build without wasm SIMD, even where the browser has SIMD (www/worker.js).
 */
export const WORKER_MODULE = ['full', 'scalar'].includes(ASKED_WORKER) ? ASKED_WORKER : 'lean';
/**
 * ?threads=N: at most N workers make the fusion's members at once (www/worker.js; 1: the
 * pipeline's worker alone, for measurements); null: as many as the machine's cores, up to 4.
 */
export const WORKER_THREADS = URL_OPTIONS.get('threads');

export const page = {
  /** Defaults and names from the library (`pageDefaults`), once the worker is ready. */
  defaults: null,
  /**
   * The two frames: { name, width, height (the photo's, upright), exif: { focal35mm, warning },
   * thumbnail (a small ImageBitmap), `source` (the file, decoded again when the working size
   * changes; null for a video frame), `bitmap` (the pixels at the working size for `side`, its
   * long side) and `decoder` ('library' for a JPEG decoded by src/jpeg.rs, 'browser', or null
   * for a video frame and for a frame restored from a session saved before it was recorded) }. Photos are never kept at full size: 12 megapixels are 48 MB of RGBA.
   */
  frames: [],
  /** "auto": intrinsics from EXIF or the default (resolved by the library); "user": the form's. */
  intrinsicsMode: 'auto',
  /** Width and height of the last result's working resolution (its pictures). */
  workingSize: null,
  /** Point count of the last result's (organised) cloud; the worker keeps the cloud itself. */
  points: 0,
  /** `savedAt` of the stored result when it is the one shown (persist.js), else null. */
  savedAt: null,
  /** Labels of the last result's superpixels whose depth is a guess (report confidence below
   *  `min_confidence`: no contact pins their scale, or their plane is a neighbour's). */
  unconfident: [],
  /** The 3D viewer in use (replaced after a lost GPU device or context), or null. */
  viewer: null,
  /** Resolves to the first viewer, or null when the 3D view cannot run (set by view3d.js). */
  viewerReady: null,
  /** The worker client (www/pipeline.js; set by worker-client.js). */
  pipeline: null,
  /** Timings of the last finished run (milliseconds), for the benchmark. */
  lastRun: null,
  /** When the current user action began (performance.now()), for lastRun.endToEndMs. */
  actionStartedAt: null,
  /** The current user action's token (see `begin`). */
  action: null,
  /** Milliseconds from navigation to the page being ready (worker loaded), and to the viewer. */
  readyMs: null,
  viewerReadyMs: null,
  /** Milliseconds from `new Worker` to its module loaded, per (re)start. */
  workerStartMs: [],
  video: null,
};
window.soupPage = page;

/**
 * Hands the memory of typed arrays (or ArrayBuffers) no longer needed back at once, rather than
 * at the next garbage collection, which may come late: a 1024 × 768 result brings 24 MB of cloud
 * and 16 MB of pictures. `ArrayBuffer.prototype.transfer(0)` detaches a buffer, which frees its
 * contents; where the browser lacks it, this does nothing.
 */
export function freeArrays(...arrays) {
  for (const array of arrays) {
    const buffer = array?.buffer ?? array;
    if (buffer instanceof ArrayBuffer && !buffer.detached) {
      buffer.transfer?.(0);
    }
  }
}

export function setState(state) {
  document.body.dataset.state = state;
  const running = state === 'running';
  $('cancel-button').disabled = !running;
  $('run-button').disabled = running || page.defaults === null;
}

export function setStatus(text) {
  $('status').textContent = text;
}

/** Shows `message` in the alert, with an optional action button { label, run }. */
export function showAlert(message, action = null) {
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

export function clearAlert() {
  $('alert').hidden = true;
  $('alert').replaceChildren();
}

/**
 * Starts a user action (reading input, a run): clears the alert and sets the state to
 * "running" until the action ends. Returns a check that turns false once a later action or a
 * cancel has taken over, so an action stops after its next await.
 */
export function begin(status) {
  page.actionStartedAt ??= performance.now();
  const token = {};
  page.action = token;
  clearAlert();
  setStatus(status);
  setState('running');
  return () => page.action === token;
}

/** Shows an error and leaves the page ready for the next input. */
export function fail(message, action = null) {
  page.actionStartedAt = null;
  showAlert(message, action);
  setStatus('');
  setState('error');
}

/** `text` with a capital first letter (the library's messages start in lower case). */
export const sentence = (text) => text.charAt(0).toUpperCase() + text.slice(1);

/** Resolves on the first of `events` (a name or a list) from `target`; rejects on its `error`. */
export function waitFor(target, events) {
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

/** Saves `bytes` (a Blob part) as a download named `name`. */
export function saveFile(bytes, name, type) {
  const url = URL.createObjectURL(new Blob([bytes], { type }));
  const link = document.createElement('a');
  link.href = url;
  link.download = name;
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10_000);
}
