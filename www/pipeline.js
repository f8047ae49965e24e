// The main thread's side of the worker (www/worker.js): starts it, sends requests and matches
// the replies, forwards progress, and cancels a run by terminating the worker and starting a
// fresh one (a wasm computation cannot be interrupted from outside).
//
// Memory: a wasm instance's memory never shrinks, so a worker that has run a reconstruction
// keeps its peak (81 MiB at 1024 × 768) for as long as it lives, in the same renderer process
// as the page and its 3D view. `release` hands that memory back once the page has a run's
// result: it replaces the worker by a fresh one and computes the same reconstruction again
// there (the pipeline is deterministic) in the background, after the page has shown the result,
// or as soon as a request needs it (a cloud, a download, a ground-truth score), which then waits
// for it. The tab's peak is then the larger of the run and the display of its result, not
// their sum.

/** A request that ended because the worker was terminated (cancel) or replaced (crash). */
export class CancelledError extends Error {
  constructor() {
    super('cancelled');
    this.name = 'CancelledError';
  }
}

/** Requests that need the last reconstruction (kept in the worker). */
const NEEDS_RESULT = new Set(['cloud', 'export', 'score-depth', 'score-flow']);

export class Pipeline {
  /**
   * @param {object} handlers
   *   onProgress(stage, fraction): progress of the running reconstruction;
   *   onReady({ version, defaults, build, startMs }): each time a (re)started worker has loaded its
   *     module (`build`: which wasm build, www/worker.js);
   *   onFailed(message): the worker could not load its module.
   * @param {'lean' | 'scalar' | 'full'} module the worker's wasm build (see www/worker.js)
   * @param {string | null} threads at most this many workers make a run's fusion members at
   *   once (www/worker.js); null: the worker's own limit
   */
  constructor(handlers, module = 'lean', threads = null) {
    this.handlers = handlers;
    this.module = module;
    this.threads = threads;
    this.worker = null;
    this.pending = new Map();
    this.nextId = 1;
    this.ready = null;
    /** After `release`: the released run's { frames, options, flow }, until they are sent again. */
    this.inputs = null;
    /** The run computing the released result again, while it runs. */
    this.recomputing = null;
    this.start();
  }

  /** The URL of the worker script with this pipeline's module. */
  workerUrl() {
    const url = new URL('./worker.js', import.meta.url);
    if (this.module !== 'lean') {
      url.searchParams.set('module', this.module);
    }
    if (this.threads !== null) {
      url.searchParams.set('threads', this.threads);
    }
    return url;
  }

  /** Starts a worker; `this.ready` resolves once its wasm module is loaded. */
  start() {
    const started = performance.now();
    const worker = new Worker(this.workerUrl(), { type: 'module' });
    this.worker = worker;
    this.ready = new Promise((resolve, reject) => {
      worker.onmessage = ({ data }) => {
        if (data.type === 'ready') {
          const info = { version: data.version, defaults: data.defaults, build: data.build, startMs: performance.now() - started };
          this.handlers.onReady?.(info);
          resolve(info);
        } else if (data.type === 'failed') {
          this.handlers.onFailed?.(data.message);
          reject(new Error(data.message));
        } else {
          this.receive(data);
        }
      };
      worker.onerror = (event) => {
        event.preventDefault();
        const message = `the worker failed to start: ${event.message || 'script error'}`;
        this.handlers.onFailed?.(message);
        reject(new Error(message));
      };
    });
    this.ready.catch(() => {}); // reported through onFailed
  }

  receive(data) {
    const request = this.pending.get(data.id);
    if (request === undefined) {
      return;
    }
    if (data.type === 'progress') {
      this.handlers.onProgress?.(data.stage, data.fraction);
      return;
    }
    this.pending.delete(data.id);
    if (data.type === 'reply') {
      request.resolve(data);
    } else {
      const error = new Error(data.message);
      error.name = data.name;
      error.fatal = data.fatal;
      request.reject(error);
      if (data.fatal) {
        // The wasm instance is unusable: whatever else was asked of it fails the same way.
        this.restart(error);
      }
    }
  }

