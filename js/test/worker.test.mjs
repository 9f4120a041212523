// The worker and its promise API (pkg/worker.js + pkg/worker-client.js), driven from Node: the
// worker runs in worker_threads behind a small shim (node-worker-shim.mjs), the client is the
// package's own createWorkerRegistrar.
import test from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { Worker } from "node:worker_threads";
import path from "node:path";
import { pathToFileURL } from "node:url";
import { pkg, root, source, target, sourcePly, errors } from "./common.mjs";

const { createWorkerRegistrar, STAGES } = await import(pathToFileURL(path.join(pkg, "worker-client.js")).href);
const wasm = readFileSync(path.join(pkg, "arps_bg.wasm"));
// The test shim is a plain worker: it gets the default model like the engine, as bytes.
const model = readFileSync(path.join(pkg, "models", "arps-web.safetensors"));

/**
 * A worker_threads Worker running pkg/worker.js, with the DOM Worker methods the client uses.
 * `crash()` makes it die with an uncaught error (through the test shim).
 */
function nodeWorker() {
  const w = new Worker(new URL("./node-worker-shim.mjs", import.meta.url), {
    workerData: { workerUrl: pathToFileURL(path.join(pkg, "worker.js")).href },
  });
  nodeWorker.started++;
  return {
    postMessage: (m, transfer) => w.postMessage(m, transfer),
    addEventListener: (type, fn) => {
      if (type === "message") w.on("message", (v) => fn({ data: v }));
      if (type === "error") {
        w.on("error", (v) => fn({ message: v?.message, error: v }));
        w.on("exit", (code) => fn({ message: `exited with code ${code}` }));
      }
    },
    terminate: () => w.terminate(),
    crash: () => w.postMessage({ type: "test:crash" }),
  };
}
nodeWorker.started = 0;

/** A larger pair (the fixture, each point repeated with a small deterministic jitter). */
function upsampled(cloud, copies) {
  const out = new Float32Array(cloud.length * copies);
  let seed = 12345;
  const rand = () => ((seed = (seed * 1103515245 + 12345) >>> 0) / 2 ** 32 - 0.5) * 0.004;
  for (let c = 0; c < copies; c++) for (let i = 0; i < cloud.length; i++) out[c * cloud.length + i] = cloud[i] + (c ? rand() : 0);
  return out;
}

test("worker: options that are not its own, and a createWorker that makes no worker, are refused by name", async () => {
  await assert.rejects(createWorkerRegistrar({ onprogress: () => {} }), /^Error: createWorkerRegistrar: unknown option `onprogress`; the options are wasm, model, weights, worker, createWorker, onProgress/);
  await assert.rejects(createWorkerRegistrar("fast"), /^Error: createWorkerRegistrar: expected an options object \(or nothing\), got string/);
  await assert.rejects(createWorkerRegistrar({ createWorker: "worker.js" }), /^Error: createWorkerRegistrar: createWorker must be a function, got string/);
  await assert.rejects(createWorkerRegistrar({ createWorker: () => null, wasm, model }), /^Error: arps worker: createWorker\(\) is null, not a Worker/);
});

