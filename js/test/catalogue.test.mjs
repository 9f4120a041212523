// The catalogue of hostile input, through the built package (pkg/): every case asserts the error
// (or the correct answer) AND that the same Registrar then registers the fixture pair correctly.
// Cases: bad lengths, NaN, too few / too many points, wrong types, array-likes that lie about
// their length, bad options (unknown, wrong type, throwing getters, Proxies, bad
// initialTransform), bad onProgress, bad files (corrupt LAZ and E57 too) and file names, bad
// matrices and clouds for transformPointCloud / writePly / transformFile, bad
// weights, use after
// free, and
// a real trap inside the engine, after which the module is re-instantiated and the registrars
// built before it keep working.
// Run after scripts/build-pkg.sh: node --test js/test/
import test from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";
import { pathToFileURL } from "node:url";
import { pkg, root, source, target, sourcePly, targetPly, errors, groundTruth } from "./common.mjs";

const nodeBuild = await import(pathToFileURL(path.join(pkg, "node", "index.mjs")).href);
const webBuild = await import(pathToFileURL(path.join(pkg, "arps.js")).href);
const { MAX_POINTS, makeApi } = await import(pathToFileURL(path.join(pkg, "facade.js")).href);

/** The registrar still recovers the fixture transform. */
function stillWorks(r, label) {
  const res = r.register(source(), target());
  const { rot, tr } = errors(res.T_target_source);
  assert.ok(rot < 1 && tr < 0.02, `${label}: afterwards rotation ${rot} deg, translation ${tr}`);
}

/** `fn` throws a plain Error (not a trap) whose message matches `re`; then `r` still works. */
function rejects(r, label, fn, re) {
  let thrown;
  try {
    fn();
  } catch (e) {
    thrown = e;
  }
  assert.ok(thrown !== undefined, `${label}: expected an error`);
  assert.ok(thrown instanceof Error && !(thrown instanceof WebAssembly.RuntimeError), `${label}: ${thrown}`);
  assert.match(thrown.message, re, label);
  stillWorks(r, label);
}

const lyingLength = () => {
  class Liar extends Float32Array {
    get length() {
      return 3;
    }
  }
  const s = source();
  const l = new Liar(s.length);
  l.set(s);
  return l;
};

