// The main thread's side of the worker (www/worker.js): starts it, sends requests and matches
// the replies, forwards progress, and cancels a run by terminating the worker and starting a
// fresh one (a wasm computation cannot be interrupted from outside).

/** A request that ended because the worker was terminated (cancel) or replaced (crash). */
export class CancelledError extends Error {
  constructor() {
    super('cancelled');
    this.name = 'CancelledError';
  }
}

export class Pipeline {
  /**
   * @param {object} handlers
   *   onProgress(stage, fraction): progress of the running reconstruction;
   *   onReady({ version, defaults, startMs }): each time a (re)started worker has loaded its module;
   *   onFailed(message): the worker could not load its module.
   * @param {'lean' | 'full'} module the worker's wasm build (see www/worker.js)
   */
  constructor(handlers, module = 'lean') {
    this.handlers = handlers;
    this.module = module;
    this.worker = null;
    this.pending = new Map();
    this.nextId = 1;
    this.ready = null;
    this.start();
  }

  /** Starts a worker; `this.ready` resolves once its wasm module is loaded. */
  start() {
    const started = performance.now();
    const url = new URL('./worker.js', import.meta.url);
    if (this.module !== 'lean') {
      url.searchParams.set('module', this.module);
    }
    const worker = new Worker(url, { type: 'module' });
    this.worker = worker;
    this.ready = new Promise((resolve, reject) => {
      worker.onmessage = ({ data }) => {
        if (data.type === 'ready') {
          const info = { version: data.version, defaults: data.defaults, startMs: performance.now() - started };
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

  /** Sends a request once the worker is ready; resolves with the reply message. */
  async request(type, payload = {}, transfer = []) {
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
    for (const { reject } of this.pending.values()) {
      reject(reason);
    }
    this.pending.clear();
    this.start();
  }
}