  /**
   * Sends a request once the worker is ready; resolves with the reply message. A request for
   * the last result (NEEDS_RESULT) after `release` waits until it is computed again; a new run
   * ends that computation.
   */
  async request(type, payload = {}, transfer = []) {
    if (type === 'run' && (this.inputs !== null || this.recomputing !== null)) {
      this.restart(); // the released result is superseded
    } else if (NEEDS_RESULT.has(type) && (this.inputs !== null || this.recomputing !== null)) {
      await this.recompute();
    }
    return this.send(type, payload, transfer);
  }

  /**
   * Sends a request as it is once the worker is ready (no waiting for a released result: see
   * `request`); resolves with the reply message.
   */
  async send(type, payload, transfer) {
    await this.ready;
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject });
      this.worker.postMessage({ type, id, ...payload }, transfer);
    });
  }

  /**
   * Terminates the worker (ending whatever it computes) and starts a fresh one. Pending requests
   * fail with `reason` (by default a CancelledError).
   */
  restart(reason = new CancelledError()) {
    this.worker.terminate();
    this.inputs?.frames.forEach((frame) => frame.close());
    this.inputs = null;
    this.recomputing = null;
    for (const { reject } of this.pending.values()) {
      reject(reason);
    }
    this.pending.clear();
    this.start();
  }

  /**
   * Frees the memory of the worker that just handed over a run's result (module comment):
   * replaces it by a fresh worker, which is given `inputs` ({ frames: ImageBitmaps, owned and
   * closed here, options, flow: the result's first flow or null }) of that run again by
   * `recompute` (given the flow, it need not compute it again: less time and memory).
   */
  release(inputs) {
    this.restart();
    this.inputs = inputs;
  }

  /**
   * Decodes a JPEG photo (`bytes`, an ArrayBuffer, transferred) upright at the working size for
   * `maxSide` (www/worker.js `decode-jpeg`) in a worker of its own, started for it and
   * terminated once it replied: the decoder's wasm memory goes back at once, and the pipeline's
   * worker (which may be computing a released result again) neither waits for the decode nor
   * keeps its memory. Resolves to { width, height, frameWidth, frameHeight, pixels, exif };
   * rejects when the decoder refuses the file (the page then lets the browser decode it).
   */
  async decodeJpeg(bytes, maxSide) {
    const worker = new Worker(this.workerUrl(), { type: 'module' });
    try {
      return await new Promise((resolve, reject) => {
        worker.onmessage = ({ data }) => {
          if (data.type === 'ready') {
            worker.postMessage({ type: 'decode-jpeg', id: 0, bytes, maxSide }, [bytes]);
          } else if (data.type === 'reply') {
            resolve(data);
          } else if (data.type === 'error' || data.type === 'failed') {
            reject(new Error(data.message));
          }
        };
        worker.onerror = (event) => {
          event.preventDefault();
          reject(new Error(`the decoding worker failed: ${event.message || 'script error'}`));
        };
      });
    } finally {
      worker.terminate();
    }
  }

  /**
   * Computes the released result again in the worker (once, however often it is asked);
   * resolves when the worker has it. Rejects with a CancelledError when a new run, a cancel or
   * a restart ends it.
   */
  recompute() {
    if (this.inputs === null) {
      return this.recomputing ?? Promise.resolve();
    }
    if (this.recomputing === null) {
      const { frames, options, flow = null } = this.inputs;
      this.inputs = null; // the frames and flow go to the worker (transferred)
      const transfer = flow === null ? frames : [...frames, flow.forward.buffer, flow.backward.buffer];
      const recomputing = this.send('run', { frames, options, quiet: true, flow }, transfer).then(() => {}).finally(() => {
        if (this.recomputing === recomputing) {
          this.recomputing = null;
        }
      });
      recomputing.catch(() => {}); // reported to the requests that wait for it
      this.recomputing = recomputing;
    }
    return this.recomputing;
  }
}
