// The page's Web Worker (a module worker): loads the lean wasm build (the library without the 3D
// viewer; scripts/build-web.sh) and runs the reconstruction off the main thread, so the page
// stays responsive. The algorithm is all in wasm: this file only moves pixels and results
// across. The lean build comes in two: www/pkg/soup_worker_simd.js, compiled with wasm SIMD,
// where the browser validates a SIMD instruction (every browser with WebGPU, and Safari from
// 16.4), else www/pkg/soup_worker.js; they give the same results bit for bit, and the SIMD one
// makes the superpixels about twice as fast. `worker.js?module=scalar` loads the build without
// SIMD wherever (the page's `?worker=scalar`), `worker.js?module=full` the full build (the
// page's `?worker=full`; benches/page.mjs compares them).
//
// The fusion's members (src/soup/ensemble.rs: four more reconstructions of the same flow from
// other superpixel counts, two thirds of a run's time) are made in parallel: a run starts up to
// MAX_THREADS − 1 helper workers (this same script with `?helper=1`, nested, given this
// worker's compiled module), each makes some of the members (a `MemberSource` from a copy of
// the run's inputs) while this worker makes the rest (`memberVote`), and this worker fuses the
// votes (src/web/members.rs). Before that, while this worker computes a flow from frame 1 to
// frame 2, the first helper computes it from frame 2 to frame 1 (`directionsApart`: each
// direction is half the flow's time): the run's first flow, and a finer one where a pass asks
// for it (`reconstructUnfused` asks for each flow's directions, src/web/reconstruct.rs). The
// result is the same, bit for bit, however many make them. A helper that cannot start or
// crashes leaves its work to this worker. `worker.js?threads=1` (the page's `?threads=1`) makes
// every member here, one after the other.
//
// Requests (each with an `id`; answered by { type: 'reply', id, ... } or { type: 'error', id, ... }):
//   { type: 'exif', bytes: ArrayBuffer }                   → { exif: { focal35mm, warning } }
//   { type: 'decode-jpeg', bytes: ArrayBuffer, maxSide }   → { width, height (the photo,
//       upright), frameWidth, frameHeight, pixels: RGBA at the working size, exif } (a DCT-scaled
//       decode, src/jpeg.rs; an error when the decoder refuses the file; www/pipeline.js sends it
//       to a worker of its own)
//   { type: 'intrinsics', width, height, focal35mm }        → { camera: { intrinsics, source } }
//   { type: 'run', frames: [ImageBitmap, ImageBitmap], options, quiet, flow }
//       → { type: 'progress', id, stage, fraction }…, then a reply with the result (below);
//       `quiet: true` (the page computing a result it already has again, www/pipeline.js):
//       no progress and no result in the reply, the reconstruction is only kept; `flow`
//       (optional): { forward, backward, preset, ms }, the first flow's directions and the
//       time they took, as an earlier run of the same frames and options gave them in its
//       result (`result.flow`): this run does not compute them, and its report's flow time
//       counts that time
//   { type: 'cloud', soup: 'organised' | 'scaled' | 'unorganised' } → { cloud }
//   { type: 'export', name }                                → { bytes: ArrayBuffer, mediaType }
//   { type: 'score-depth', name, bytes, pngScale }          → { score, picture: RGBA at the
//       working size } (ground-truth depth of frame 1: PFM, .dpt or 16-bit PNG; see
//       src/web/ground_truth.rs)
//   { type: 'score-flow', name, bytes }                     → { score } (ground-truth .flo)
//   { type: 'members', source: { options (JSON), memberInputs' arrays }, counts }
//       → { type: 'vote', id, index, vote: { width, height, depth, pinned } | error }… (one per
//       count, `index` its place in `counts`), then a reply (a helper's request)
//   { type: 'backward-flow', frames: [{ width, height, data: RGBA }, …], options (JSON) }
//       → { flow: Float32Array } (a flow of the run frame 2 → 1, with the options' flow preset;
//       a helper's request)
// Unasked: { type: 'ready', version, defaults, build } once the module is loaded (`build`: the
// name of the wasm build in www/pkg/ it loaded); { type: 'failed', message } when it cannot be
// loaded. A helper (`?helper=1`) first posts { type: 'waiting' }
// and loads the module it is then sent, { type: 'module', module: WebAssembly.Module }.
// Errors: { type: 'error', id, name, message, fatal }. `fatal` means the wasm instance aborted
// (out of memory, or a bug) and is unusable: the page replaces the worker. An out-of-memory abort
// is named OutOfMemoryError.

