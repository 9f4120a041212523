// Node entry of the arps worker: runs worker.js inside a worker_threads Worker (started by
// `createWorkerRegistrar()` from `arps/worker-client` when there is no DOM Worker). It gives
// worker.js the `self.postMessage` / `self.addEventListener("message")` it expects, queues the
// messages that arrive before worker.js has run, and, for an "init" request, reads from disk what
// it does not carry (Node's fetch cannot read file: URLs): arps_bg.wasm next to this file, the
// default model models/arps-web.safetensors (unless `weights` replace it), and `wasm`, `model` or
// `weights` given as a file: URL or a path (as Registrar.fromUrl reads them in Node).
import { parentPort } from "node:worker_threads";
import { readFile } from "node:fs/promises";

/**
 * A string naming a file on disk: a `file:` URL (any case), or a path, relative ones to the
 * process's working folder (no URL scheme of two letters or more; `C:\\` is a path).
 */
const fileUrl = (v) => /^file:/i.test(v);
const onDisk = (v) => typeof v === "string" && (fileUrl(v) || !/^[a-z][a-z0-9+.-]+:/i.test(v));
const fromDisk = (v) => readFile(fileUrl(v) ? new URL(v) : v);

const listeners = [];
const queued = [];
let started = false;
globalThis.self = globalThis;
globalThis.postMessage = (message, transfer) => parentPort.postMessage(message, transfer);
globalThis.addEventListener = (type, fn) => {
  if (type === "message") listeners.push(fn);
};
let wasmBytes = null;
let modelBytes = null;
const none = (v) => v === undefined || v === null;
const deliver = async (data) => {
  if (data && data.type === "init") {
    if (none(data.wasm)) {
      wasmBytes ??= readFile(new URL("./arps_bg.wasm", import.meta.url));
      data = { ...data, wasm: await wasmBytes };
    }
    if (none(data.weights) && (none(data.model) || data.model === true)) {
      modelBytes ??= readFile(new URL("./models/arps-web.safetensors", import.meta.url));
      data = { ...data, model: await modelBytes };
    }
    for (const key of ["wasm", "model", "weights"]) {
      // (a model is not read when weights replace it)
      if (!onDisk(data[key]) || (key === "model" && !none(data.weights))) continue;
      try {
        data = { ...data, [key]: await fromDisk(data[key]) };
      } catch (e) {
        // the load fails as a fetch would: an error naming the file, for createWorkerRegistrar
        parentPort.postMessage({ id: data.id, type: "error", message: `arps worker: reading ${key} ${data[key]} failed: ${e?.message ?? e}`, name: "Error" });
        return;
      }
    }
  }
  for (const fn of listeners) fn({ data });
};
let chain = Promise.resolve();
const enqueue = (data) => {
  // In order, even while the .wasm is being read.
  chain = chain.then(() => deliver(data));
};
parentPort.on("message", (data) => {
  if (started) enqueue(data);
  else queued.push(data);
});
// a request whose data could not be received here (a buffer detached in its transfer list):
// the client fails the request in flight instead of waiting for it
parentPort.on("messageerror", (e) => {
  parentPort.postMessage({ type: "undeliverable", message: String(e?.message ?? e) });
});
await import("./worker.js");
started = true;
queued.splice(0).forEach(enqueue);
