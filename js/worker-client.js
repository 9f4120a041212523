// Promise API around the arps worker (worker.js): the engine runs off the main thread, so the
// page never freezes. Types: worker-client.d.ts.
//
//   import { createWorkerRegistrar } from "arps/worker-client";
//   const arps = await createWorkerRegistrar();
//   const result = await arps.register(source, target, { icp: "plane" }, { onProgress: console.log, signal });
//   mesh.matrix.fromArray(result.T_target_source);
//
// One worker at a time, one request at a time on it (the others wait in call order). It is
// replaced by a fresh one (started on the next request) when it crashes, when the engine in it
// traps, and when the request it runs is aborted: that request rejects, nothing is retried
// behind the caller's back, the requests waiting go to the new worker, and the client keeps
// working. A request aborted while it waits is dropped alone.

import { inheritedMessage, inheritedOption } from "./facade.js";

/** Progress stages, in order. */
export const STAGES = Object.freeze(["loading", "preparing", "network", "refining", "done"]);

/** The default worker where there is a DOM Worker (browsers, bundlers). */
const domWorker = () => new Worker(new URL("./worker.js", import.meta.url), { type: "module", name: "arps" });

/**
 * The default worker under Node (no DOM Worker) and Deno: a worker_threads Worker running node-worker.mjs,
 * behind the DOM Worker methods the client uses. An exit reports as an error, so a crashed
 * worker's requests reject.
 */
async function nodeWorkerFactory() {
  if (typeof process !== "object" || !process?.versions?.node) {
    throw new Error("arps worker: no Worker in this environment (pass `createWorker` or `worker`)");
  }
  // A variable specifier keeps bundlers from resolving the Node module for the browser.
  const specifier = "node:worker_threads";
  const { Worker: ThreadWorker } = await import(/* webpackIgnore: true */ /* @vite-ignore */ specifier);
  return () => {
    const w = new ThreadWorker(new URL("./node-worker.mjs", import.meta.url), { name: "arps" });
    return {
      postMessage: (message, transfer) => w.postMessage(message, transfer),
      addEventListener: (type, fn) => {
        if (type === "message") w.on("message", (data) => fn({ data }));
        if (type === "error") {
          w.on("error", (error) => fn({ message: error?.message, error }));
          w.on("exit", (code) => fn({ message: `the worker exited with code ${code}` }));
        }
      },
      terminate: () => void w.terminate(),
      // (the client holds the process only while a request is in flight: `Pending`)
      ref: () => w.ref(),
      unref: () => w.unref(),
    };
  };
}

/**
 * A worker's requests in flight, by id. A worker that can be unreferenced (Node's worker_threads)
 * keeps the process alive only while it has some: a script that never calls `terminate()` still
 * exits once its last answer is in.
 */
class Pending extends Map {
  constructor(worker) {
    super();
    this.worker = worker;
  }
  set(id, request) {
    super.set(id, request);
    if (typeof this.worker.ref === "function") this.worker.ref();
    return this;
  }
  delete(id) {
    const had = super.delete(id);
    if (this.size === 0 && typeof this.worker.unref === "function") this.worker.unref();
    return had;
  }
}

/**
 * Starts the worker, loads the engine and the model, and resolves to a registrar whose
 * methods return promises.
 */