/**
 * Whether this browser's WebAssembly has SIMD: it validates a function that returns
 * `i8x16.popcnt(i8x16.splat(0))` (a v128).
 */
function hasWasmSimd() {
  const probe = new Uint8Array([
    0, 97, 115, 109, 1, 0, 0, 0, // "\0asm", version 1
    1, 5, 1, 96, 0, 1, 123, // one function type: () -> v128
    3, 2, 1, 0, // one function of that type
    10, 10, 1, 8, 0, 65, 0, 253, 15, 253, 98, 11, // i32.const 0, i8x16.splat, i8x16.popcnt, end
  ]);
  try {
    return WebAssembly.validate(probe);
  } catch {
    return false;
  }
}

/** The wasm build (its name in www/pkg/) of each `?module=`. */
const MODULES = {
  lean: hasWasmSimd() ? 'soup_worker_simd' : 'soup_worker',
  scalar: 'soup_worker',
  full: 'superpixel_soup',
};
const SEARCH = new URL(import.meta.url).searchParams;
const ASKED = SEARCH.get('module') ?? 'lean';
/** The wasm build this worker loads (the lean one for an unknown `?module=`). */
const BUILD = Object.hasOwn(MODULES, ASKED) ? MODULES[ASKED] : MODULES.lean;
const soup = await import(`./pkg/${BUILD}.js`);

/**
 * Workers making a run's members at once, this one included: 4, the default number of members
 * (more would idle). Each helper holds one member's memory until the run ends (HELPERS_MIB).
 */
const MAX_THREADS = 4;

/** The last reconstruction, kept in wasm memory for clouds and exports on request. */
let current = null;

/** Bytes of RGBA read from a canvas at a time by readFrame (a few rows, not the whole frame). */
const STRIP_BYTES = 4 * 2 ** 20;

/**
 * An ImageBitmap (closed here) drawn on a canvas to read its pixels from: { context, width,
 * height, release }; `release()` frees the canvas's pixels now rather than at the next garbage
 * collection.
 */
function drawn(bitmap) {
  const { width, height } = bitmap;
  const canvas = new OffscreenCanvas(width, height);
  const context = canvas.getContext('2d', { willReadFrequently: true });
  context.drawImage(bitmap, 0, 0);
  bitmap.close();
  const release = () => {
    canvas.width = 0;
    canvas.height = 0;
  };
  return { context, width, height, release };
}

/** Rows of `width` RGBA pixels in a strip of STRIP_BYTES (at least one). */
const stripRows = (width) => Math.max(1, Math.floor(STRIP_BYTES / (4 * width)));

/** The RGBA pixels of an ImageBitmap (closed here): { width, height, data }. */
function pixelsOf(bitmap) {
  const { context, width, height, release } = drawn(bitmap);
  const { data } = context.getImageData(0, 0, width, height);
  release();
  return { width, height, data };
}

/** A wasm FrameBuilder of RGBA `pixels` ({ width, height, data }), given in strips of rows. */
function builderOf({ width, height, data }) {
  const frame = new soup.FrameBuilder(width, height);
  const rows = stripRows(width);
  for (let y = 0; y < height; y += rows) {
    frame.pushRows(data.subarray(4 * width * y, 4 * width * Math.min(height, y + rows)));
  }
  return frame;
}