test("worker: loads, reports progress, rejects errors and keeps working", async () => {
  const initStages = [];
  const arps = await createWorkerRegistrar({ worker: nodeWorker(), wasm, model, onProgress: (s) => initStages.push(s) });
  try {
    assert.deepEqual(initStages, ["loading"]);
    assert.equal(arps.modelConfig.preset, "web");
    assert.equal(typeof arps.provenance, "object");
    assert.deepEqual([...STAGES], ["loading", "preparing", "network", "refining", "done"]);

    await assert.rejects(arps.register(source(), target(), { nope: 1 }), /unknown field `nope`/);
    await assert.rejects(arps.register(new Float32Array(5), target()), /packed xyz buffer has length 5/);
    // request options (the last argument): a typo, a transfer list as postMessage takes one, a
    // register-only option elsewhere, a non-object are refused by name, nothing sent or moved
    const kept = source();
    await assert.rejects(arps.register(kept, target(), {}, { tranfser: true }), /^Error: register: unknown request option `tranfser`; the request options are onProgress, transfer, signal/);
    await assert.rejects(arps.register(kept, target(), {}, { transfer: [kept.buffer] }), /^Error: register: transfer: expected true or false .*got an array/);
    await assert.rejects(arps.writePly(kept, { onProgress: () => {} }), /^Error: writePly: unknown request option `onProgress`; the request options are transfer, signal/);
    await assert.rejects(arps.listScans(new Uint8Array(4), "a.ply", true), /^Error: listScans: the request options must be an object/);
    assert.equal(kept.length, source().length);

    const stages = [];
    const res = await arps.register(source(), target(), undefined, { onProgress: (s) => stages.push(s) });
    assert.deepEqual(stages.filter((s) => s !== "network" && s !== "refining"), ["preparing", "done"]);
    assert.ok(Array.isArray(res.T_target_source) && res.T_target_source.length === 16);
    const { rot, tr } = errors(res.T_target_source);
    assert.ok(rot < 1 && tr < 0.02, `rotation ${rot} deg, translation ${tr}`);
    // A throwing progress callback fails its request, as in the engine's own API (not the
    // process); the next request is answered.
    const boom = new Error("progress boom");
    await assert.rejects(arps.register(source(), target(), {}, { onProgress: () => { throw boom; } }), (e) => /^onProgress threw: progress boom/.test(e.message) && e.cause === boom);
    assert.deepEqual((await arps.register(source(), target())).T_target_source, res.T_target_source);

    // Transferred inputs: the caller's arrays are detached; the result is the same.
    const s = source();
    const t = target();
    const res2 = await arps.register(s, t, {}, { transfer: true });
    assert.equal(s.length, 0, "source buffer transferred");
    assert.deepEqual(res2.T_target_source, res.T_target_source);
    await assert.rejects(arps.register(source(), target(), {}, { signal: "stop" }), /^Error: signal: expected an AbortSignal/);
    // The same (now detached) arrays sent again: refused before anything is posted or moved (a
    // detached buffer in a transfer list never reached the worker, and the queue waited on it)
    const fresh = target();
    await assert.rejects(arps.register(s, fresh, {}, { transfer: true }), /^Error: source: its buffer cannot be read: it was transferred away/);
    assert.equal(fresh.length, target().length, "the other array is not transferred by a refused request");
    await assert.rejects(arps.parsePointCloud(s, "x.ply"), /^Error: bytes: its buffer cannot be read/);
    assert.deepEqual((await arps.register(source(), fresh)).T_target_source, res.T_target_source);
    // The source saved in the target's frame, in the worker: moved, then PLY bytes; a bad
    // matrix rejects and the client keeps working.
    const moved = await arps.transformPointCloud({ points: source(), origin: [5e5, 4e6, 10] }, res.T_target_source);
    assert.ok(moved.points instanceof Float32Array && moved.points.length === source().length && moved.origin.length === 3);
    const ply = await arps.writePly(moved, { transfer: true });
    assert.equal(moved.points.length, 0, "written cloud's points transferred");
    assert.match(new TextDecoder().decode(ply.subarray(0, 150)), /property double x/);
    await assert.rejects(arps.transformPointCloud(source(), [1, 2, 3]), /matrix has 3 elements/);
    const plyFile = new Uint8Array(sourcePly);
    await assert.rejects(arps.transformFile(plyFile, "source.ply", res.T_target_source, { transfer: true }), /request options \(transfer, signal\) come fifth/);
    const movedFile = await arps.transformFile(plyFile, "source.ply", res.T_target_source, null, { transfer: true });
    assert.equal(plyFile.length, 0, "the file's bytes transferred");
    assert.ok(movedFile instanceof Uint8Array && movedFile.length > 100);
    const las = readFileSync(path.join(root, "fixtures", "formats", "simple.las"));
    const movedLas = await arps.transformFile(las, "simple.las", res.T_target_source);
    assert.ok(movedLas.length === las.length && new TextDecoder().decode(movedLas.subarray(0, 4)) === "LASF");
    await assert.rejects(arps.transformFile(las, "simple.las", [1, 2]), /matrix has 2 elements/);
    await assert.rejects(arps.transformFile(new Uint8Array(8), "drawing.dxf", res.T_target_source), /cannot tell the format/);
    const two = readFileSync(path.join(root, "fixtures", "formats", "velodyne_two_scans.e57"));
    assert.deepEqual((await arps.listScans(two, "two.e57")).map((s) => s.name), ["scan 1", "scan 2"]);
    // read options pass through: one scan saved alone
    const second = await arps.transformFile(two, "two.e57", res.T_target_source, { scan: 1 });
    assert.deepEqual((await arps.listScans(second, "second.e57")).map((s) => s.name), ["scan 2"]);
    // Clouds with an origin transfer their points too; zero origins give the same answer.
    const so = { points: source(), origin: [0, 0, 0] };
    const to = { points: target(), origin: [0, 0, 0] };
    const res3 = await arps.register(so, to, {}, { transfer: true });
    assert.equal(so.points.length, 0, "a { points, origin } source's points transferred");
    assert.equal(to.points.length, 0, "a { points, origin } target's points transferred");
    assert.deepEqual(res3.T_target_source, res.T_target_source);
    // The inputs are taken during the call: an array refilled once it returns changes nothing.
    const scratch = target();
    const pending = arps.register(source(), scratch);
    scratch.fill(0);
    assert.deepEqual((await pending).T_target_source, res.T_target_source);
    // The kept target given back: the next registration prepares it afresh, the same answer.
    assert.equal(await arps.forgetTarget(), undefined);
    assert.deepEqual((await arps.register(source(), target())).T_target_source, res.T_target_source);

    // Concurrent requests resolve to their own results.
    const [a, b] = await Promise.all([
      arps.register(source(), target(), { icp: "off" }),
      arps.register(source(), target(), { icp: "point" }),
    ]);
    assert.equal(a.icpIterations, 0);
    assert.ok(b.icpIterations > 0);

    const points = await arps.parsePointCloud(sourcePly, "source.ply");
    assert.deepEqual([...points], [...source()]);
    // Read options pass through the worker: a mesh's surface sampled there.
    const stl = readFileSync(path.join(root, "fixtures", "formats", "angle_block_binary_solid.stl"));
    const surface = await arps.parsePointCloud(stl, "block.stl", { surfacePoints: 1000 }, { transfer: false });
    assert.equal(surface.length, 3000);
    const cloud = await arps.readPointCloud(stl, "block.stl", { surfacePoints: 1000 });
    assert.deepEqual([...cloud.points], [...surface], "no origin needed near zero: the same points");
    await assert.rejects(arps.parsePointCloud(stl, "block.stl", { surfacePoints: 3 }), /surfacePoints = 3 is fewer than 16/);
    await assert.rejects(arps.parsePointCloud(stl, "block.stl", { transfer: true }), /request options \(transfer, signal\) come fourth/);
  } finally {
    arps.terminate();
  }
});