for (const [name, arps] of [["node build", nodeBuild], ["web build", webBuild]]) {
  if (name === "web build") webBuild.initSync({ module: readFileSync(path.join(pkg, "arps_bg.wasm")), model: readFileSync(path.join(pkg, "models", "arps-web.safetensors")) });

  test(`${name}: hostile clouds`, () => {
    const r = arps.Registrar.withDefaultModel();
    const s = source();
    const t = target();
    const nan = s.slice();
    nan[5] = NaN;
    const cases = [
      ["length not a multiple of 3", () => r.register(s.subarray(1), t), /^source: invalid point cloud: packed xyz buffer has length/],
      ["target length", () => r.register(s, t.subarray(2)), /^target: invalid point cloud/],
      ["NaN", () => r.register(nan, t), /source point 1 has a non-finite coordinate/],
      ["Infinity", () => r.register(s, Float32Array.of(...t.subarray(0, 60), Infinity)), /./],
      ["too few points", () => r.register(s.subarray(0, 30), t), /source has 10 finite points/],
      ["empty", () => r.register(new Float32Array(0), t), /source has 0 finite points/],
      ["a number", () => r.register(5, t), /^source: expected a Float32Array \(or Float64Array\) of packed xyz .*got a number/],
      ["undefined", () => r.register(undefined, t), /^source: expected a Float32Array.*got undefined/],
      ["a string", () => r.register("1 2 3", t), /^source: expected a Float32Array/],
      ["an array-like claiming 1.2e9 elements", () => r.register({ length: 1.2e9 }, t), /^source: expected a Float32Array.*got an object/],
      ["a Proxy of a Float32Array", () => r.register(new Proxy(s, {}), t), /^source: expected a Float32Array.*got an object/],
      ["a cloud object whose points are a Float64Array", () => r.register({ points: Float64Array.from(s), origin: [0, 0, 0] }, t), /^source\.points: expected a Float32Array .*got a Float64Array/],
      ["an Int32Array", () => r.register(new Int32Array(s.length), t), /^source: expected a Float32Array.*got an Int32Array/],
      ["an Array with a string", () => r.register([...s.subarray(0, 59), "x"], t), /^source: element 59 is a string/],
      ["an Array with a throwing getter", () => {
        const a = [...s];
        Object.defineProperty(a, 4, { get() { throw new Error("boom"); } });
        return r.register(a, t);
      }, /^source: reading element 4 threw: Error: boom/],
      ["over the points limit", () => r.register(new Float32Array(3 * MAX_POINTS + 3), t), /^source has 16000001 points, more than the 16000000 a registration accepts per cloud .*downsample it first/],
      ["a detached buffer", () => {
        const gone = new Float32Array(s);
        structuredClone(gone.buffer, { transfer: [gone.buffer] });
        return r.register(gone, t);
      }, /^source: its buffer cannot be read .* detached/],
    ];
    for (const [label, fn, re] of cases) rejects(r, label, fn, re);
    // The array-like that leaked 482 MB per call and trapped on the 9th: rejected every time.
    for (let i = 0; i < 12; i++) assert.throws(() => r.register({ length: 1.2e9 }, t), /expected a Float32Array/);
    stillWorks(r, "after 12 array-likes");
    // The usual slips, each named with its fix: nested points, a three.js attribute, x, y, z, w
    // positions (every fourth number 1), a Uint8Array
    const nested = Array.from({ length: s.length / 3 }, (_, i) => [s[3 * i], s[3 * i + 1], s[3 * i + 2]]);
    assert.throws(() => r.register(nested, t), /^Error: source: element 0 is an Array, expected a number: a flat list x0, y0, z0, x1, \.\.\. \(a list of points: pass them flat, e\.g\. source\.flat\(\)/);
    assert.throws(() => r.register({ isBufferAttribute: true, array: s, itemSize: 3 }, t), /got an object \(a three\.js BufferAttribute: pass its \.array\)/);
    assert.throws(() => r.register({ isBufferGeometry: true }, t), /pass geometry\.attributes\.position\.array/);
    const xyzw = new Float32Array((s.length / 9) * 12);
    for (let i = 0; i < xyzw.length / 4; i++) xyzw.set([s[3 * i], s[3 * i + 1], s[3 * i + 2], 1], 4 * i);
    assert.throws(() => r.register(xyzw, t), /^Error: source: every fourth number is 1, as in x, y, z, w positions/);
    assert.throws(() => r.register(new Uint8Array(9), t), /got a Uint8Array/);
    stillWorks(r, "after the usual slips");
    // Accepted: a plain Array of numbers, a subclass that lies about its length (its real
    // contents are used), a view into a larger buffer, and a Float64Array.
    for (const [label, src] of [
      ["Array", Array.from(s)],
      ["lying subclass", lyingLength()],
      ["offset view", (() => { const big = new Float32Array(s.length + 7); big.set(s, 7); return big.subarray(7); })()],
      ["Float64Array", Float64Array.from(s)],
    ]) {
      const { rot, tr } = errors(r.register(src, t).T_target_source);
      assert.ok(rot < 1 && tr < 0.02, `${label}: rotation ${rot} deg, translation ${tr}`);
    }
    r.free();
  });

  test(`${name}: hostile options`, () => {
    const r = arps.Registrar.withDefaultModel();
    const s = source();
    const t = target();
    const reg = (o, p) => () => r.register(s, t, o, p);
    const proxy = (handler, obj = { icp: "point" }) => new Proxy(obj, handler);
    const cases = [
      ["unknown field", reg({ icpMaxIteration: 3 }), /unknown field `icpMaxIteration`/],
      ["wrong enum", reg({ icp: "planar" }), /^invalid options: `icp`: unknown variant `planar`, expected one of/],
      ["a number for a choice", reg({ icpLoss: 1 }), /^invalid options: `icpLoss`: invalid type: floating point `1.0`, expected `squared` or `robust`$/],
      ["a number in a list of choices", reg({ starts: ["network", 2] }), /^invalid options: `starts`: invalid type: floating point `2.0`, expected one of `network`, `centroids`/],
      ["wrong type", reg({ seed: "seven" }), /^invalid options: `seed`: invalid type: string "seven", expected a whole number, 0 or more$/],
      ["negative count", reg({ icpMaxIterations: -1 }), /^invalid options: `icpMaxIterations`: invalid value: -1, expected a whole number from 0 to 4294967295$/],
      ["a float of 301 digits", reg({ icpMaxIterations: 1e300 }), /^invalid options: `icpMaxIterations`: invalid type: floating point `1e300`, expected a whole number from 0 to 4294967295$/],
      ["count beyond 32 bits", reg({ networkPoints: 2 ** 32 }), /^invalid options: `networkPoints`: invalid value: integer `4294967296`, expected a whole number from 0 to 4294967295$/],
      ["a seed beyond 2^64", reg({ seed: 2n ** 70n }), /^invalid options: `seed`: invalid value: a bigint beyond 0\.\.=18446744073709551615 \(2\^64 - 1\)/],
      ["wrong type after a right one", reg({ icp: "point", icpMaxIterations: 1.5 }), /^invalid options: `icpMaxIterations`: invalid type: floating point `1.5`/],
      ["three rows", reg({ initialTransform: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]] }), /^invalid options: initialTransform has 3 rows; expected/],
      ["sixteen strings", reg({ initialTransform: new Array(16).fill("1") }), /^invalid options: initialTransform\[0\] is a string/],
      ["out of range", reg({ networkPoints: 1 }), /networkPoints = 1/],
      ["empty starts", reg({ starts: [] }), /starts is empty/],
      ["a number", reg(3), /^invalid options: expected a plain object \(or undefined\), got a number/],
      ["an array", reg([1, 2]), /^invalid options: expected a plain object.*got an Array/],
      ["a string", reg("fast"), /^invalid options: expected a plain object/],
      ["a Map", reg(new Map([["icp", "bogus"]])), /^invalid options: expected a plain object \(or undefined\), got a Map$/],
      ["a Date", reg(new Date(0)), /^invalid options: expected a plain object \(or undefined\), got a Date$/],
      ["an inherited option", reg(Object.create({ icp: "bogus" })), /^invalid options: `icp` is inherited from a prototype/],
      ["a throwing top-level getter", reg({ get seed() { throw new Error("boom"); } }), /^invalid options: reading `seed` threw: Error: boom/],
      ["a Proxy whose ownKeys throws", reg(proxy({ ownKeys() { throw new Error("no keys"); } })), /^invalid options: listing the options threw: Error: no keys/],
      ["a Proxy whose get throws", reg(proxy({ get() { throw new Error("no get"); } })), /^invalid options: reading `icp` threw: Error: no get/],
      ["a revoked Proxy", reg((() => { const p = Proxy.revocable({}, {}); p.revoke(); return p.proxy; })()), /^invalid options/],
      ["a throwing getter in starts", reg({ starts: Object.defineProperty(["network", "initial"], 1, { get() { throw new Error("nested"); } }) }), /^invalid options: reading `starts\[1\]` threw: Error: nested/],
      ["a Proxy as initialTransform", reg({ initialTransform: proxy({ get() { throw new Error("matrix"); } }, []) }), /^invalid options: reading `initialTransform.length` threw: Error: matrix/],
      ["15-element initialTransform", reg({ initialTransform: new Array(15).fill(0) }), /^invalid options: initialTransform has 15 elements; expected 16 numbers/],
      ["15-element Float32Array initialTransform", reg({ initialTransform: new Float32Array(15) }), /^invalid options: initialTransform has 15 elements/],
      ["a row with a string", reg({ initialTransform: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, "0"], [0, 0, 0, 1]] }), /^invalid options: initialTransform\[2\]\[3\] is a string/],
      ["non-rigid initialTransform", reg({ initialTransform: [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1] }), /initialTransform is not rigid/],
      ["a huge array", reg({ starts: { length: 1e9 } }), /^invalid options/],
      ["onProgress not a function", reg({}, 42), /^onProgress: expected a function, got a number/],
      ["onProgress throws", reg({}, () => { throw new Error("progress boom"); }), /^onProgress threw: progress boom/],
      ["onProgress re-enters register", reg({}, () => r.register(s, t)), /^onProgress threw: arps: register while this Registrar is registering/],
      ["onProgress frees the registrar", reg({}, () => r.free()), /^onProgress threw: arps: free\(\) while this Registrar is registering/],
    ];
    for (const [label, fn, re] of cases) rejects(r, label, fn, re);
    // A getter that works is read once, like any value.
    let reads = 0;
    const res = r.register(s, t, { get icp() { reads++; return "off"; } });
    assert.equal(res.icpIterations, 0);
    assert.equal(reads, 1);
    r.free();
  });

  test(`${name}: hostile files, weights, and use after free`, () => {
    const regression = (f) => readFileSync(path.join(root, "fuzz", "regressions", "read_point_cloud", f)).subarray(1);
    const laz = readFileSync(path.join(root, "fixtures", "formats", "1_4_w_evlr.laz"));
    const flipped = (b, at) => { const c = Uint8Array.from(b); c[at] ^= 0x55; return c; };
    const r = arps.Registrar.withDefaultModel();
    const parse = (b, n) => () => arps.parsePointCloud(b, n);
    const cases = [
      ["a number as file name", parse(sourcePly, 5), /^fileName: expected a string .*got a number/],
      ["an object as file name", parse(sourcePly, { toString: () => "a.ply" }), /^fileName: expected a string/],
      ["a huge file name", parse(sourcePly, "x".repeat(5000) + ".ply"), /^fileName: 5004 characters is over the limit/],
      ["a string as bytes", parse("ply\n", "a.ply"), /^bytes: expected a Uint8Array or an ArrayBuffer, got a string/],
      ["an array-like as bytes", parse({ length: 1.2e9 }, "a.ply"), /^bytes: expected a Uint8Array or an ArrayBuffer, got an object/],
      ["truncated PLY", parse(sourcePly.subarray(0, 300), "a.ply"), /./],
      ["empty file", parse(new Uint8Array(0), "a.ply"), /./],
      ["garbage with an unknown extension", parse(new Uint8Array([0, 1, 2, 3]), "x.unknownext"), /./],
      // corrupt LAZ found by fuzzing (the file after the fuzz input's first byte): errors, not traps
      ["LAZ whose GPS time switches without end", parse(regression("laz-gps-time-switches-without-end"), "a.laz"), /corrupt GPS time/],
      ["LAZ point-wise with chunks of variable size", parse(regression("laz-pointwise-variable-chunks"), "a.laz"), /vary in size/],
      ["LAZ cut in half", parse(laz.subarray(0, laz.length >> 1), "a.laz"), /LAS parse error/],
      ["E57 with a flipped byte", parse(flipped(readFileSync(path.join(root, "fixtures", "formats", "velodyne_two_scans.e57")), 3000), "a.e57"), /E57 parse error: .*checksum/i],
      ["weights: 3 bytes", () => arps.Registrar.fromBytes(new Uint8Array([1, 2, 3])), /^weights: /],
      ["weights: a string", () => arps.Registrar.fromBytes("model.safetensors"), /^weights: expected a Uint8Array or an ArrayBuffer, got a string/],
      ["new Registrar()", () => new arps.Registrar(), /^arps: use Registrar.withDefaultModel\(\), Registrar.fromBytes\(bytes\) or await Registrar.fromUrl/],
    ];
    for (const [label, fn, re] of cases) rejects(r, label, fn, re);
    // Accepted: an ArrayBuffer, a DataView, a Buffer; no file name (the format is sniffed).
    const expected = [...source()];
    const buf = sourcePly.buffer.slice(sourcePly.byteOffset, sourcePly.byteOffset + sourcePly.byteLength);
    assert.deepEqual([...arps.parsePointCloud(buf, "s.ply")], expected);
    assert.deepEqual([...arps.parsePointCloud(new DataView(buf), "s.ply")], expected);
    assert.deepEqual([...arps.parsePointCloud(sourcePly)], expected);
    // Use after free: a clear error, also for the getters; free twice is harmless.
    const gone = arps.Registrar.withDefaultModel();
    gone.free();
    gone.free();
    assert.throws(() => gone.register(source(), target()), /^Error: arps: register on a Registrar that was freed/);
    assert.throws(() => gone.provenance, /arps: provenance on a Registrar that was freed/);
    stillWorks(r, "after use after free");
    const parsed = r.register(arps.parsePointCloud(sourcePly, "s.ply"), arps.parsePointCloud(targetPly, "t.ply"));
    assert.ok(errors(parsed.T_target_source).rot < 1);
    r.free();
  });
}