/** The pixels of an ImageBitmap (closed here) in a wasm FrameBuilder, read in strips of rows. */
function readFrame(bitmap) {
  const { context, width, height, release } = drawn(bitmap);
  const frame = new soup.FrameBuilder(width, height);
  const rows = stripRows(width);
  for (let y = 0; y < height; y += rows) {
    frame.pushRows(context.getImageData(0, y, width, Math.min(rows, height - y)).data);
  }
  release();
  return frame;
}

/** Plain object of a wasm CloudBuffers (freed), with the buffers to transfer. */
function takeCloud(buffers) {
  const cloud = {
    count: buffers.count,
    positions1: buffers.positions1,
    positions2: buffers.positions2,
    colours: buffers.colours,
    labels: buffers.labels,
  };
  buffers.free();
  return cloud;
}

const cloudTransfer = (c) => [c.positions1.buffer, c.positions2.buffer, c.colours.buffer, c.labels.buffer];

async function run(id, { frames, options, quiet = false, flow: given = null }) {
  const clock = performance.now();
  current?.free();
  current = null;
  const [width, height] = [frames[0].width, frames[0].height];
  const wanted = threadsFor(options, quiet, width, height) - 1;
  // With helpers, each flow's two directions are computed at once (directionsApart), from the
  // frames' pixels read whole here (at the working size) and held until the passes are made,
  // for those that ask for finer flow; else the frames go to wasm in strips, never whole in
  // JavaScript.
  let pixels = wanted > 0 ? frames.map(pixelsOf) : null;
  const [one, two] = pixels === null ? frames.map(readFrame) : [null, null];
  const pixelsMs = performance.now() - clock;
  let last = { stage: '', fraction: -1 };
  const progress = quiet ? undefined : (stage, fraction) => {
    // At most ~50 messages per stage, never a step back within one (the flow joined after its
    // directions apart reports its start again).
    if (stage !== last.stage || fraction - last.fraction >= 0.02 || fraction === 1) {
      last = { stage, fraction };
      postMessage({ type: 'progress', id, stage, fraction });
    }
  };
  const start = performance.now();
  const json = JSON.stringify(options);
  const firstPreset = options?.flowPreset ?? pageDefaults.options.flowPreset;
  let made;
  // The first flow's directions when computed apart here ({ forward, backward, apart, preset,
  // ms }), and the milliseconds of directions computed before the run asked for them (handed
  // to it, or computed first), which its report's flow time has yet to count.
  let firstFlow = null;
  let uncountedMs = given?.ms ?? 0;
  let flowsApart = 0; // flow computations of which a helper computed one direction
  // A nested worker loads its script through this worker's event loop: the helpers are
  // waited for here, not while the kept pass holds the loop.
  const helpers = await startHelpers(wanted);
  // The directions of each flow the run computes (src/web/reconstruct.rs, `reconstructUnfused`,
  // which asks with the flow's preset): the first flow's as this run was handed them or
  // computed them (a pass kept after a finer one asks for them again), else computed apart with
  // the first helper, else null (computed in wasm, one after the other).
  // Where they are computed, their progress is that of `stage` from `from` to `to`. A wasm
  // abort while computing them ends the run (`crash`): the instance is unusable, so the pass
  // waiting for them must not go on.
  let crash;
  const crashed = new Promise((_, reject) => {
    crash = reject;
  });
  crashed.catch(() => {}); // raced below, or never settled
  const directions = async (preset, stage = 'flow', from = 0, to = 1) => {
    const known = [given, firstFlow].find((flow) => flow?.preset === preset);
    if (known !== undefined) {
      const ms = uncountedMs;
      uncountedMs = 0;
      return { forward: known.forward, backward: known.backward, ms };
    }
    if (helpers.length === 0) {
      return null;
    }
    try {
      const asked = JSON.stringify({ ...options, flowPreset: preset });
      const flow = await directionsApart(pixels, asked, helpers, (f) => progress?.(stage, from + (to - from) * f));
      flowsApart += Number(flow.apart);
      firstFlow ??= { ...flow, preset };
      return flow;
    } catch (e) {
      if (describe(e).fatal) {
        crash(e);
        return new Promise(() => {});
      }
      return null; // computed in wasm, which says what is wrong
    }
  };
  try {
    if (given === null && helpers.length > 0) {
      // The first flow before the pass holds the frames in wasm: the flow's peak holds only its own.
      const computing = performance.now();
      await Promise.race([directions(firstPreset), crashed]);
      if (firstFlow !== null) {
        firstFlow.ms = performance.now() - computing;
        uncountedMs = firstFlow.ms;
      }
    }
    const [a, b] = pixels === null ? [one, two] : pixels.map(builderOf);
    made = await untilAborted(soup.reconstructUnfused(a, b, json, progress, directions), crashed);
    pixels = null; // no more flows to compute
    await fuseMembers(made, json, helpers, progress);
  } catch (e) {
    if (!describe(e).fatal) {
      made?.free(); // after a crash the instance is unusable, and so is freeing
    }
    throw e;
  } finally {
    helpers.forEach((helper) => helper.terminate());
  }
  current = made;
  const reconstructMs = performance.now() - start;
  if (quiet) {
    return [{ result: null }];
  }
  const collect = performance.now();
  const cloud = takeCloud(current.cloud('organised'));
  const pictures = {};
  for (const name of ['depth', 'unorganised', 'superpixels', 'flow', 'confidence']) {
    pictures[name] = current.picture(name);
  }
  const result = {
    width: current.width,
    height: current.height,
    cloud,
    pictures,
    legend: JSON.parse(current.depthLegend(64)),
    report: JSON.parse(current.report()),
    // `helpers`: the helper workers that made members (lastRun.worker, www/page/worker-client.js);
    // `flowsApart`: how many of the run's flow computations had one direction computed by a
    // helper (a pass kept after a finer one, other than the first, computes its flow again).
    timings: {
      pixelsMs, reconstructMs, collectMs: performance.now() - collect, helpers: helpers.length, flowsApart,
    },
    memoryBytes: soup.memoryBytes(),
    // The first flow's directions when computed apart: the page gives them back to the run
    // that computes this result again (www/pipeline.js), which then need not compute them.
    flow: firstFlow === null ? null : {
      forward: firstFlow.forward, backward: firstFlow.backward, preset: firstFlow.preset, ms: firstFlow.ms,
    },
  };
  const transfer = [...cloudTransfer(cloud), ...Object.values(pictures).map((p) => p.buffer)];
  if (firstFlow !== null) {
    transfer.push(firstFlow.forward.buffer, firstFlow.backward.buffer);
  }
  return [{ result }, transfer];
}

