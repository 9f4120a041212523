// Node entry of the arps worker: runs worker.js inside a worker_threads Worker (started by
// `createWorkerRegistrar()` from `arps/worker-client` when there is no DOM Worker). It gives
// worker.js the `self.postMessage` / `self.addEventListener("message")` it expects, queues the
// messages that arrive before worker.js has run, and, for an "init" request, reads from disk what
// it does not carry (Node's fetch cannot read file: URLs): arps_bg.wasm next to this file, the
// default model models/arps-web.safetensors (unless `weights` replace it), and `weights` given as
// a file: URL.
import { parentPort } from "node:worker_threads";
import { readFile } from "node:fs/promises";

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
    if (typeof data.weights === "string" && data.weights.startsWith("file:")) {
      data = { ...data, weights: await readFile(new URL(data.weights)) };
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
await import("./worker.js");
started = true;
queued.splice(0).forEach(enqueue);