test("worker: custom weights that do not load reject createWorkerRegistrar", async () => {
  await assert.rejects(
    createWorkerRegistrar({ worker: nodeWorker(), wasm, model, weights: new Uint8Array([1, 2, 3]) }),
    /^Error: weights: /,
  );
});

test("worker: requests after terminate reject", async () => {
  const arps = await createWorkerRegistrar({ worker: nodeWorker(), wasm, model });
  arps.terminate();
  await assert.rejects(arps.register(source(), target()), /terminated/);
});

test("worker: a request that cannot be sent rejects alone, and the client keeps working", async () => {
  const arps = await createWorkerRegistrar({ createWorker: nodeWorker, wasm, model });
  try {
    await assert.rejects(arps.register(source(), target(), { onProgress: () => {} }), (e) => e.name === "DataCloneError" && /cannot be sent/.test(e.message));
    await assert.rejects(arps.register(source(), target(), { seed: () => 1 }), /DataCloneError/);
    const res = await arps.register(source(), target());
    assert.ok(errors(res.T_target_source).rot < 1);
    // Hostile input is rejected by the engine's boundary checks, in the worker, with its message.
    await assert.rejects(arps.register({ length: 1.2e9 }, target()), /^Error: source: expected a Float32Array/);
    await assert.rejects(arps.parsePointCloud(sourcePly, 5), /^Error: fileName: expected a string/);
    await assert.rejects(arps.register(source(), target(), { initialTransform: new Array(15).fill(0) }), /initialTransform has 15 elements/);
    assert.ok(errors((await arps.register(source(), target())).T_target_source).rot < 1);
  } finally {
    arps.terminate();
  }
});