/**
 * `promise` (of an async wasm export), or rejected with the error of an abort of the wasm
 * instance (out of memory, or a bug) while it is pending: the export's work runs in tasks of
 * wasm-bindgen's, from which an abort escapes as an uncaught error (handled here, so that the
 * page hears of it as the run's error) and leaves the promise pending; or rejected as
 * `crashed` is (an abort the export's callbacks caught).
 */
function untilAborted(promise, crashed) {
  let listener;
  const aborted = new Promise((_, reject) => {
    listener = (event) => {
      const error = event.error ?? event.reason ?? new Error(event.message);
      if (describe(error).fatal) {
        event.preventDefault();
        reject(error);
      }
    };
  });
  for (const type of ['error', 'unhandledrejection']) {
    self.addEventListener(type, listener);
  }
  return Promise.race([promise, aborted, crashed]).finally(() => {
    for (const type of ['error', 'unhandledrejection']) {
      self.removeEventListener(type, listener);
    }
  });
}

/**
 * A flow's two directions (src/web/reconstruct.rs, `flowDirection`, with the options `json`) at
 * once: frame 2 → 1 in the first of `helpers`, 1 → 2 here, from RGBA `pixels` of both frames
 * (the helper gets copies); `report(fraction)` hears of the share done. Resolves to { forward,
 * backward } (Float32Arrays) and `apart`, whether the helper computed one: a helper that fails
 * is left out of the run (terminated), and its direction is computed here after the other.
 */