export async function createWorkerRegistrar(options = {}) {
  options = checkedOptions(options);
  const given = options.worker ?? null;
  // (Deno has a DOM Worker, but one that cannot be unreferenced: its worker_threads Worker can)
  const dom = typeof Worker === "function" && typeof globalThis.Deno !== "object";
  const createWorker = options.createWorker ?? (given ? null : dom ? domWorker : await nodeWorkerFactory());
  // A Response body can be read once; a restarted worker needs the bytes again. URLs travel as
  // strings (a URL object cannot be posted).
  const portable = async (v) => {
    if (typeof Response === "function" && v instanceof Response) return v.arrayBuffer();
    return v instanceof URL ? v.href : v;
  };
  const wasm = await portable(options.wasm);
  const model = await portable(options.model);
  const weights = await portable(options.weights);
  let nextId = 1;
  let current = null; // the live worker: { worker, pending, ready, dead }
  let terminated = false;
  let first = true;

  /** Stops worker `w` for good: its pending requests reject with `error` (or `errorFor(id)`). */
  const retire = (w, error, errorFor = () => error) => {
    if (w.dead) return;
    w.dead = error;
    if (current === w) current = null;
    try {
      w.worker.terminate();
    } catch {
      /* already gone */
    }
    for (const [id, p] of w.pending) p.reject(errorFor(id));
    w.pending.clear();
  };

  const send = (w, message, { onProgress, transfer = [] } = {}) => {
    if (w.dead) return { id: 0, promise: Promise.reject(w.dead) };
    const id = nextId++;
    const promise = new Promise((resolve, reject) => {
      w.pending.set(id, { resolve, reject, onProgress });
      try {
        w.worker.postMessage({ ...message, id }, transfer);
      } catch (e) {
        // Nothing reached the worker (e.g. a DataCloneError): this request alone fails.
        w.pending.delete(id);
        reject(unsendable(e));
      }
    });
    return { id, promise };
  };

  const spawn = (onProgress) => {
    let worker;
    if (first && given) worker = given;
    else if (createWorker) worker = createWorker();
    else throw new Error("arps worker: the worker stopped and cannot be restarted (pass `createWorker` instead of `worker` to allow restarts)");
    if (!worker || typeof worker.postMessage !== "function" || typeof worker.addEventListener !== "function") {
      throw new Error(`arps worker: ${first && given ? "worker" : "createWorker()"} is ${worker === null ? "null" : typeof worker}, not a Worker (an object with postMessage and addEventListener)`);
    }
    first = false;
    const w = { worker, pending: new Pending(worker), dead: null, ready: null };
    worker.addEventListener("message", (event) => {
      const msg = event.data;
      if (msg && msg.type === "undeliverable") {
        // a request the worker could not receive (its data could not be cloned there): the
        // requests in flight fail, the worker stays (requests run one at a time; the init is
        // answered before any is sent)
        for (const [id, p] of w.pending) {
          if (id === w.initId && w.loaded !== true) continue;
          w.pending.delete(id);
          p.reject(new Error(`arps worker: the worker could not receive the request (${msg.message}); send it again with fresh arrays`));
        }
        return;
      }
      const p = msg && w.pending.get(msg.id);
      if (!p) return;
      switch (msg.type) {
        case "progress":
          if (p.onProgress) {
            try {
              p.onProgress(msg.stage);
            } catch (e) {
              // As in the engine's own API, a throwing callback fails its request (with an Error
              // that says so); the worker's answer, when it comes, is dropped.
              w.pending.delete(msg.id);
              p.reject(new Error(`onProgress threw: ${e?.message ?? e}`, { cause: e }));
            }
          }
          return;
        case "error": {
          w.pending.delete(msg.id);
          const e = new Error(msg.message);
          if (msg.name && msg.name !== "Error") e.name = msg.name;
          if (msg.code) e.code = msg.code;
          p.reject(e);
          // After a trap the engine re-instantiated itself, but the worker's memory may be
          // huge (wasm memory never shrinks): start afresh on the next request.
          if (msg.code === "ARPS_TRAPPED" || msg.code === "ARPS_UNUSABLE") {
            retire(w, new Error(`arps worker: stopped after a trap in another request (${msg.message})`));
          }
          return;
        }
        default:
          w.pending.delete(msg.id);
          p.resolve(msg);
      }
    });
    worker.addEventListener("error", (event) => {
      // A worker that failed to load or crashed: its pending requests reject; the next request
      // starts a new worker.
      if (event && typeof event.preventDefault === "function") event.preventDefault();
      const given = event && (event.message || (event.error && event.error.message));
      // a script that never loaded (a 404, a page served in its place) reports no message
      const message =
        given ||
        (w.loaded
          ? "worker failed"
          : "the worker failed to start: its script (worker.js next to worker-client.js) did not load or run. " +
            "Under Vite's dev server, exclude the package from dependency pre-bundling " +
            '(vite.config: optimizeDeps: { exclude: ["arps"] }), or pass createWorker');
      retire(w, new Error(`arps worker: ${message}`));
    });
    const init = send(w, { type: "init", wasm, model, weights }, { onProgress });
    w.initId = init.id;
    w.ready = init.promise;
    w.ready.then(
      () => {
        w.loaded = true;
      },
      (e) => retire(w, e),
    );
    return w;
  };

  /** The live worker, started (and loaded) if there is none. */
  const live = async (onProgress) => {
    if (terminated) throw new Error("arps worker: terminated");
    if (!current) current = spawn(onProgress);
    const w = current;
    await w.ready;
    return w;
  };

  // Requests run one at a time, in call order: each waits in `queue` until the one before it
  // has answered. A request aborted while it waits is dropped from the queue alone; an aborted
  // request that runs stops the worker, and the requests waiting behind it go to the next one.
  const queue = [];
  let running = false;
  const pump = () => {
    if (running || queue.length === 0) return;
    running = true;
    queue.shift().run().finally(() => {
      running = false;
      pump();
    });
  };

  /** The live worker when it is loaded and usable, else null. */
  const loadedWorker = () => (current && current.loaded && !current.dead && !terminated ? current : null);

  const request = (message, { onProgress, transfer = [], signal } = {}) => {
    if (signal !== undefined && signal !== null && (typeof signal !== "object" || typeof signal.addEventListener !== "function")) {
      return Promise.reject(new Error(`signal: expected an AbortSignal (e.g. AbortSignal.timeout(ms), or an AbortController's signal), got ${typeof signal}`));
    }
    if (signal?.aborted) return Promise.reject(abortReason(signal));
    // A request sent now has its inputs copied (or transferred) as the call is made, as
    // postMessage does: a caller may refill its arrays once the call returns. One that waits
    // (another request runs, or the worker loads) has them copied now, and the copy is sent
    // when its turn comes.
    const now = !running && queue.length === 0 && loadedWorker();
    let payload = message;
    let moved = transfer;
    if (!now && typeof structuredClone === "function") {
      try {
        payload = structuredClone(message, { transfer });
        moved = [];
      } catch (e) {
        return Promise.reject(unsendable(e));
      }
    }
    return new Promise((resolve, reject) => {
      let w = null;
      let id = 0;
      let done = false;
      const job = {};
      const onAbort = () => {
        if (done) return;
        done = true;
        const aborted = abortReason(signal);
        reject(aborted);
        const waiting = queue.indexOf(job);
        if (waiting >= 0) queue.splice(waiting, 1);
        // Sent: the engine cannot be interrupted mid-call, so the worker stops (a request that
        // waited, or whose worker was still loading, was never sent: the worker stays).
        if (w && id) {
          retire(w, aborted, (other) =>
            other === id ? aborted : new Error("arps worker: stopped to cancel another request; this request did not complete, send it again"),
          );
        }
      };
      const settle = (fn) => (value) => {
        if (done) return;
        done = true;
        signal?.removeEventListener("abort", onAbort);
        fn(value);
      };
      signal?.addEventListener("abort", onAbort, { once: true });
      // its turn: the live worker (started and loaded if there is none), then the request; a
      // loaded worker gets it at once (synchronously when it is sent as the call is made)
      const go = (ready) => {
        if (done) return undefined; // aborted while the worker was loading: not sent
        w = ready;
        const sent = send(w, payload, { onProgress, transfer: moved });
        id = sent.id;
        return sent.promise.then(settle(resolve), settle(reject));
      };
      job.run = () => {
        if (done) return Promise.resolve();
        const loaded = loadedWorker();
        return loaded ? Promise.resolve(go(loaded)) : live(onProgress).then(go, settle(reject));
      };
      queue.push(job);
      pump();
    });
  };

  /**
   * `request` for a method: the buffers of `inputs` transferred when its request options say
   * `transfer`, their `signal` passed on (and `onProgress`, for `register`).
   */
  const ask = (message, inputs, req, onProgress = undefined) => {
    const { transfer = false, signal } = req ?? {};
    // a buffer transferred away by an earlier request ({ transfer: true }) cannot be sent again:
    // refused here, as the engine's own API refuses it, before anything is posted or moved
    for (const v of inputs) {
      if (isDetached(v)) {
        const name = Object.keys(message).find((k) => message[k] === v) ?? "input";
        return Promise.reject(
          new Error(
            `${name}: its buffer cannot be read: it was transferred away (to a worker, say: an earlier request with { transfer: true }) and is detached; pass a fresh array`,
          ),
        );
      }
    }
    return request(message, { onProgress, transfer: transfer ? uniqueBuffers(inputs) : [], signal });
  };

  current = spawn(options.onProgress);
  const ready = await current.ready; // on failure the worker was already stopped

  return {
    provenance: ready.provenance,
    modelConfig: ready.modelConfig,
    async register(source, target, registerOptions, req) {
      checkRequest("register", req, ["onProgress", "transfer", "signal"]);
      inheritedOptions(registerOptions);
      const message = { type: "register", source, target, options: registerOptions };
      return (await ask(message, [source, target], req, req?.onProgress)).result;
    },
    async parsePointCloud(bytes, fileName, readOptions, req) {
      checkRequest("parsePointCloud", req);
      misplacedRequest("parsePointCloud", readOptions);
      inheritedOptions(readOptions);
      return (await ask({ type: "parse", bytes, fileName, options: readOptions }, [bytes], req)).points;
    },
    async readPointCloud(bytes, fileName, readOptions, req) {
      checkRequest("readPointCloud", req);
      misplacedRequest("readPointCloud", readOptions);
      inheritedOptions(readOptions);
      return (await ask({ type: "read", bytes, fileName, options: readOptions }, [bytes], req)).cloud;
    },
    async transformPointCloud(cloud, matrix, req) {
      checkRequest("transformPointCloud", req);
      return (await ask({ type: "transform", cloud, matrix }, [cloud], req)).cloud;
    },
    async writePly(cloud, req) {
      checkRequest("writePly", req);
      return (await ask({ type: "write", cloud }, [cloud], req)).bytes;
    },
    async listScans(bytes, fileName, req) {
      checkRequest("listScans", req);
      return (await ask({ type: "scans", bytes, fileName }, [bytes], req)).scans;
    },
    async transformFile(bytes, fileName, matrix, readOptions, req) {
      checkRequest("transformFile", req);
      misplacedRequest("transformFile", readOptions, "fifth");
      inheritedOptions(readOptions);
      return (await ask({ type: "move", bytes, fileName, matrix, options: readOptions }, [bytes], req)).bytes;
    },
    async forgetTarget(req) {
      checkRequest("forgetTarget", req);
      // a worker not loaded (or none, after an abort, a crash or a trap) holds no target: no
      // worker is started for nothing to forget
      if (!current || !current.loaded || current.dead) return;
      await ask({ type: "forget" }, [], req);
    },
    terminate() {
      terminated = true;
      if (current) retire(current, new Error("arps worker: terminated"));
    },
  };
}