test("sourceScale: a source in millimetres onto a target in metres; the answer maps the source as given", () => {
  const r = nodeBuild.Registrar.withDefaultModel();
  const mm = Float32Array.from(source(), (x) => x * 1000);
  // the 3x3 part divided by the factor is the rotation; the translation is the truth's
  const rigidOf = (m, f) => m.map((v, i) => (i < 12 && i % 4 < 3 ? v / f : v));
  const res = r.register(mm, target(), { sourceScale: 0.001 });
  const { rot, tr } = errors(rigidOf(res.T_target_source, 0.001));
  assert.ok(rot < 1 && tr < 0.02, `rotation ${rot} deg, translation ${tr}`);
  assert.ok(!res.warnings.some((w) => /differ in size/.test(w)), JSON.stringify(res.warnings));
  // three.js-style: the matrix places the millimetre points in the target's metres
  const truth = (p) => [0, 1, 2].map((k) => groundTruth[k][0] * p[0] + groundTruth[k][1] * p[1] + groundTruth[k][2] * p[2] + groundTruth[k][3]);
  const placed = nodeBuild.transformPointCloud(mm, res.T_target_source);
  const s = source();
  for (const i of [0, 300, 600]) {
    const want = truth([s[i], s[i + 1], s[i + 2]]);
    const got = [0, 1, 2].map((k) => placed.origin[k] + placed.points[i + k]);
    assert.ok(Math.hypot(...got.map((g, k) => g - want[k])) < 0.02, `point ${i / 3}: ${got} vs ${want}`);
  }
  // without the factor the sizes differ by 1000 and the engine says so
  assert.ok(r.register(mm, target()).warnings.some((w) => /differ in size by \d+x.*the option sourceScale does it/.test(w)));
  // a previous answer is a guess as it is; a rigid matrix is not one for a scaled source
  const again = r.register(mm, target(), { sourceScale: 0.001, initialTransform: res.T_target_source, starts: ["initial"], network: false });
  assert.ok(errors(rigidOf(again.T_target_source, 0.001)).rot < 1);
  assert.throws(
    () => r.register(mm, target(), { sourceScale: 0.001, initialTransform: rigidOf(res.T_target_source, 0.001) }),
    /initialTransform is not rigid once its 3x3 part is divided by sourceScale \(0\.001\)/,
  );
  for (const bad of [0, -1, Infinity]) assert.throws(() => r.register(mm, target(), { sourceScale: bad }), /sourceScale = .* must be a finite number > 0/);
  // far from zero too (the facade's origins): the same answer in the caller's frame
  const a = [512345.25, 4123456.5, 87.125];
  const farMm = Float64Array.from(mm, (x, i) => x + a[i % 3] * 1000);
  const far = r.register(farMm, target(), { sourceScale: 0.001 });
  const at = nodeBuild.transformPointCloud(Float64Array.from(mm.subarray(0, 3), (x, i) => x + a[i] * 1000), far.T_target_source);
  const want = truth([s[0], s[1], s[2]]);
  const got = [0, 1, 2].map((k) => at.origin[k] + at.points[k]);
  assert.ok(Math.hypot(...got.map((g, k) => g - want[k])) < 0.02, `far: ${got} vs ${want}`);
  r.free();
});