async function directionsApart(pixels, json, helpers, report) {
  const helper = helpers[0];
  const copies = pixels.map(({ width, height, data }) => ({ width, height, data: data.slice() }));
  const asked = new Promise((resolve) => {
    helper.onmessage = ({ data }) => resolve(data.type === 'reply' ? data.flow : null);
    helper.onmessageerror = () => resolve(null);
    helper.onerror = (event) => {
      event.preventDefault();
      resolve(null);
    };
  });
  helper.postMessage({ type: 'backward-flow', id: 0, frames: copies, options: json }, copies.map((c) => c.data.buffer));
  const [a, b] = pixels.map(builderOf);
  const forward = soup.flowDirection(a, b, json, false, (f) => report(0.5 * f));
  let backward = await asked;
  const apart = backward !== null;
  if (!apart) {
    helpers.shift().terminate(); // its members are made by the others
    const [c, d] = pixels.map(builderOf);
    backward = soup.flowDirection(c, d, json, true, (f) => report(0.5 + 0.5 * f));
  }
  return { forward, backward, apart };
}

/**
 * How many workers make the members of a run with `options` on frames of `width × height`
 * pixels: one per member, at most MAX_THREADS, the machine's cores, the page's `?threads=`, and
 * as many helpers as HELPERS_MIB allows at the working size; one where a worker cannot start
 * workers of its own, and for a `quiet` run. A quiet run computes a result the page already
 * shows again in the background (www/pipeline.js), while the page holds that result's clouds
 * and pictures: that is when the tab's memory peaks, and a helper there took the 12 MP photo
 * pair from 367 to 409 MiB, above the page's 400.
 */
function threadsFor(options, quiet, width, height) {
  if (quiet || typeof Worker !== 'function') {
    return 1;
  }
  // Options that do not say take the library's defaults.
  const defaults = pageDefaults.options;
  const members = options?.params?.ensemble?.members ?? defaults.params.ensemble.members;
  const maxSide = options?.maxSide ?? defaults.maxSide;
  const shrink = Math.min(1, maxSide / Math.max(width, height));
  const helperMiB = HELPER_MIB + (HELPER_BYTES_PER_PIXEL * width * height * shrink * shrink) / 2 ** 20;
  const threads = Number(SEARCH.get('threads'));
  const asked = Number.isInteger(threads) && threads >= 1 ? threads : MAX_THREADS;
  const cores = navigator.hardwareConcurrency ?? 1;
  const affordable = 1 + Math.floor(HELPERS_MIB / helperMiB);
  return Math.max(1, Math.min(members - 1, asked, cores, MAX_THREADS, affordable));
}

/**
 * The tab memory one helper takes during a run: HELPER_MIB for the worker and its instance, and
 * HELPER_BYTES_PER_PIXEL per pixel of the working size for a member and its copy of the inputs
 * (sampled during runs: 47 MiB a helper at 1024 × 768, 30 MiB at 1024 × 436). The first helper
 * computes a flow direction before its members, which grows its wasm memory by the flow's
 * working memory (at 1024 × 768 with preset fine both directions hold 58 MiB at their peak);
 * with it the tab stayed at 346–350 MiB during a 12 MP run, below the peak after the run
 * (docs/RESULTS.md, stop 59). Where a pass asks for finer flow it computes a direction of
 * preset high's too, whose peak is fine's (63 bytes per pixel each); no photo pair measured
 * takes such a pass at 12 MP (docs/RESULTS.md, stop 60).
 */
const HELPER_MIB = 8;
const HELPER_BYTES_PER_PIXEL = 50;