test("worker: after the worker crashes, in-flight requests reject and the next request starts a new worker", async () => {
  const workers = [];
  const arps = await createWorkerRegistrar({ createWorker: () => workers[workers.push(nodeWorker()) - 1], wasm, model });
  try {
    workers[0].crash(); // processed before the request below
    const inFlight = arps.register(source(), target());
    await assert.rejects(inFlight, /^Error: arps worker: /);
    assert.equal(workers.length, 1, "nothing retried behind the caller's back");
    const stages = [];
    const res = await arps.register(source(), target(), {}, { onProgress: (s) => stages.push(s) });
    assert.equal(workers.length, 2, "a new worker");
    assert.equal(stages[0], "loading", "the new worker loads the engine");
    assert.ok(errors(res.T_target_source).rot < 1);
  } finally {
    arps.terminate();
  }
});

test("worker: abort mid-refinement rejects within 300 ms with an AbortError, then the client works", async () => {
  const arps = await createWorkerRegistrar({ createWorker: nodeWorker, wasm, model });
  try {
    const s = upsampled(source(), 20);
    const t = upsampled(target(), 20);
    const controller = new AbortController();
    let abortedAt = 0;
    const started = performance.now();
    const call = arps.register(s, t, { voxelSize: 0 }, {
      signal: controller.signal,
      onProgress: (stage) => {
        if (stage === "refining") {
          abortedAt = performance.now();
          controller.abort();
        }
      },
    });
    const e = await call.then(() => null, (err) => err);
    const latency = performance.now() - abortedAt;
    assert.ok(abortedAt > 0, "the refining stage was reported");
    assert.ok(e instanceof DOMException && e.name === "AbortError", `rejected with ${e}`);
    assert.ok(latency < 300, `rejected ${latency.toFixed(1)} ms after abort()`);
    console.log(`abort: refining began ${(abortedAt - started).toFixed(0)} ms in; rejected ${latency.toFixed(1)} ms after abort()`);
    // An already-aborted signal rejects at once, without starting anything.
    await assert.rejects(arps.register(source(), target(), {}, { signal: AbortSignal.abort() }), { name: "AbortError" });
    // the signal's own reason, as fetch rejects: a timeout's TimeoutError, a reason given
    const mine = new Error("superseded by a newer frame");
    await assert.rejects(arps.register(source(), target(), {}, { signal: AbortSignal.abort(mine) }), (e) => e === mine);
    const timeout = AbortSignal.timeout(0);
    await new Promise((r) => setTimeout(r, 20));
    await assert.rejects(arps.register(source(), target(), {}, { signal: timeout }), { name: "TimeoutError" });
    // Aborted while the replacement worker is still loading the engine: rejects at once too.
    const c2 = new AbortController();
    let loadingAbortAt = 0;
    const duringLoad = arps.register(source(), target(), {}, {
      signal: c2.signal,
      onProgress: (stage) => {
        if (stage === "loading") {
          loadingAbortAt = performance.now();
          c2.abort();
        }
      },
    });
    await assert.rejects(duringLoad, { name: "AbortError" });
    assert.ok(loadingAbortAt > 0 && performance.now() - loadingAbortAt < 300, "rejected promptly while loading");
    const res = await arps.register(source(), target());
    assert.ok(errors(res.T_target_source).rot < 1, "the client works after the abort");
    // The uninterrupted large pair, for comparison: it takes longer than the abort did.
    const t0 = performance.now();
    await arps.register(s, t, { voxelSize: 0 });
    console.log(`abort: the same pair uninterrupted takes ${(performance.now() - t0).toFixed(0)} ms`);
  } finally {
    arps.terminate();
  }
});