/**
 * Throws when a method's request options (its last argument) are not an object of its own keys
 * (`known`): a typo (`tranfser`) or a `transfer` list as `postMessage` takes one would otherwise
 * be ignored, or read as `true`.
 */
function checkRequest(what, req, known = ["transfer", "signal"]) {
  if (req === undefined || req === null) return;
  if (typeof req !== "object" || Array.isArray(req)) {
    throw new Error(`${what}: the request options must be an object (${known.join(", ")}), got ${Array.isArray(req) ? "an array" : typeof req}`);
  }
  for (const key of Object.keys(req)) {
    if (!known.includes(key)) throw new Error(`${what}: unknown request option \`${key}\`; the request options are ${known.join(", ")}`);
  }
  if (req.transfer !== undefined && typeof req.transfer !== "boolean") {
    throw new Error(`${what}: transfer: expected true or false (the client finds the inputs' buffers itself), got ${Array.isArray(req.transfer) ? "an array" : typeof req.transfer}`);
  }
  if (req.onProgress !== undefined && req.onProgress !== null && typeof req.onProgress !== "function") {
    throw new Error(`${what}: onProgress: expected a function, got ${typeof req.onProgress}`);
  }
}

/**
 * Throws when `options` has an enumerable option inherited from a prototype: posting copies own
 * properties only, so the worker would run without it (the engine's facade refuses it too; a
 * `Map` or `Date` reaches the worker as one, and is refused there).
 */