test("alternatives are in the caller's frame for clouds far from zero", () => {
  const r = nodeBuild.Registrar.withDefaultModel();
  // a box, 2 x 1 x 0.5: its half turns fit as well as the truth (deterministic samples)
  let state = 12345;
  const rand = () => ((state = (state * 1103515245 + 12345) % 2147483648) / 2147483648);
  const box = (n) => {
    const out = new Float64Array(n * 3);
    const half = [1, 0.5, 0.25];
    for (let i = 0; i < n; i++) {
      const axis = Math.floor(rand() * 3);
      const p = half.map((h) => (rand() * 2 - 1) * h);
      p[axis] = rand() < 0.5 ? -half[axis] : half[axis];
      out.set(p, i * 3);
    }
    return out;
  };
  const a = [512345.25, 4123456.5, 87.125];
  const b = [512349.75, 4123450.25, 91.0];
  const src = Float64Array.from(box(3000), (x, i) => x + a[i % 3]);
  const tgt = Float64Array.from(box(3000), (x, i) => x + b[i % 3]);
  const res = r.register(src, tgt);
  assert.ok(res.alternatives.length >= 1, `alternatives: ${res.alternatives.length}`);
  for (const m of [res.T_target_source, ...res.alternatives.map((alt) => alt.T_target_source)]) {
    // each pose puts the source's centre (a) on the target's (b)
    const c = [0, 1, 2].map((k) => m[k] * a[0] + m[4 + k] * a[1] + m[8 + k] * a[2] + m[12 + k] - b[k]);
    assert.ok(Math.hypot(...c) < 0.1, `the centre lands ${Math.hypot(...c)} from the target's`);
  }
  r.free();
});

