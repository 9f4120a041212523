// Runs pkg/worker.js (a browser module worker) inside a Node worker_threads Worker for the tests:
// gives it the `self.postMessage` / `self.addEventListener("message")` it expects. As in a
// browser, messages that arrive before the worker module has run are queued, not lost.
import { parentPort, workerData } from "node:worker_threads";

const listeners = [];
const queued = [];
let started = false;
globalThis.self = globalThis;
globalThis.postMessage = (message, transfer) => parentPort.postMessage(message, transfer);
globalThis.addEventListener = (type, fn) => {
  if (type === "message") listeners.push(fn);
};
const deliver = (data) => {
  for (const fn of listeners) fn({ data });
};
parentPort.on("message", (data) => {
  // Test hook (this shim is test code, not the package): crash the worker like a fatal error would.
  if (data && data.type === "test:crash") throw new Error("worker crashed (test)");
  if (started) deliver(data);
  else queued.push(data);
});
await import(workerData.workerUrl);
started = true;
queued.splice(0).forEach(deliver);