test("worker: a request aborted while it waits behind another is dropped alone; the running one completes", async () => {
  const arps = await createWorkerRegistrar({ createWorker: nodeWorker, wasm, model });
  const before = nodeWorker.started;
  try {
    // one tab's long request runs; another tab's waits behind it and is cancelled
    const s = upsampled(source(), 20);
    const t = upsampled(target(), 20);
    let refining = false;
    const long = arps.register(s, t, { voxelSize: 0 }, { onProgress: (stage) => (refining ||= stage === "refining") });
    const controller = new AbortController();
    const stages = [];
    const waiting = arps.register(source(), target(), {}, { signal: controller.signal, onProgress: (stage) => stages.push(stage) });
    const third = arps.register(source(), target());
    while (!refining) await new Promise((r) => setTimeout(r, 5));
    controller.abort();
    await assert.rejects(waiting, { name: "AbortError" });
    assert.deepEqual(stages, [], "the waiting request never started");
    assert.ok(errors((await long).T_target_source).rot < 1, "the running request completes");
    assert.ok(errors((await third).T_target_source).rot < 1, "the request behind the aborted one runs");
    assert.equal(nodeWorker.started, before, "the worker was kept");
    // A running request aborted: the worker stops, and a request waiting behind it goes to the next.
    const c2 = new AbortController();
    let refining2 = false;
    const running = arps.register(s, t, { voxelSize: 0 }, { signal: c2.signal, onProgress: (stage) => (refining2 ||= stage === "refining") });
    const behind = arps.register(source(), target());
    while (!refining2) await new Promise((r) => setTimeout(r, 5));
    c2.abort();
    await assert.rejects(running, { name: "AbortError" });
    assert.ok(errors((await behind).T_target_source).rot < 1, "the waiting request ran on a new worker");
    assert.equal(nodeWorker.started, before + 1);
    // a cloud on a SharedArrayBuffer is shared, not transferred, when `transfer` is asked
    const shared = new Float32Array(new SharedArrayBuffer(source().byteLength));
    shared.set(source());
    assert.ok(errors((await arps.register(shared, target(), {}, { transfer: true })).T_target_source).rot < 1);
  } finally {
    arps.terminate();
  }
});

test("worker: after a trap reported by the worker, the client replaces it and retries nothing", async () => {
  // Stand-in workers speaking worker.js's protocol: the first reports a trap (as worker.js does
  // with the facade's ARPS_TRAPPED error), the next ones answer normally.
  const started = [];
  const fakeWorker = () => {
    const listeners = [];
    const index = started.length;
    const w = {
      terminated: false,
      requests: [],
      postMessage(m) {
        w.requests.push(m.type);
        const reply = (data) => queueMicrotask(() => listeners.forEach((fn) => fn({ data })));
        if (m.type === "init") reply({ id: m.id, type: "ready", provenance: {}, modelConfig: { preset: "web" } });
        else if (index === 0) reply({ id: m.id, type: "error", name: "Error", code: "ARPS_TRAPPED", message: "arps: register trapped in the engine (RuntimeError: unreachable)" });
        else reply({ id: m.id, type: "result", result: { T_target_source: new Array(16).fill(0) } });
      },
      addEventListener(type, fn) {
        if (type === "message") listeners.push(fn);
      },
      terminate() {
        w.terminated = true;
      },
    };
    started.push(w);
    return w;
  };
  const arps = await createWorkerRegistrar({ createWorker: fakeWorker });
  await assert.rejects(arps.register(source(), target()), (e) => e.code === "ARPS_TRAPPED" && /trapped/.test(e.message));
  assert.ok(started[0].terminated, "the trapped worker is stopped");
  assert.deepEqual(started[0].requests, ["init", "register"], "nothing retried");
  const res = await arps.register(source(), target());
  assert.equal(res.T_target_source.length, 16);
  assert.equal(started.length, 2, "a new worker served the next request");
  assert.deepEqual(started[1].requests, ["init", "register"]);
  arps.terminate();
});

