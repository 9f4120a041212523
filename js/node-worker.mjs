// Node entry of the arps worker: runs worker.js inside a worker_threads Worker (started by
// `createWorkerRegistrar()` from `arps/worker-client` when there is no DOM Worker). It gives
// worker.js the `self.postMessage` / `self.addEventListener("message")` it expects, queues the
// messages that arrive before worker.js has run, and, when an "init" request carries no `wasm`,
// reads arps_bg.wasm from disk next to this file (Node's fetch cannot read file: URLs).
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
const deliver = async (data) => {
  if (data && data.type === "init" && (data.wasm === undefined || data.wasm === null)) {
    wasmBytes ??= readFile(new URL("./arps_bg.wasm", import.meta.url));
    data = { ...data, wasm: await wasmBytes };
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