/**
 * The most tab memory a run's helpers may take together (MiB): 1024 × 436 gets three helpers,
 * 1024 × 768 (12 MP photos) two. During a run without helpers the tab holds about 260 MiB at
 * 1024 × 768, and after it, with the result shown and computed again in the background, 370:
 * two helpers stay below that peak, while three took the run to 410 MiB, above the page's 400.
 */
const HELPERS_MIB = 100;

/**
 * `n` helper workers running this script with this worker's module, once they have loaded it:
 * those that fail to load, or take longer than HELPER_LOAD_MS, are left out (terminated).
 */
async function startHelpers(n) {
  const started = [];
  for (let i = 0; i < n; i += 1) {
    try {
      const url = new URL(import.meta.url);
      url.searchParams.set('helper', '1');
      started.push(new Worker(url, { type: 'module' }));
    } catch {
      break; // this worker makes their members
    }
  }
  const loaded = await Promise.all(started.map(loadedHelper));
  started.filter((_, i) => !loaded[i]).forEach((helper) => helper.terminate());
  return started.filter((_, i) => loaded[i]);
}

/** The longest wait for a helper to load its module (ms), after which it is left out. */
const HELPER_LOAD_MS = 5000;

/** Resolves to whether `helper` loaded its module within HELPER_LOAD_MS. */
function loadedHelper(helper) {
  return new Promise((resolve) => {
    const timer = setTimeout(() => resolve(false), HELPER_LOAD_MS);
    const settle = (ok) => {
      clearTimeout(timer);
      resolve(ok);
    };
    helper.onmessage = ({ data }) => {
      if (data.type === 'waiting') {
        helper.postMessage({ type: 'module', module: compiled });
      } else {
        settle(data.type === 'ready');
      }
    };
    helper.onerror = (event) => {
      event.preventDefault();
      settle(false);
    };
  });
}

/**
 * Makes the members of `result` (src/web/members.rs), each in the worker `assign` gives it
 * (this one or a helper), then adds the votes in the order of their counts and fuses them. The
 * members of a helper that crashes are made here afterwards.
 */
async function fuseMembers(result, json, helpers, progress) {
  const start = performance.now();
  const counts = [...result.memberCounts()];
  const owners = assign(counts, helpers.length + 1);
  const mine = (k) => owners.flatMap((owner, i) => (owner === k ? [i] : []));
  const votes = new Array(counts.length).fill(null);
  let done = 0;
  const settle = (index, vote) => {
    votes[index] = vote;
    done += 1;
    progress?.('ensemble', done / counts.length);
  };
  progress?.('ensemble', 0);
  const asked = helpers.length === 0 ? [] : askHelpers(result, json, helpers, counts, mine, settle);
  const here = (index) => settle(index, takeVote(() => result.memberVote(counts[index])));
  for (const index of mine(0)) {
    here(index);
    if (helpers.length > 0) {
      await nextTask(); // the helpers' votes come in (progress)
    }
  }
  await Promise.all(asked);
  votes.forEach((vote, index) => vote === null && here(index));
  for (const vote of votes) {
    if (vote.error === undefined) {
      result.addVote(vote.width, vote.height, vote.depth, vote.pinned);
    } else {
      result.addFailure(vote.error);
    }
  }
  result.fuse(performance.now() - start);
  progress?.('ensemble', 1);
}

/**
 * The worker of each member (0: this one, k: helper k − 1) among `workers`: the largest counts
 * first, each to the worker with the fewest superpixels so far (a member's time grows with its
 * count; with two workers 1300–1700 split as 1700 + 1300 and 1600 + 1400).
 */
function assign(counts, workers) {
  const load = new Array(workers).fill(0);
  const owners = new Array(counts.length);
  const order = counts.map((_, i) => i).sort((a, b) => counts[b] - counts[a] || a - b);
  for (const i of order) {
    const k = load.indexOf(Math.min(...load));
    owners[i] = k;
    load[k] += counts[i];
  }
  return owners;
}

