// The page's Web Worker (a module worker): loads the lean wasm build (www/pkg/soup_worker.js,
// the library without the 3D viewer; scripts/build-web.sh) and runs the reconstruction off the
// main thread, so the page stays responsive. The algorithm is all in wasm: this file only moves
// pixels and results across. `worker.js?module=full` loads the full build instead (the page's
// `?worker=full`; benches/page.mjs compares the two).
//
// Requests (each with an `id`; answered by { type: 'reply', id, ... } or { type: 'error', id, ... }):
//   { type: 'exif', bytes: ArrayBuffer }                   → { exif: { focal35mm, warning } }
//   { type: 'decode-jpeg', bytes: ArrayBuffer, maxSide }   → { width, height (the photo,
//       upright), frameWidth, frameHeight, pixels: RGBA at the working size, exif } (a DCT-scaled
//       decode, src/jpeg.rs; an error when the decoder refuses the file; www/pipeline.js sends it
//       to a worker of its own)
//   { type: 'intrinsics', width, height, focal35mm }        → { camera: { intrinsics, source } }
//   { type: 'run', frames: [ImageBitmap, ImageBitmap], options, quiet }
//       → { type: 'progress', id, stage, fraction }…, then a reply with the result (below);
//       `quiet: true` (the page computing a result it already has again, www/pipeline.js):
//       no progress and no result in the reply, the reconstruction is only kept
//   { type: 'cloud', soup: 'organised' | 'scaled' | 'unorganised' } → { cloud }
//   { type: 'export', name }                                → { bytes: ArrayBuffer, mediaType }
//   { type: 'score-depth', name, bytes, pngScale }          → { score, picture: RGBA at the
//       working size } (ground-truth depth of frame 1: PFM, .dpt or 16-bit PNG; see
//       src/web/ground_truth.rs)
//   { type: 'score-flow', name, bytes }                     → { score } (ground-truth .flo)
// Unasked: { type: 'ready', version, defaults } once the module is loaded; { type: 'failed',
// message } when it cannot be loaded.
// Errors: { type: 'error', id, name, message, fatal }. `fatal` means the wasm instance aborted
// (out of memory, or a bug) and is unusable: the page replaces the worker. An out-of-memory abort
// is named OutOfMemoryError.

const MODULES = { lean: './pkg/soup_worker.js', full: './pkg/superpixel_soup.js' };
const soup = await import(MODULES[new URL(import.meta.url).searchParams.get('module') ?? 'lean']);

/** The last reconstruction, kept in wasm memory for clouds and exports on request. */
let current = null;

/** Bytes of RGBA read from a canvas at a time (a few rows; a photo is never copied whole). */
const STRIP_BYTES = 4 * 2 ** 20;

/** The pixels of an ImageBitmap (closed here) in a wasm FrameBuilder, read in strips of rows. */
function readFrame(bitmap) {
  const { width, height } = bitmap;
  const canvas = new OffscreenCanvas(width, height);
  const context = canvas.getContext('2d', { willReadFrequently: true });
  context.drawImage(bitmap, 0, 0);
  bitmap.close();
  const frame = new soup.FrameBuilder(width, height);
  const rows = Math.max(1, Math.floor(STRIP_BYTES / (4 * width)));
  for (let y = 0; y < height; y += rows) {
    frame.pushRows(context.getImageData(0, y, width, Math.min(rows, height - y)).data);
  }
  // Release the canvas's pixels now rather than at the next garbage collection.
  canvas.width = 0;
  canvas.height = 0;
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

function run(id, { frames, options, quiet = false }) {
  const clock = performance.now();
  current?.free();
  current = null;
  const [one, two] = frames.map(readFrame);
  const pixelsMs = performance.now() - clock;
  let last = { stage: '', fraction: -1 };
  const progress = quiet ? undefined : (stage, fraction) => {
    // At most ~50 messages per stage.
    if (stage !== last.stage || fraction - last.fraction >= 0.02 || fraction === 1) {
      last = { stage, fraction };
      postMessage({ type: 'progress', id, stage, fraction });
    }
  };
  const start = performance.now();
  current = soup.reconstruct(one, two, JSON.stringify(options), progress);
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
    timings: { pixelsMs, reconstructMs, collectMs: performance.now() - collect },
    memoryBytes: soup.memoryBytes(),
  };
  const transfer = [...cloudTransfer(cloud), ...Object.values(pictures).map((p) => p.buffer)];
  return [{ result }, transfer];
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

async function main() {
  try {
    await soup.default();
  } catch (e) {
    postMessage({ type: 'failed', message: `could not load the WebAssembly module: ${e.message ?? e}` });
    return;
  }
  onmessage = ({ data }) => {
    try {
      const [reply, transfer = []] = handle(data);
      postMessage({ type: 'reply', id: data.id, ...reply }, transfer);
    } catch (e) {
      postMessage({ type: 'error', id: data.id, ...describe(e) });
    }
  };
  postMessage({ type: 'ready', version: soup.version(), defaults: JSON.parse(soup.pageDefaults()) });
}

main();
