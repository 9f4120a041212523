// The built npm package (pkg/) from plain JavaScript: both builds, the package.json exports,
// the result object's types, thrown Errors, and the instance surviving them.
// Run after scripts/build-pkg.sh: node --test js/test/
import test from "node:test";
import assert from "node:assert/strict";
import { readFileSync, mkdtempSync, mkdirSync, symlinkSync, writeFileSync, rmSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { createRequire } from "node:module";
import os from "node:os";
import path from "node:path";
import { pathToFileURL } from "node:url";
import { pkg, root, source, target, sourcePly, errors } from "./common.mjs";

const nodeBuild = await import(pathToFileURL(path.join(pkg, "node", "index.mjs")).href);
const webBuild = await import(pathToFileURL(path.join(pkg, "arps.js")).href);
const modelFile = path.join(pkg, "models", "arps-web.safetensors");
webBuild.initSync({ module: readFileSync(path.join(pkg, "arps_bg.wasm")), model: readFileSync(modelFile) });

for (const [name, arps] of [["node build", nodeBuild], ["web build", webBuild]]) {
  test(`${name}: API surface`, async () => {
    assert.equal(typeof arps.default, "function", "default export init()");
    await arps.default(name === "web build" ? { module_or_path: readFileSync(path.join(pkg, "arps_bg.wasm")), model: readFileSync(modelFile) } : undefined);
    assert.equal(arps.version(), JSON.parse(readFileSync(path.join(pkg, "package.json"), "utf8")).version);
    const r = arps.Registrar.withDefaultModel();
    assert.equal(typeof r.provenance, "object");
    assert.equal(r.modelConfig.preset, "web");
    assert.ok(Number.isInteger(r.modelConfig.nPoints) && r.modelConfig.nPoints >= 16, "camelCase nPoints");
    assert.equal(r.modelConfig.n_points, undefined);
    r.free();
  });

  test(`${name}: errors are thrown Errors with the engine's message`, () => {
    const r = arps.Registrar.withDefaultModel();
    const s = source();
    const t = target();
    // A thrown Error with the message, never a wasm trap (a panic that reached JS).
    const throws = (fn, re) =>
      assert.throws(fn, (e) => e instanceof Error && !(e instanceof WebAssembly.RuntimeError) && re.test(e.message));
    throws(() => r.register(s.subarray(1), t), /source: invalid point cloud: packed xyz buffer has length/);
    const nan = s.slice();
    nan[5] = NaN;
    throws(() => r.register(nan, t), /source point 1 has a non-finite coordinate/);
    throws(() => r.register(s.subarray(0, 30), t), /source has 10 finite points/);
    throws(() => r.register(s, t, { icpMaxIteration: 3 }), /unknown field `icpMaxIteration`/);
    // an own `__proto__` key (options parsed from JSON) is a key like any other, refused
    throws(() => r.register(s, t, JSON.parse('{"__proto__": {"icp": "off"}, "starts": ["network"]}')), /unknown field `__proto__`/);
    throws(() => r.register(s, t, { icp: "planar" }), /invalid options/);
    throws(() => r.register(s, t, { networkPoints: 1 }), /networkPoints = 1/);
    throws(() => r.register(s, t, { starts: [] }), /starts is empty/);
    throws(() => r.register(s, t, { search: "thorough" }), /invalid options: .*thorough.*adaptive.*exhaustive/);
    throws(() => arps.Registrar.fromBytes(new Uint8Array([1, 2, 3])), /^weights: /);
    throws(() => arps.parsePointCloud(new Uint8Array([0, 1, 2, 3]), "x.unknownext"), /./);
    throws(() => r.register(s, t, { sourceOverlap: 0 }), /sourceOverlap = 0 must be a number in \(0, 1\]/);
    // what onProgress throws is the error's cause, itself (an AbortError stays one)
    const stop = new DOMException("stop", "AbortError");
    assert.throws(() => r.register(s, t, {}, () => { throw stop; }), (e) => /^onProgress threw: stop/.test(e.message) && e.cause === stop);
    r.free();
  });

  test(`${name}: registers the fixture pair, before and after errors`, () => {
    const r = arps.Registrar.withDefaultModel();
    const check = (res) => {
      assert.ok(Array.isArray(res.T_target_source) && res.T_target_source.length === 16);
      assert.ok(Array.isArray(res.T_target_source_network) && res.T_target_source_network.length === 16);
      for (const k of ["fitness", "inlierRmse", "icpIterations", "maxCorrespondenceDistance"]) assert.equal(typeof res[k], "number", k);
      assert.equal(typeof res.icpConverged, "boolean");
      assert.ok(["network", "centroids", "initial", "turned", "turnedInitial", "global", "globalNetwork", "rotations", "rotationsNetwork"].includes(res.start), `start ${res.start}`);
      for (const k of ["preprocessMs", "networkMs", "gmrMs", "icpMs", "globalMs", "totalMs"]) assert.equal(typeof res.timings[k], "number", k);
      assert.ok(res.confidence >= 0.8 && res.confidence <= 1, `confidence ${res.confidence} on the known pair`);
      assert.ok(!res.warnings.some((w) => w.startsWith("low confidence")), String(res.warnings));
      assert.deepEqual(Object.keys(res.evidence).sort(), ["alternatives", "ambiguity", "constraint", "fitness", "fitnessCoarse", "fitnessLoose", "fitnessTight", "overlapReverse", "rmseRatio", "slide"]);
      assert.ok(Number.isInteger(res.startsRefined) && res.startsRefined >= 1, `startsRefined ${res.startsRefined}`);
      assert.ok(res.timings.totalMs > 0);
      assert.ok(Array.isArray(res.warnings));
      const { rot, tr } = errors(res.T_target_source);
      assert.ok(rot < 1 && tr < 0.02, `rotation ${rot} deg, translation ${tr}`);
      structuredClone(res); // plain data: postMessage-able
      assert.deepEqual(JSON.parse(JSON.stringify(res)), res, "JSON round trip (the CLI prints the same object)");
    };
    check(r.register(source(), target()));
    assert.throws(() => r.register(source(), target(), { bogus: 1 }));
    assert.throws(() => r.register(new Float32Array(7), target()));
    check(r.register(source(), target(), {}));
    const exhaustive = r.register(source(), target(), { search: "exhaustive" });
    check(exhaustive);
    assert.ok(exhaustive.startsRefined > r.register(source(), target()).startsRefined, "exhaustive refines more starts");
    // A previous result's matrix as the initial guess (column-major, as three.js holds it).
    const first = r.register(source(), target());
    check(r.register(source(), target(), { initialTransform: first.T_target_source }));
    // The readers' output registers as is.
    check(r.register(arps.parsePointCloud(sourcePly, "source.ply"), target()));
    // The target kept from the call before, or forgotten: the same answer without the timings.
    const untimed = ({ timings, ...rest }) => rest;
    const kept = untimed(r.register(source(), target()));
    r.forgetTarget();
    assert.deepEqual(untimed(r.register(source(), target())), kept);
    r.free();
    assert.throws(() => r.forgetTarget(), /freed/);
  });

  test(`${name}: a mesh file read as its sampled surface (ReadOptions)`, () => {
    const stl = readFileSync(path.join(root, "fixtures", "formats", "angle_block_binary_solid.stl"));
    // The vertices by default; with surfacePoints, that many points over the surface, the same
    // for the same seed, others for another; a point file is read as it is.
    assert.equal(arps.parsePointCloud(stl, "block.stl").length, 398 * 3);
    const surface = arps.parsePointCloud(stl, "block.stl", { surfacePoints: 5000 });
    assert.equal(surface.length, 5000 * 3);
    assert.deepEqual([...arps.parsePointCloud(stl, "block.stl", { surfacePoints: 5000 })], [...surface]);
    assert.notDeepEqual([...arps.parsePointCloud(stl, "block.stl", { surfacePoints: 5000, seed: 1 })], [...surface]);
    const read = arps.readPointCloud(stl, "block.stl", { surfacePoints: 2000 });
    assert.equal(read.points.length, 2000 * 3);
    assert.deepEqual([...arps.parsePointCloud(sourcePly, "source.ply", { surfacePoints: 5000 })], [...source()]);
    assert.throws(() => arps.parsePointCloud(stl, "block.stl", { surfacePoint: 5000 }), /invalid read options: unknown field `surfacePoint`/);
    assert.throws(() => arps.parsePointCloud(stl, "block.stl", JSON.parse('{"__proto__": {"surfacePoints": 5000}}')), /invalid read options: unknown field `__proto__`/);
    assert.throws(() => arps.parsePointCloud(stl, "block.stl", { surfacePoints: 3 }), /surfacePoints = 3 is fewer than 16/);
    assert.throws(() => arps.parsePointCloud(stl, "block.stl", { surfacePoints: 2e7 }), /more than the 16000000/);
    assert.throws(() => arps.parsePointCloud(stl, "block.stl", { surfacePoints: "many" }), /invalid read options/);
  });
}

test("package.json exports resolve for import and require under Node", () => {
  const dir = mkdtempSync(path.join(os.tmpdir(), "arps-exports-"));
  try {
    mkdirSync(path.join(dir, "node_modules"));
    symlinkSync(pkg, path.join(dir, "node_modules", "arps"), "dir");
    writeFileSync(
      path.join(dir, "esm.mjs"),
      `import init, { Registrar, version } from "arps";
       import { createWorkerRegistrar, STAGES } from "arps/worker-client";
       await init();
       const r = Registrar.withDefaultModel();
       console.log(JSON.stringify({ v: version(), preset: r.modelConfig.preset, w: typeof createWorkerRegistrar, s: STAGES.length }));`,
    );
    writeFileSync(
      path.join(dir, "cjs.cjs"),
      `const { Registrar, version } = require("arps");
       console.log(JSON.stringify({ v: version(), preset: Registrar.withDefaultModel().modelConfig.preset }));`,
    );
    const esm = JSON.parse(execFileSync(process.execPath, ["esm.mjs"], { cwd: dir, encoding: "utf8" }));
    assert.deepEqual(esm, { v: nodeBuild.version(), preset: "web", w: "function", s: 5 });
    const cjs = JSON.parse(execFileSync(process.execPath, ["cjs.cjs"], { cwd: dir, encoding: "utf8" }));
    assert.deepEqual(cjs, { v: nodeBuild.version(), preset: "web" });
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test("the Node build imports without its .wasm beside it (a server bundle), and says so when called", () => {
  // what a bundler that copies the JavaScript into a server bundle leaves: node/ without ../arps_bg.wasm
  const dir = mkdtempSync(path.join(os.tmpdir(), "arps-ssr-"));
  try {
    mkdirSync(path.join(dir, "node"));
    for (const f of ["arps.js", "arps_glue.js", "facade.cjs", "index.mjs", "package.json"]) {
      writeFileSync(path.join(dir, "node", f), readFileSync(path.join(pkg, "node", f)));
    }
    const run = (code) => JSON.parse(execFileSync(process.execPath, ["--input-type=module", "-e", code], { cwd: dir, encoding: "utf8" }));
    const out = run(`import * as arps from "./node/index.mjs";
      let error = "", model = "";
      try { arps.version(); } catch (e) { error = e.message; }
      try { arps.Registrar.withDefaultModel(); } catch (e) { model = e.message; }
      console.log(JSON.stringify({ registrar: typeof arps.Registrar, error, model }));`);
    assert.equal(out.registrar, "function", "imported without the .wasm");
    assert.match(out.error, /its WebAssembly file is not at .*arps_bg\.wasm.*serverExternalPackages/);
    assert.match(out.model, /serverExternalPackages/, "the default model, left behind too, says the same");
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

test("package files: what npm would publish, and nothing else", () => {
  const out = execFileSync("npm", ["pack", "--dry-run", "--json"], { cwd: pkg, encoding: "utf8" });
  const files = JSON.parse(out)[0].files.map((f) => f.path).sort();
  for (const f of ["arps.js", "arps.d.ts", "arps_bg.wasm", "worker.js", "worker-client.js", "worker-client.d.ts", "node/arps.js", "node/index.mjs", "models/arps-web.safetensors", "package.json"]) {
    assert.ok(files.includes(f), `${f} is published`);
  }
  for (const f of files) {
    if (f === "models/arps-web.safetensors") continue; // the default model, the one data file
    assert.ok(!/\.(ply|pcd|xyz|obj|off|stl|safetensors|bin|npz|h5)$/i.test(f), `${f}: no data files in the package`);
  }
  // The engine once: the Node build loads the web build's .wasm.
  assert.deepEqual(files.filter((f) => f.endsWith(".wasm")), ["arps_bg.wasm"]);
});
