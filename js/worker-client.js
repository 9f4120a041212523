// Promise API around the arps worker (worker.js): the engine runs off the main thread, so the
// page never freezes. Types: worker-client.d.ts.
//
//   import { createWorkerRegistrar } from "arps/worker-client";
//   const arps = await createWorkerRegistrar();
//   const result = await arps.register(source, target, { icp: "plane" }, { onProgress: console.log });
//   mesh.matrix.fromArray(result.matrix);

/** Progress stages, in order. */
export const STAGES = Object.freeze(["loading", "preparing", "network", "refining", "done"]);

/**
 * Starts the worker, loads the engine and the model, and resolves to a registrar whose
 * methods return promises.
 */
export async function createWorkerRegistrar(options = {}) {
  const worker =
    options.worker ?? new Worker(new URL("./worker.js", import.meta.url), { type: "module", name: "arps" });
  const pending = new Map();
  let nextId = 1;
  let dead = null;

  const fail = (error) => {
    dead = error;
    for (const p of pending.values()) p.reject(error);
    pending.clear();
  };
  worker.addEventListener("message", (event) => {
    const msg = event.data;
    const p = msg && pending.get(msg.id);
    if (!p) return;
    switch (msg.type) {
      case "progress":
        if (p.onProgress) {
          try {
            p.onProgress(msg.stage);
          } catch (e) {
            // A throwing progress callback must not break the request.
            setTimeout(() => {
              throw e;
            });
          }
        }
        return;
      case "error": {
        pending.delete(msg.id);
        const e = new Error(msg.message);
        if (msg.name && msg.name !== "Error") e.name = msg.name;
        p.reject(e);
        return;
      }
      default:
        pending.delete(msg.id);
        p.resolve(msg);
    }
  });
  worker.addEventListener("error", (event) => {
    // A worker that failed to load or crashed: every pending and later request rejects.
    if (event && typeof event.preventDefault === "function") event.preventDefault();
    const message = (event && (event.message || (event.error && event.error.message))) || "worker failed";
    fail(new Error(`arps worker: ${message}`));
  });

  const request = (message, { onProgress, transfer = [] } = {}) => {
    if (dead) return Promise.reject(dead);
    const id = nextId++;
    return new Promise((resolve, reject) => {
      pending.set(id, { resolve, reject, onProgress });
      worker.postMessage({ ...message, id }, transfer);
    });
  };

  const ready = await request(
    { type: "init", wasm: options.wasm, weights: options.weights },
    { onProgress: options.onProgress },
  ).catch((e) => {
    worker.terminate();
    throw e;
  });

  return {
    provenance: ready.provenance,
    modelConfig: ready.modelConfig,
    async register(source, target, registerOptions, { onProgress, transfer = false } = {}) {
      const buffers = transfer ? uniqueBuffers([source, target]) : [];
      const reply = await request({ type: "register", source, target, options: registerOptions }, { onProgress, transfer: buffers });
      return reply.result;
    },
    async parsePointCloud(bytes, fileName, { transfer = false } = {}) {
      const buffers = transfer ? uniqueBuffers([bytes]) : [];
      const reply = await request({ type: "parse", bytes, fileName }, { transfer: buffers });
      return reply.points;
    },
    terminate() {
      worker.terminate();
      fail(new Error("arps worker: terminated"));
    },
  };
}

function uniqueBuffers(views) {
  const out = [];
  for (const v of views) {
    const b = ArrayBuffer.isView(v) ? v.buffer : v instanceof ArrayBuffer ? v : null;
    if (b && !out.includes(b)) out.push(b);
  }
  return out;
}