function inheritedOptions(options) {
  if (options === null || typeof options !== "object") return;
  let inherited;
  try {
    inherited = inheritedOption(options);
  } catch {
    return; // a Proxy that throws: the worker's copy says so
  }
  if (inherited !== undefined) throw new Error(inheritedMessage(inherited));
}

/**
 * Throws when the request options (`transfer`, `signal`) were passed where the read options go
 * (they come after them: fourth, as for `register`; fifth for `transformFile`).
 */
function misplacedRequest(what, readOptions, place = "fourth") {
  if (readOptions && typeof readOptions === "object" && ("transfer" in readOptions || "signal" in readOptions)) {
    throw new Error(`${what}: the request options (transfer, signal) come ${place}, after the read options (e.g. { surfacePoints })`);
  }
}

/**
 * The rejection of a request that cannot be sent (postMessage or the copy threw): an `Error`
 * named as what was thrown (`DataCloneError`; `TypeError` for a buffer that cannot be
 * transferred), that error as its `cause`.
 */
function unsendable(e) {
  const err = new Error(`arps worker: the request cannot be sent to the worker (${e?.name ?? "Error"}: ${e?.message ?? e})`, { cause: e });
  if (e?.name) err.name = e.name;
  return err;
}

/**
 * The rejection of an aborted request, as `fetch` rejects: the signal's reason (a `DOMException`
 * named `AbortError` from `abort()`, `TimeoutError` from `AbortSignal.timeout`, or the value given
 * to `abort(reason)`), else a `DOMException` named `AbortError`.
 */