/** Resolves after the messages already queued for this worker are handled. */
const nextTask = () => new Promise((resolve) => setTimeout(resolve));

/**
 * A member's vote from `make()` (a wasm VoteBuffers) as { width, height, depth, pinned }, or
 * { error } (why it could not be made). A crash of this instance is thrown on.
 */
function takeVote(make) {
  try {
    const vote = make();
    const plain = { width: vote.width, height: vote.height, depth: vote.depth, pinned: vote.pinned };
    vote.free();
    return plain;
  } catch (e) {
    const { message, fatal } = describe(e);
    if (fatal) {
      throw e; // this instance is unusable: the run fails as a crash
    }
    return { error: message };
  }
}

/**
 * Sends each helper (loaded) what the members are made from (copies; the last one is given
 * this worker's) and its members (`mine(k + 1)`, indices into `counts`); `settle(index, vote)`
 * gets each vote as it comes. One promise per helper, resolved when it is done or crashed (its
 * members without a vote are then made here); the helper is terminated then.
 */
function askHelpers(result, json, helpers, counts, mine, settle) {
  const inputs = result.memberInputs();
  const source = {
    options: json, width: inputs.width, height: inputs.height, intrinsics: inputs.intrinsics,
    frame: inputs.frame, flow: inputs.flow, reliable: inputs.reliable,
  };
  inputs.free();
  const buffers = [source.intrinsics, source.frame, source.flow, source.reliable].map((a) => a.buffer);
  return helpers.map((helper, k) => new Promise((resolve) => {
    const indices = mine(k + 1);
    const end = () => {
      helper.terminate(); // its memory back now, not at the end of the run
      resolve();
    };
    helper.onmessage = ({ data }) => {
      if (data.type === 'vote') {
        settle(indices[data.index], data.vote);
      } else {
        end(); // the reply, or an error
      }
    };
    helper.onmessageerror = end;
    helper.onerror = (event) => {
      event.preventDefault();
      end();
    };
    const transfer = k === helpers.length - 1 ? buffers : [];
    helper.postMessage({ type: 'members', id: 0, source, counts: indices.map((i) => counts[i]) }, transfer);
  }));
}

/** A helper's request: the votes of `counts` from `source`, each posted as it is made. */
function makeMembers(id, { source: s, counts }) {
  const source = new soup.MemberSource(s.options, s.width, s.height, s.intrinsics, s.frame, s.flow, s.reliable);
  try {
    for (const [index, count] of counts.entries()) {
      const vote = takeVote(() => source.vote(count));
      const transfer = vote.error === undefined ? [vote.depth.buffer, vote.pinned.buffer] : [];
      postMessage({ type: 'vote', id, index, vote }, transfer);
    }
  } finally {
    source.free();
  }
  return [{}];
}

function handle(message) {
  switch (message.type) {
    case 'exif':
      return [{ exif: JSON.parse(soup.readExif(new Uint8Array(message.bytes))) }];
    case 'decode-jpeg': {
      const decoded = soup.decodeJpeg(new Uint8Array(message.bytes), message.maxSide);
      const reply = {
        width: decoded.width,
        height: decoded.height,
        frameWidth: decoded.frameWidth,
        frameHeight: decoded.frameHeight,
        exif: JSON.parse(decoded.exif),
        pixels: decoded.takePixels(),
      };
      decoded.free();
      return [reply, [reply.pixels.buffer]];
    }
    case 'intrinsics':
      return [{ camera: JSON.parse(soup.resolveIntrinsics(message.width, message.height, message.focal35mm ?? undefined)) }];
    case 'run':
      return run(message.id, message);
    case 'members':
      return makeMembers(message.id, message);
    case 'backward-flow': {
      const [a, b] = message.frames.map(builderOf);
      const flow = soup.flowDirection(a, b, message.options, true);
      return [{ flow }, [flow.buffer]];
    }
    case 'cloud': {
      const cloud = takeCloud(needResult().cloud(message.soup));
      return [{ cloud }, cloudTransfer(cloud)];
    }
    case 'export': {
      const result = needResult();
      const bytes = result.exportFile(message.name);
      return [{ bytes: bytes.buffer, mediaType: result.exportMediaType(message.name) }, [bytes.buffer]];
    }
    case 'score-depth': {
      const result = needResult();
      const score = JSON.parse(result.scoreDepth(message.name, new Uint8Array(message.bytes), message.pngScale ?? undefined));
      const picture = result.errorPicture();
      return [{ score, picture }, [picture.buffer]];
    }
    case 'score-flow':
      return [{ score: JSON.parse(needResult().scoreFlow(message.name, new Uint8Array(message.bytes))) }];
    default:
      throw new Error(`unknown request ${message.type}`);
  }
}