test("worker: the default worker under Node (worker_threads, .wasm read from disk) registers a pair", async () => {
  assert.equal(typeof globalThis.Worker, "undefined", "this test is about Node without a DOM Worker");
  const arps = await createWorkerRegistrar(); // no worker, createWorker or wasm given
  try {
    assert.equal(arps.modelConfig.preset, "web");
    const res = await arps.register(source(), target());
    const { rot, tr } = errors(res.T_target_source);
    assert.ok(rot < 1 && tr < 0.02, `rotation ${rot} deg, translation ${tr}`);
    const parsed = await arps.parsePointCloud(sourcePly, "source.ply");
    assert.ok(parsed instanceof Float32Array && parsed.length > 0 && parsed.length % 3 === 0);
    await assert.rejects(arps.register(new Float32Array(5), target()), /packed xyz buffer has length 5/);
    assert.ok(errors((await arps.register(source(), target())).T_target_source).rot < 1);
  } finally {
    arps.terminate();
  }
});

test("worker: under Node, model and weights given as paths or file: URLs are read from disk", async () => {
  const file = path.join(root, "models", "web.safetensors");
  for (const options of [{ weights: file }, { model: file }, { model: pathToFileURL(file).href }, { model: pathToFileURL(file) }]) {
    const arps = await createWorkerRegistrar(options);
    try {
      assert.equal(arps.modelConfig.preset, "web", JSON.stringify(options));
      assert.ok(errors((await arps.register(source(), target())).T_target_source).rot < 1);
    } finally {
      arps.terminate();
    }
  }
  await assert.rejects(createWorkerRegistrar({ weights: path.join(root, "no-such.safetensors") }), /reading weights .*no-such\.safetensors failed/);
});

test("worker: under Node, a script that never calls terminate() exits once its answers are in", async () => {
  const { execFile } = await import("node:child_process");
  const script = `
    const { createWorkerRegistrar } = await import(${JSON.stringify(pathToFileURL(path.join(pkg, "worker-client.js")).href)});
    const arps = await createWorkerRegistrar();
    const pts = new Float32Array(3 * 400).map((_, i) => Math.sin(i * 12.9898) * 0.5);
    const r = await arps.register(pts, pts);
    console.log("done " + r.T_target_source.length);
  `;
  const { mkdtempSync, rmSync, writeFileSync } = await import("node:fs");
  const { tmpdir } = await import("node:os");
  const dir = mkdtempSync(path.join(tmpdir(), "arps-exit-"));
  const file = path.join(dir, "never-terminates.mjs");
  writeFileSync(file, script);
  try {
    const { stdout } = await new Promise((resolve, reject) => {
      execFile(process.execPath, [file], { timeout: 60_000 }, (e, stdout, stderr) =>
        e ? reject(new Error(`${e.message} (killed: ${e.killed}) ${stderr}`)) : resolve({ stdout }),
      );
    });
    assert.match(stdout, /done 16/);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test("worker: options inherited from a prototype, or a Map, are refused, as by the engine's own API", async () => {
  const arps = await createWorkerRegistrar();
  try {
    await assert.rejects(arps.register(source(), target(), Object.create({ icp: "point" })), /^Error: invalid options: `icp` is inherited from a prototype/);
    await assert.rejects(arps.readPointCloud(sourcePly, "s.ply", Object.create({ surfacePoints: 100 })), /`surfacePoints` is inherited/);
    await assert.rejects(arps.register(source(), target(), new Map([["icp", "point"]])), /expected a plain object \(or undefined\), got a Map/);
    assert.equal((await arps.register(source(), target(), { icp: "point" })).T_target_source.length, 16);
  } finally {
    arps.terminate();
  }
});