function abortReason(signal) {
  const reason = signal.reason;
  return reason !== undefined ? reason : new DOMException("arps worker: the request was aborted", "AbortError");
}

/** The options of `createWorkerRegistrar`, checked: a plain object (or nothing) of known keys, functions where they are. */
function checkedOptions(options) {
  if (options === undefined || options === null) return {};
  if (typeof options !== "object" || Array.isArray(options)) {
    throw new Error(`createWorkerRegistrar: expected an options object (or nothing), got ${Array.isArray(options) ? "an Array" : typeof options}`);
  }
  const known = ["wasm", "model", "weights", "worker", "createWorker", "onProgress"];
  for (const key of Object.keys(options)) {
    if (!known.includes(key)) throw new Error(`createWorkerRegistrar: unknown option \`${key}\`; the options are ${known.join(", ")}`);
  }
  for (const key of ["createWorker", "onProgress"]) {
    const v = options[key];
    if (v !== undefined && v !== null && typeof v !== "function") throw new Error(`createWorkerRegistrar: ${key} must be a function, got ${typeof v}`);
  }
  return options;
}

/** The buffer a request input holds (a view's, a `{ points, origin }` cloud's points'), else null. */
function bufferOf(item) {
  let v = item;
  if (item && typeof item === "object" && !ArrayBuffer.isView(item) && !(item instanceof ArrayBuffer)) {
    try {
      v = item.points;
    } catch {
      v = null;
    }
  }
  return ArrayBuffer.isView(v) ? v.buffer : v instanceof ArrayBuffer ? v : null;
}

/** Whether a request input's buffer was transferred away (detached): a view of it cannot be made. */
function isDetached(item) {
  const b = bufferOf(item);
  if (!b || (typeof SharedArrayBuffer === "function" && b instanceof SharedArrayBuffer)) return false;
  try {
    new Uint8Array(b, 0, 0);
    return false;
  } catch {
    return true;
  }
}

function uniqueBuffers(views) {
  const out = [];
  for (const item of views) {
    // (a cloud's points getter that throws is left to the engine's own check, which names it)
    const b = bufferOf(item);
    // a SharedArrayBuffer is shared, not transferred (and cannot be)
    const shared = typeof SharedArrayBuffer === "function" && b instanceof SharedArrayBuffer;
    if (b && !shared && !out.includes(b)) out.push(b);
  }
  return out;
}