function needResult() {
  if (current === null) {
    throw new Error('there is no reconstruction yet');
  }
  return current;
}

/** The error message for the page: out-of-memory aborts are told apart from other crashes. */
function describe(error) {
  const mb = (bytes) => (bytes < 2 ** 20 ? `${Math.ceil(bytes / 2 ** 10)} kB` : `${Math.round(bytes / 2 ** 20)} MB`);
  if (error instanceof WebAssembly.RuntimeError) {
    const failed = soup.failedAllocation();
    if (failed !== undefined) {
      return {
        name: 'OutOfMemoryError',
        message: `Out of memory: the browser would not give the reconstruction another ${mb(failed)} ` +
          `(it already uses ${mb(soup.memoryBytes())}). Try a smaller working size or smaller photos.`,
        fatal: true,
      };
    }
    return { name: 'CrashError', message: `The reconstruction crashed (${error.message}); it was restarted.`, fatal: true };
  }
  if (error instanceof RangeError && /alloc|memory/i.test(error.message)) {
    return {
      name: 'OutOfMemoryError',
      message: `Out of memory: ${error.message}. Try a smaller working size or smaller photos.`,
      fatal: true,
    };
  }
  return { name: error?.name ?? 'Error', message: error?.message ?? String(error), fatal: false };
}

/**
 * The module compiled: fetched by the page's worker; a helper is given its worker's (the
 * `module` message), so that they share the compiled code, its optimised tiers included.
 */
async function compiledModule() {
  if (SEARCH.has('helper')) {
    return new Promise((resolve) => {
      onmessage = ({ data }) => resolve(data.module);
      postMessage({ type: 'waiting' });
    });
  }
  const url = new URL(`./pkg/${BUILD}_bg.wasm`, import.meta.url);
  try {
    return await WebAssembly.compileStreaming(fetch(url));
  } catch {
    // Served without the type application/wasm.
    return WebAssembly.compile(await (await fetch(url)).arrayBuffer());
  }
}

/** This worker's compiled module (see compiledModule), for its helpers. */
let compiled = null;

/** The page's defaults (src/web/reconstruct.rs, `pageDefaults`), read once the module is loaded. */
let pageDefaults = null;

async function main() {
  try {
    compiled = await compiledModule();
    await soup.default({ module_or_path: compiled });
    pageDefaults = JSON.parse(soup.pageDefaults());
  } catch (e) {
    postMessage({ type: 'failed', message: `could not load the WebAssembly module: ${e.message ?? e}` });
    return;
  }
  // One request at a time, in order: a run waits for its helpers, and a request that comes
  // meanwhile (a cloud, an export) waits for the run's result rather than finding none.
  let queue = Promise.resolve();
  onmessage = ({ data }) => {
    queue = queue.then(async () => {
      try {
        const [reply, transfer = []] = await handle(data);
        postMessage({ type: 'reply', id: data.id, ...reply }, transfer);
      } catch (e) {
        postMessage({ type: 'error', id: data.id, ...describe(e) });
      }
    });
  };
  postMessage({ type: 'ready', version: soup.version(), defaults: pageDefaults, build: BUILD });
}

main();
