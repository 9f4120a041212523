// The worker and its promise API (pkg/worker.js + pkg/worker-client.js), driven from Node: the
// worker runs in worker_threads behind a small shim (node-worker-shim.mjs), the client is the
// package's own createWorkerRegistrar.
import test from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { Worker } from "node:worker_threads";
import path from "node:path";
import { pathToFileURL } from "node:url";
import { pkg, source, target, sourcePly, errors, coreStubbed } from "./common.mjs";

const { createWorkerRegistrar, STAGES } = await import(pathToFileURL(path.join(pkg, "worker-client.js")).href);
const wasm = readFileSync(path.join(pkg, "arps_bg.wasm"));

/** A worker_threads Worker running pkg/worker.js, with the DOM Worker methods the client uses. */
function nodeWorker() {
  const w = new Worker(new URL("./node-worker-shim.mjs", import.meta.url), {
    workerData: { workerUrl: pathToFileURL(path.join(pkg, "worker.js")).href },
  });
  return {
    postMessage: (m, transfer) => w.postMessage(m, transfer),
    addEventListener: (type, fn) => w.on(type, (v) => fn(type === "message" ? { data: v } : { message: v?.message, error: v })),
    terminate: () => w.terminate(),
  };
}

test("worker: loads, reports progress, rejects errors and keeps working", async () => {
  const initStages = [];
  const arps = await createWorkerRegistrar({ worker: nodeWorker(), wasm, onProgress: (s) => initStages.push(s) });
  try {
    assert.deepEqual(initStages, ["loading"]);
    assert.equal(arps.modelConfig.preset, "web");
    assert.equal(typeof arps.provenance, "object");
    assert.deepEqual([...STAGES], ["loading", "preparing", "network", "refining", "done"]);

    await assert.rejects(arps.register(source(), target(), { nope: 1 }), /unknown field `nope`/);
    await assert.rejects(arps.register(new Float32Array(5), target()), /packed xyz buffer has length 5/);
    if (coreStubbed) return;

    const stages = [];
    const res = await arps.register(source(), target(), undefined, { onProgress: (s) => stages.push(s) });
    assert.deepEqual(stages.filter((s) => s !== "network" && s !== "refining"), ["preparing", "done"]);
    assert.ok(res.matrix instanceof Float32Array && res.matrix.length === 16);
    const { rot, tr } = errors(res.matrix);
    assert.ok(rot < 1 && tr < 0.02, `rotation ${rot} deg, translation ${tr}`);

    // Transferred inputs: the caller's arrays are detached; the result is the same.
    const s = source();
    const t = target();
    const res2 = await arps.register(s, t, {}, { transfer: true });
    assert.equal(s.length, 0, "source buffer transferred");
    assert.deepEqual([...res2.matrix], [...res.matrix]);

    // Concurrent requests resolve to their own results.
    const [a, b] = await Promise.all([
      arps.register(source(), target(), { icp: "off" }),
      arps.register(source(), target(), { icp: "point" }),
    ]);
    assert.equal(a.iterations, 0);
    assert.ok(b.iterations > 0);

    const points = await arps.parsePointCloud(sourcePly, "source.ply");
    assert.deepEqual([...points], [...source()]);
  } finally {
    arps.terminate();
  }
});

test("worker: custom weights that do not load reject createWorkerRegistrar", async () => {
  await assert.rejects(
    createWorkerRegistrar({ worker: nodeWorker(), wasm, weights: new Uint8Array([1, 2, 3]) }),
    /^Error: weights: /,
  );
});

test("worker: requests after terminate reject", async () => {
  const arps = await createWorkerRegistrar({ worker: nodeWorker(), wasm });
  arps.terminate();
  await assert.rejects(arps.register(source(), target()), /terminated/);
});