test("clouds far from zero: the identity start and the warnings are in the caller's frame", () => {
  const r = nodeBuild.Registrar.withDefaultModel();
  // two overlapping survey strips already in one map frame, their origins 164 m apart
  const strip = (x0, y0, n) => {
    const out = new Float64Array(n * 3);
    for (let i = 0; i < n; i++) {
      const x = x0 + (i % 60) * 0.5;
      const y = y0 + Math.floor(i / 60) * 0.5;
      out.set([x, y, 12 + Math.sin(x * 0.3) * Math.cos(y * 0.2) * 2], i * 3);
    }
    return out;
  };
  const a = strip(450300, 5600200, 3600);
  const b = strip(450300, 5600120, 3600);
  const res = r.register(a, b, { network: false, starts: ["initial"], icp: "off" });
  // the identity of the caller's frame, not of the engine's local ones
  assert.deepEqual(res.T_target_source.map((v) => Math.abs(v) < 1e-9 ? 0 : v), [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
  // a pipe along x far from zero: the free motion's point is given in map coordinates
  const pipe = (n, phase) => {
    const out = new Float64Array(n * 3);
    for (let i = 0; i < n; i++) {
      const t = ((i * 0.618034 + phase) % 1) * 2 * Math.PI;
      out.set([450000 + (i / n) * 6, 5600000 + 0.3 * Math.cos(t), 20 + 0.3 * Math.sin(t)], i * 3);
    }
    return out;
  };
  const turned = r.register(pipe(3000, 0.1), pipe(3000, 0.35));
  // (a pipe leaves two motions free: the turn about its axis and the slide along it, both named)
  const free = turned.warnings.find((w) => w.startsWith("the fit leaves 2 motions free")) ?? turned.warnings.join("; ");
  assert.match(free, / and a slide along \(-?1, -?0(\.\d+)?, -?0(\.\d+)?\) keep the source/, free);
  // (its axis runs along x through y = 5600000, z = 20; written to a thousandth of a metre or so)
  assert.match(free, /along \(1, 0, 0\) through \(45000\d(\.\d+)?, 5600000(\.\d+)?, (19\.9\d*|20(\.0\d*)?)\)/, free);
  r.free();
});

test("large coordinates: Float64Array or { points, origin } in, T_target_source exact in the caller's frame", () => {
  const arps = nodeBuild;
  const r = arps.Registrar.withDefaultModel();
  // The fixture pair moved far from the origin (georeferenced-like), differently per cloud.
  const a = [512345.25, 4123456.5, 87.125];
  const b = [512349.75, 4123450.25, 91.0];
  const far = (cloud, o) => Float64Array.from(cloud, (x, i) => x + o[i % 3]);
  const s64 = far(source(), a);
  const t64 = far(target(), b);
  // Truth in the moved frames: T' = T(b) T T(-a).
  const rows = groundTruth.map((row) => row.slice());
  for (let i = 0; i < 3; i++) rows[i][3] = groundTruth[i][3] + b[i] - (groundTruth[i][0] * a[0] + groundTruth[i][1] * a[1] + groundTruth[i][2] * a[2]);
  // The translation error where the clouds are (at the source's centre, a): the error of the
  // transform's translation alone would scale a tiny rotation error by |a| (4e6).
  const errorAtClouds = (m) => {
    const { rot } = errors(m, rows);
    const d = [0, 1, 2].map((i) => m[i] * a[0] + m[4 + i] * a[1] + m[8 + i] * a[2] + m[12 + i] - (rows[i][0] * a[0] + rows[i][1] * a[1] + rows[i][2] * a[2] + rows[i][3]));
    return { rot, tr: Math.hypot(...d) };
  };
  const check = (res, label) => {
    assert.ok(Array.isArray(res.T_target_source) && res.T_target_source.length === 16, label);
    const { rot, tr } = errorAtClouds(res.T_target_source);
    assert.ok(rot < 1 && tr < 0.02, `${label}: rotation ${rot} deg, translation error at the clouds ${tr}`);
  };
  check(r.register(s64, t64), "Float64Array");
  // an Array of numbers holds doubles: read as a Float64Array is, its digits kept
  check(r.register(Array.from(s64), Array.from(t64)), "Array of numbers");
  // The same clouds as f32 offsets beside their origins.
  const rel = (c, o) => Float32Array.from(c, (x, i) => x - o[i % 3]);
  check(r.register({ points: rel(s64, a), origin: a }, { points: rel(t64, b), origin: b }), "{ points, origin }");
  check(r.register({ points: source(), origin: a }, t64), "mixed");
  // initialTransform is in the caller's frame too: the truth itself as the start stays put.
  const truthColMajor = [0, 1, 2, 3].flatMap((c) => [0, 1, 2, 3].map((row) => rows[row][c]));
  const fromTruth = r.register(s64, t64, { initialTransform: truthColMajor, starts: ["initial"], network: false });
  check(fromTruth, "initialTransform in the caller's frame");
  // Without origins, float32 cannot hold these coordinates (0.25-0.5 units apart near 4e6).
  const lossy = r.register(Float32Array.from(s64), Float32Array.from(t64));
  assert.ok(lossy.warnings.some((w) => /^the source's coordinates lie up to .* as f32 they are rounded to steps of about/.test(w)), JSON.stringify(lossy.warnings));
  // A stray point far from the rest (a survey's (0, 0, 0)) does not cost the others their digits.
  check(r.register(Float64Array.from([...s64, 0, 0, 0]), t64), "Float64Array with a stray (0, 0, 0)");
  // A cloud near zero placed far from it (a local scan onto a map grid) keeps its digits too.
  const local = source();
  const placed = arps.transformPointCloud(local, truthColMajor);
  let off = 0;
  for (let i = 0; i < local.length; i += 3) {
    for (let k = 0; k < 3; k++) {
      const want = rows[k][0] * local[i] + rows[k][1] * local[i + 1] + rows[k][2] * local[i + 2] + rows[k][3];
      off = Math.max(off, Math.abs(placed.origin[k] + placed.points[i + k] - want));
    }
  }
  assert.ok(off < 1e-5, `placed on the map grid to ${off}`);
  const at = (res) => errorAtClouds(res.T_target_source).tr.toExponential(2);
  console.log(`large coordinates, translation error at the clouds: as Float32Array ${at(lossy)}, as Float64Array ${at(r.register(s64, t64))}`);
  // A file with double coordinates, read keeping its precision: { points, origin } registers as is.
  const doublePly = (xyz) => {
    const header = `ply\nformat binary_little_endian 1.0\nelement vertex ${xyz.length / 3}\nproperty double x\nproperty double y\nproperty double z\nend_header\n`;
    const body = new Uint8Array(Float64Array.from(xyz).buffer);
    const out = new Uint8Array(header.length + body.length);
    out.set(new TextEncoder().encode(header));
    out.set(body, header.length);
    return out;
  };
  const read = arps.readPointCloud(doublePly(s64), "far.ply");
  assert.ok(read.points instanceof Float32Array && read.points.length === s64.length);
  assert.ok(Math.abs(read.origin[1] - a[1]) < 10, `origin near the points: ${read.origin}`);
  let worst = 0;
  for (let i = 0; i < s64.length; i++) worst = Math.max(worst, Math.abs(read.origin[i % 3] + read.points[i] - s64[i]));
  assert.ok(worst < 1e-6, `read back to ${worst}`);
  check(r.register(read, arps.readPointCloud(doublePly(t64), "far-target.ply")), "readPointCloud");
  // parsePointCloud gives float32 in the file's frame (rounded: 0.25-0.5 apart near 4e6).
  assert.ok(Math.abs(arps.parsePointCloud(doublePly(s64), "far.ply")[1] - s64[1]) < 0.5);
  // Bad origins.
  rejects(r, "origin of 2", () => r.register({ points: source(), origin: [1, 2] }, t64), /^source: origin must be 3 finite numbers/);
  rejects(r, "NaN origin", () => r.register(s64, { points: target(), origin: [0, NaN, 0] }), /^target: origin must be 3 finite numbers/);
  rejects(r, "points not f32", () => r.register({ points: [1, 2, 3], origin: a }, t64), /^source\.points: expected a Float32Array .*got an Array/);
  r.free();
});

for (const [name, arps] of [["node build", nodeBuild], ["web build", webBuild]]) {
  test(`${name}: transformPointCloud, writePly and transformFile save a registered source in the target's frame`, () => {
    const r = arps.Registrar.withDefaultModel();
    // A map-grid survey (LAS 1.4 LAZ, about 1.7e6 from zero) onto a copy of itself moved; the
    // copy comes from transformPointCloud itself, checked first against f64 arithmetic.
    const survey = arps.readPointCloud(readFileSync(path.join(root, "fixtures", "formats", "1_4_w_evlr.laz")), "survey.laz");
    const n = survey.points.length / 3;
    const abs = (c, i, k) => c.origin[k] + c.points[3 * i + k];
    const apply = (m, p) => [0, 1, 2].map((k) => m[k] * p[0] + m[4 + k] * p[1] + m[8 + k] * p[2] + m[12 + k]);
    const c = [0, 1, 2].map((k) => abs(survey, 0, k));
    const a = 0.2;
    // 0.2 rad about the vertical through the first point, then (4, -3, 0.5); column-major
    const truth = [Math.cos(a), Math.sin(a), 0, 0, -Math.sin(a), Math.cos(a), 0, 0, 0, 0, 1, 0];
    truth.push(...[0, 1, 2].map((k) => c[k] - (truth[k] * c[0] + truth[4 + k] * c[1] + truth[8 + k] * c[2]) + [4, -3, 0.5][k]), 1);
    const moved = arps.transformPointCloud(survey, truth);
    assert.ok(moved.points instanceof Float32Array && moved.points.length === survey.points.length);
    let worst = 0;
    for (let i = 0; i < n; i++) {
      const want = apply(truth, [0, 1, 2].map((k) => abs(survey, i, k)));
      for (let k = 0; k < 3; k++) worst = Math.max(worst, Math.abs(abs(moved, i, k) - want[k]));
    }
    assert.ok(worst < 1e-4, `transformPointCloud: ${worst} from f64 arithmetic`);
    // four row-major rows are the same matrix
    const rows = [0, 1, 2, 3].map((row) => [0, 1, 2, 3].map((col) => truth[col * 4 + row]));
    assert.deepEqual(arps.transformPointCloud(survey, rows), moved);

    // register, move the source by the answer, write it: the PLY is in doubles and holds the
    // answer applied in f64; read back, it lies on the target
    const res = r.register(survey, moved);
    const aligned = arps.transformPointCloud(survey, res.T_target_source);
    const ply = arps.writePly(aligned);
    assert.ok(ply instanceof Uint8Array);
    assert.match(new TextDecoder().decode(ply.subarray(0, 200)), /property double x\nproperty double y\nproperty double z\nend_header\n/);
    const back = arps.readPointCloud(ply, "aligned.ply");
    assert.equal(back.points.length, survey.points.length);
    worst = 0;
    let landed = 0;
    for (let i = 0; i < n; i++) {
      const want = apply(res.T_target_source, [0, 1, 2].map((k) => abs(survey, i, k)));
      for (let k = 0; k < 3; k++) worst = Math.max(worst, Math.abs(abs(back, i, k) - want[k]));
      landed = Math.max(landed, Math.hypot(...[0, 1, 2].map((k) => abs(back, i, k) - abs(moved, i, k))));
    }
    assert.ok(worst < 1e-4, `the written survey is ${worst} from the answer applied in f64`);
    // a strip of 1,000 points a few units apart: the answer lands every point within a unit or two
    assert.ok(landed < 3, `a written point is ${landed} from its place on the target`);
    // local clouds are written as floats; a Float64Array keeps its digits as doubles
    assert.match(new TextDecoder().decode(arps.writePly(source()).subarray(0, 120)), /property float x/);
    const far = Float64Array.from([1e6 + 0.125, 2e6, 3, 1e6, 2e6 + 0.0625, 4]);
    const farBack = arps.readPointCloud(arps.writePly(far), "far.ply");
    far.forEach((v, i) => assert.ok(Math.abs(farBack.origin[i % 3] + farBack.points[i] - v) < 1e-9, `coordinate ${i}`));

    // bad input: clear errors, and the registrar still works
    const T = res.T_target_source;
    rejects(r, "matrix of 15", () => arps.transformPointCloud(survey, T.slice(0, 15)), /^matrix has 15 elements; expected 16 numbers/);
    rejects(r, "no matrix", () => arps.transformPointCloud(survey), /^matrix is undefined/);
    rejects(r, "stretched", () => arps.transformPointCloud(survey, T.map((v, i) => (i < 3 ? 2 * v : v))), /^matrix is not rigid \(or uniformly scaled\): its linear part/);
    rejects(r, "NaN matrix", () => arps.transformPointCloud(survey, T.map((v, i) => (i === 13 ? NaN : v))), /^matrix is not rigid/);
    // a rigid matrix written with four decimals (a benchmark's ground truth, a text file) is used
    // as the rigid transform nearest it, here and as an initial guess
    const [cs, sn] = [Math.cos(0.5), Math.sin(0.5)];
    const turn = [cs, sn, 0, 0, -sn, cs, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1];
    const written = turn.map((v) => Math.round(v * 1e4) / 1e4);
    const small = source();
    const near = arps.transformPointCloud(small, written);
    const exact = arps.transformPointCloud(small, turn);
    let nearWorst = 0;
    for (let i = 0; i < small.length; i++) nearWorst = Math.max(nearWorst, Math.abs(near.origin[i % 3] + near.points[i] - exact.origin[i % 3] - exact.points[i]));
    assert.ok(nearWorst < 1e-3, `a matrix written with four decimals moves points ${nearWorst} from the exact one's`);
    assert.equal(r.register(small, small, { initialTransform: written, starts: ["initial"] }).T_target_source.length, 16);
    rejects(r, "row of 3", () => arps.transformPointCloud(survey, [[1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]), /^matrix row 0 has 3 elements/);
    rejects(r, "bad origin", () => arps.writePly({ points: source(), origin: [1, 2] }), /^cloud: origin must be 3 finite numbers/);
    rejects(r, "length 4", () => arps.writePly(new Float32Array(4)), /^cloud: .*not a multiple of 3/);
    rejects(r, "not a cloud", () => arps.transformPointCloud("points", T), /^cloud: expected a Float32Array/);

    // how far the points of `moved` (a file named `name`) are from those of `file` moved by T
    // through transformPointCloud (in f64, each beside its origin), beyond what a float32 field
    // holds at their magnitude when `float32` (a file of float coordinates near zero, moved onto
    // the map grid, holds them to a float32 step there; transformPointCloud keeps every digit)
    const apartFrom = (file, moved, name, float32 = false) => {
      const want = arps.transformPointCloud(arps.readPointCloud(file, name), T);
      const got = arps.readPointCloud(moved, name);
      let apart = 0;
      for (let i = 0; i < got.points.length; i++) {
        const w = want.origin[i % 3] + want.points[i];
        const step = float32 ? Math.abs(w) * 2 ** -23 : 0;
        apart = Math.max(apart, Math.abs(got.origin[i % 3] + got.points[i] - w) - step);
      }
      return apart;
    };
    // transformFile on a PLY: the file moved as it is (a fragment with normals, colours and faces):
    // on the map grid float would round its points, so x, y and z become double (12 more bytes a
    // vertex), the rest of the header as it was, its points those transformPointCloud gives, its
    // colours kept
    const frag = readFileSync(path.join(root, "fixtures", "formats", "frag_115_2000_binary.ply"));
    const movedPly = arps.transformFile(frag, "frag.ply", T);
    // ("float" to "double" three times in the header)
    assert.ok(movedPly instanceof Uint8Array && movedPly.length === frag.length + 12 * 2000 + 3, `${movedPly.length} bytes`);
    const body = frag.indexOf("end_header\n") + 11;
    const header = new TextDecoder().decode(frag.subarray(0, body)).replace(/property float ([xyz])\n/g, "property double $1\n");
    assert.equal(new TextDecoder().decode(movedPly.subarray(0, header.length)), header);
    let apart = apartFrom(frag, movedPly, "f.ply");
    assert.ok(apart < 1e-6, `transformFile's PLY points ${apart} from transformPointCloud's`);
    const at = header.length;
    for (const i of [0, 999, 1999]) assert.deepEqual(movedPly.subarray(at + i * 39 + 36, at + i * 39 + 39), new Uint8Array(frag.subarray(body + i * 27 + 24, body + i * 27 + 27)), `colour ${i}`);
    rejects(r, "transformFile: not a PLY", () => arps.transformFile(new Uint8Array([1, 2, 3]), "a.ply", T), /PLY/);
    rejects(r, "transformFile: scaled along one axis", () => arps.transformFile(frag, "a.ply", T.map((v, i) => (i === 0 ? 2 * v : v))), /not rigid/);
    rejects(r, "transformFile: no matrix", () => arps.transformFile(frag, "a.ply"), /^matrix is undefined/);
    rejects(r, "transformFile: a file name that is not a string", () => arps.transformFile(frag, 7, T), /^fileName: expected a string/);

    // transformFile on a LAS survey: moved as it is: the same length and VLRs, its points those
    // transformPointCloud gives (to the file's 0.01 scale), its records' attributes kept
    const las = readFileSync(path.join(root, "fixtures", "formats", "simple.las"));
    const movedLas = arps.transformFile(las, "simple.las", T);
    assert.ok(movedLas instanceof Uint8Array && movedLas.length === las.length);
    const offset = las.readUInt32LE(96);
    assert.deepEqual(movedLas.subarray(227, offset), new Uint8Array(las.subarray(227, offset)), "the VLRs");
    assert.deepEqual(movedLas.subarray(offset + 12, offset + 34), new Uint8Array(las.subarray(offset + 12, offset + 34)), "a record's attributes");
    apart = apartFrom(las, movedLas, "a.las");
    assert.ok(apart <= 0.0052, `transformFile's LAS points ${apart} from transformPointCloud's`);
    const laz = readFileSync(path.join(root, "fixtures", "formats", "simple.laz"));
    // a LAZ file comes back as LAZ, compressed again: its points what the LAS file gives
    const movedLaz = arps.transformFile(laz, "simple.laz", T);
    assert.ok(movedLaz[104] & 0x80 && movedLaz.length < movedLas.length * 0.6, "LAZ moved as LAZ");
    assert.deepEqual(arps.readPointCloud(movedLaz, "a.laz"), arps.readPointCloud(movedLas, "a.las"), "LAZ's points");
    rejects(r, "transformFile: not LAS", () => arps.transformFile(new Uint8Array(400), "a.las", T), /LASF/);
    // classes: the ground (class 2) of the LAZ survey alone, 276 of its 1065 points; an empty
    // list and a file without classes refused; transformFile with the same read options moves
    // every point of the file
    assert.equal(arps.readPointCloud(laz, "simple.laz", { classes: [2] }).points.length, 3 * 276);
    assert.equal(arps.parsePointCloud(laz, "simple.laz", { classes: [1, 2] }).length, 3 * 1065);
    rejects(r, "readPointCloud: no class named", () => arps.readPointCloud(laz, "simple.laz", { classes: [] }), /keeps no point/);
    rejects(r, "readPointCloud: no point of those classes", () => arps.readPointCloud(laz, "simple.laz", { classes: [6] }), /none of its 1065 points is of classes 6 \(it holds classes 1 \(789\), 2 \(276\)/);
    rejects(r, "readPointCloud: classes of a PLY", () => arps.readPointCloud(frag, "frag.ply", { classes: [2] }), /only LAS and LAZ files hold classifications/);
    assert.deepEqual(arps.transformFile(laz, "simple.laz", T, { classes: [2] }), movedLaz);
    // a file under another format's name goes by its signature: a PLY named .las is moved as PLY
    assert.deepEqual(arps.transformFile(frag, "a.las", T), movedPly);
    // a PCD (x y z normal_x normal_y normal_z rgb) moved as it is (near zero): its points those
    // transformPointCloud gives, its header and colours kept; moved onto the map grid, where its
    // float32 fields would round the points, with x, y, z as doubles; the names canTransform accepts
    const pcd = readFileSync(path.join(root, "fixtures", "formats", "cloud_bin_0_binary.pcd"));
    const farPcd = arps.transformFile(pcd, "cloud.pcd", T);
    assert.ok(new TextDecoder().decode(farPcd.subarray(0, 200)).includes("SIZE 8 8 8 4 4 4 4"), "x, y, z as doubles");
    assert.equal(farPcd.length, pcd.length + 12 * 3903);
    const farWant = arps.transformPointCloud(arps.readPointCloud(pcd, "c.pcd"), T);
    const farGot = arps.readPointCloud(farPcd, "c.pcd");
    let farApart = 0;
    for (let i = 0; i < farGot.points.length; i++) farApart = Math.max(farApart, Math.abs(farGot.origin[i % 3] + farGot.points[i] - farWant.origin[i % 3] - farWant.points[i]));
    assert.ok(farApart < 1e-5, `transformFile's PCD points on the map grid ${farApart} from transformPointCloud's`);
    const movedPcd = arps.transformFile(pcd, "cloud.pcd", turn);
    const pcdBody = pcd.indexOf("DATA binary\n") + 12;
    assert.ok(movedPcd.length === pcd.length);
    assert.deepEqual(movedPcd.subarray(0, pcdBody), new Uint8Array(pcd.subarray(0, pcdBody)), "the PCD header");
    assert.deepEqual(movedPcd.subarray(pcdBody + 24, pcdBody + 28), new Uint8Array(pcd.subarray(pcdBody + 24, pcdBody + 28)), "a colour");
    const pcdWant = arps.transformPointCloud(arps.readPointCloud(pcd, "c.pcd"), turn);
    const pcdGot = arps.readPointCloud(movedPcd, "c.pcd");
    apart = 0;
    for (let i = 0; i < pcdGot.points.length; i++) apart = Math.max(apart, Math.abs(pcdGot.origin[i % 3] + pcdGot.points[i] - pcdWant.origin[i % 3] - pcdWant.points[i]));
    assert.ok(apart < 1e-5, `transformFile's PCD points ${apart} from transformPointCloud's`);
    assert.deepEqual(["a.ply", "b.PCD", "c.pts", "d.csv", "e.obj", "f.stl", "g.las", "h.laz", "i.e57", "j.off", "k.glb", "l.GLTF", "m.dxf"].map(arps.canTransform), [true, true, true, true, true, true, true, true, true, true, true, true, false]);
    // a GLB (trimesh's, its mesh under a node): read as placed, its surface sampled, moved as it
    // is (its binary chunk kept) to transformPointCloud's points
    const glb = readFileSync(path.join(root, "fixtures", "formats", "fuze_trimesh.glb"));
    assert.equal(arps.parsePointCloud(glb, "fuze.glb").length, 3 * 664);
    assert.equal(arps.parsePointCloud(glb, "fuze.glb", { surfacePoints: 1000 }).length, 3000);
    const movedGlb = arps.transformFile(glb, "fuze.glb", turn);
    assert.deepEqual(movedGlb.subarray(movedGlb.length - 7968), new Uint8Array(glb.subarray(glb.length - 7968)), "the GLB's positions, byte for byte");
    const glbWant = arps.transformPointCloud(arps.readPointCloud(glb, "f.glb"), turn);
    const glbGot = arps.readPointCloud(movedGlb, "f.glb");
    apart = 0;
    for (let i = 0; i < glbGot.points.length; i++) apart = Math.max(apart, Math.abs(glbGot.origin[i % 3] + glbGot.points[i] - glbWant.origin[i % 3] - glbWant.points[i]));
    assert.ok(apart < 1e-5, `transformFile's GLB points ${apart} from transformPointCloud's`);
    rejects(r, "parsePointCloud: a Draco GLB", () => arps.parsePointCloud(readFileSync(path.join(root, "fixtures", "formats", "fuze_draco.glb")), "d.glb"), /KHR_draco_mesh_compression/);
    rejects(r, "transformFile: no format", () => arps.transformFile(new Uint8Array(8), "drawing.dxf", T), /cannot tell the format/);
    // an E57 file's scans, by name and records; one chosen is read alone; the file moved by its
    // scans' poses reads as transformPointCloud's points
    const e57 = readFileSync(path.join(root, "fixtures", "formats", "velodyne_two_scans.e57"));
    apart = apartFrom(e57, arps.transformFile(e57, "two.e57", T), "two.e57");
    assert.ok(apart < 1e-3, `transformFile's E57 points ${apart} from transformPointCloud's`);
    rejects(r, "transformFile: E57 scaled", () => arps.transformFile(e57, "two.e57", T.map((v, i) => (i < 12 && i % 4 < 3 ? 2 * v : v))), /poses are rigid/);
    assert.deepEqual(arps.listScans(e57, "two.e57"), [{ name: "scan 1", records: 1000 }, { name: "scan 2", records: 1000 }]);
    assert.equal(arps.readPointCloud(e57, "two.e57", { scan: 1 }).points.length, 3000);
    // one scan saved alone: an E57 file of that scan, its points those of the scan moved
    const second = arps.transformFile(e57, "two.e57", T, { scan: 1 });
    assert.deepEqual(arps.listScans(second, "second.e57"), [{ name: "scan 2", records: 1000 }]);
    const want = arps.transformPointCloud(arps.readPointCloud(e57, "two.e57", { scan: 1 }), T);
    const got = arps.readPointCloud(second, "second.e57");
    apart = 0;
    for (let i = 0; i < got.points.length; i++) apart = Math.max(apart, Math.abs(got.origin[i % 3] + got.points[i] - (want.origin[i % 3] + want.points[i])));
    assert.ok(got.points.length === 3000 && apart < 1e-3, `one scan saved alone: ${apart} from transformPointCloud's`);
    rejects(r, "transformFile: a scan beyond the file's", () => arps.transformFile(e57, "two.e57", T, { scan: 2 }), /scan = 2, but the E57 file holds 2 scans/);
    rejects(r, "transformFile: bad read options", () => arps.transformFile(e57, "two.e57", T, { scan: -1 }), /invalid read options/);
    assert.deepEqual(arps.listScans(frag, "frag.ply"), []);
    rejects(r, "listScans: half an E57 file", () => arps.listScans(e57.subarray(0, 5000), "two.e57"), /E57/);
    r.free();
  });
}

test("a real trap in the engine: the module is re-instantiated and registrars keep working", () => {
  // The raw glue that the Node build's facade wraps; a facade over it whose parsePointCloud
  // passes a number as the file name, which traps inside the wasm instance (memory access out
  // of bounds). The package never does this (it checks file names): the wrapper only stands in
  // for any trap (out of memory, an engine bug).
  const require = createRequire(import.meta.url);
  const glue = require(path.join(pkg, "node", "arps_glue.js"));
  const trapping = Object.create(glue, { parsePointCloud: { value: (bytes) => glue.parsePointCloud(bytes, 5) } });
  const api = makeApi(trapping, () => true, { readDefaultModel: () => readFileSync(path.join(pkg, "models", "arps-web.safetensors")) });
  const before = api.Registrar.withDefaultModel();
  stillWorks(before, "before the trap");
  let thrown;
  try {
    api.parsePointCloud(sourcePly, "s.ply");
  } catch (e) {
    thrown = e;
  }
  assert.ok(thrown instanceof Error && !(thrown instanceof WebAssembly.RuntimeError), String(thrown));
  assert.equal(thrown.code, "ARPS_TRAPPED");
  assert.match(thrown.message, /^arps: parsePointCloud trapped in the engine \(RuntimeError: .*\).*the engine was re-instantiated/);
  assert.ok(thrown.cause instanceof WebAssembly.RuntimeError, "the trap is the cause");
  // The registrar built before the trap reloads its model and works; so do new ones.
  stillWorks(before, "the registrar built before the trap");
  stillWorks(api.Registrar.withDefaultModel(), "a new registrar");
  const res = before.register(source(), target(), { icp: "off" });
  assert.equal(res.icpIterations, 0);
  assert.equal(api.version(), nodeBuild.version());
  // Again: every trap is recovered from, not just the first.
  assert.throws(() => api.parsePointCloud(sourcePly, "s.ply"), (e) => e.code === "ARPS_TRAPPED");
  stillWorks(before, "after a second trap");
  before.free();
});

test("web build: a call before init() says so, without breaking the module", async () => {
  // A fresh copy of the web entry (a query string makes a new module instance).
  const url = pathToFileURL(path.join(pkg, "arps.js")).href + "?fresh";
  const fresh = await import(url);
  assert.throws(() => fresh.Registrar.withDefaultModel(), /^Error: arps: the engine is not loaded yet; call and await init\(\) first/);
  await fresh.default({ module_or_path: readFileSync(path.join(pkg, "arps_bg.wasm")), model: readFileSync(path.join(pkg, "models", "arps-web.safetensors")) });
  stillWorks(fresh.Registrar.withDefaultModel(), "after init");
});

for (const [name, arps] of [["node build", nodeBuild], ["web build", webBuild]]) {
  test(`${name}: rigidFromPairs fits landmarks, names what is wrong, and its answer starts a registration`, () => {
    // the fixture's ground truth (row-major rows) maps source landmarks onto target ones
    const T = groundTruth;
    const at = (p) => [0, 1, 2].map((r) => T[r][0] * p[0] + T[r][1] * p[1] + T[r][2] * p[2] + T[r][3]);
    const src = source();
    const picks = [0, 97, 311, 523, 801].map((i) => [src[3 * i], src[3 * i + 1], src[3 * i + 2]]);
    const fit = arps.rigidFromPairs(picks, picks.map(at));
    const { rot, tr } = errors(fit.T_target_source);
    assert.ok(rot < 1e-4 && tr < 1e-5 && fit.rmse < 1e-5, `${rot} deg, ${tr}, rmse ${fit.rmse}`);
    // packed numbers and typed arrays read alike
    const packed = arps.rigidFromPairs(new Float32Array(picks.flat()), picks.map(at).flat());
    assert.ok(errors(packed.T_target_source).rot < 1e-3);
    // noisy landmarks: a guess the registration refines
    const noisy = picks.map(at).map((p, i) => p.map((v, k) => v + 0.01 * Math.sin(7 * i + k)));
    const guess = arps.rigidFromPairs(picks, noisy);
    assert.ok(guess.rmse > 0.001 && guess.rmse < 0.05, `rmse ${guess.rmse}`);
    const r = arps.Registrar.withDefaultModel();
    const res = r.register(source(), target(), { initialTransform: guess.T_target_source });
    assert.ok(errors(res.T_target_source).rot < 1, `refined ${errors(res.T_target_source).rot} deg`);
    for (const [label, fn, re] of [
      ["two pairs", () => arps.rigidFromPairs(picks.slice(0, 2), picks.slice(0, 2).map(at)), /the pairs: 2 given, at least 3 are needed/],
      ["lengths differ", () => arps.rigidFromPairs(picks, picks.slice(0, 4).map(at)), /5 source points against 4 target points/],
      ["not xyz", () => arps.rigidFromPairs([1, 2, 3, 4], [1, 2, 3, 4]), /source has 4 numbers, not a multiple of 3/],
      ["on a line", () => arps.rigidFromPairs([[0, 0, 0], [1, 1, 1], [2, 2, 2]], picks.slice(0, 3).map(at)), /source points lie on one line/],
      ["NaN", () => arps.rigidFromPairs(picks, picks.map(at).map((p, i) => (i === 2 ? [p[0], NaN, p[2]] : p))), /target point 2 is not finite/],
      ["a string", () => arps.rigidFromPairs("1,2,3", picks.map(at)), /source: got a string; expected packed xyz numbers/],
      ["a short row", () => arps.rigidFromPairs([[1, 2]], picks.map(at)), /source\[0\] has 2 numbers/],
    ]) rejects(r, label, fn, re);
  });
}
