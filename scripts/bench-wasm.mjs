#!/usr/bin/env node
// Median milliseconds per pair of the WebAssembly build in Node next to the native CLI, on the
// same pairs with the same (default) options, and their ratio.
//
//   scripts/build-pkg.sh                                   # the wasm build (pkg/node)
//   cargo build --release --features cli --bin arps        # the native CLI (built here if missing)
//   node scripts/bench-wasm.mjs [--pairs DIR] [--reps N] [--no-native] [--starts a,b,...]
//
// DIR holds pairs.tsv (name, source, target, ...) and the PLY files; default fixtures/pairs.
// Per pair and build, N timed runs (default 3) after one untimed warm-up pass for wasm.
// --starts sets `starts` for both builds (default: the engine's default starts).
// Columns:
//   "read+register": wasm = parsePointCloud of both files' bytes + register (wall clock);
//                    native = the CLI's `wallMs` (reads both files + registers, in-process; model
//                    loading and process start are excluded, as for wasm).
//   "engine":        the engine's own timings.totalMs (register only; the same field in the CLI's JSON).
// Also prints the largest rotation difference between the two builds' answers (a sanity check:
// the builds run the same code and should agree closely; not bit for bit).
import { readFileSync, existsSync } from "node:fs";
import { execFileSync } from "node:child_process";
import path from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const args = process.argv.slice(2);
const flag = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 ? args[i + 1] : fallback;
};
const pairsDir = path.resolve(flag("--pairs", path.join(root, "fixtures", "pairs")));
const reps = Number(flag("--reps", "3"));
const withNative = !args.includes("--no-native");
const starts = flag("--starts", null);
const options = starts ? { starts: starts.split(",") } : {};

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  const m = s.length >> 1;
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
};
const fmt = (x) => (Number.isFinite(x) ? x.toFixed(1).padStart(8) : "       -");

// Pairs.
const tsv = readFileSync(path.join(pairsDir, "pairs.tsv"), "utf8").trim().split("\n");
const header = tsv[0].split("\t");
const col = (name) => header.indexOf(name);
const pairs = tsv.slice(1).map((line) => {
  const f = line.split("\t");
  return { name: f[col("name")], source: path.join(pairsDir, f[col("source")]), target: path.join(pairsDir, f[col("target")]) };
});

// WebAssembly (the Node build of pkg/).
const entry = path.join(root, "pkg", "node", "index.mjs");
if (!existsSync(entry)) {
  console.error("bench-wasm: pkg/node not found; run scripts/build-pkg.sh first");
  process.exit(1);
}
const arps = await import(pathToFileURL(entry).href);
await arps.default();
const registrar = arps.Registrar.withDefaultModel();
const STAGE_KEYS = ["preprocessMs", "networkMs", "gmrMs", "icpMs"];
const wasm = { wall: [], engine: [], stages: [], rows: new Map() };
const runWasm = (p) => {
  const sb = readFileSync(p.source);
  const tb = readFileSync(p.target);
  const t0 = performance.now();
  const s = arps.parsePointCloud(sb, path.basename(p.source));
  const t = arps.parsePointCloud(tb, path.basename(p.target));
  const r = registrar.register(s, t, options);
  return { wall: performance.now() - t0, engine: r.timings.totalMs, stages: r.timings, matrix: r.T_target_source };
};
for (const p of pairs) runWasm(p); // warm-up: compile tiers, grow memory
// A registrar keeps the last target it prepared and reuses it for the same target; the native
// CLI starts afresh each time. Each timed call forgets it first, so that it prepares its target,
// as the CLI's does.
for (const p of pairs) {
  for (let i = 0; i < reps; i++) {
    registrar.forgetTarget();
    const r = runWasm(p);
    wasm.wall.push(r.wall);
    wasm.engine.push(r.engine);
    wasm.stages.push(r.stages);
    wasm.rows.set(p.name, r.T_target_source);
  }
}

// Native CLI.
let native = null;
let nativeNote = "";
if (withNative) {
  const bin = path.join(root, "target", "release", process.platform === "win32" ? "arps.exe" : "arps");
  try {
    console.error("bench-wasm: building the native CLI (cargo build --release --features cli --bin arps)");
    execFileSync("cargo", ["build", "--release", "--quiet", "--features", "cli", "--bin", "arps"], { cwd: root, stdio: "inherit" });
    native = { wall: [], engine: [], stages: [], rotDiff: 0 };
    for (const p of pairs) {
      for (let i = 0; i < reps; i++) {
        const out = JSON.parse(execFileSync(bin, ["register", p.source, p.target, "--json", ...(starts ? ["--starts", starts] : [])], { encoding: "utf8" }));
        native.wall.push(out.wallMs);
        native.engine.push(out.timings?.totalMs ?? NaN);
        native.stages.push(out.timings ?? {});
        native.rotDiff = Math.max(native.rotDiff, rotationDiffDeg(wasm.rows.get(p.name), out.T_target_source));
      }
    }
  } catch (e) {
    native = null;
    nativeNote = `native CLI unavailable: ${e.message.split("\n")[0]}`;
  }
}

function rotationDiffDeg(a, b) {
  // a, b column-major: trace(R_a^T R_b) = sum over (row k, col i) of a(k, i) b(k, i)
  let trace = 0;
  for (let i = 0; i < 3; i++) for (let k = 0; k < 3; k++) trace += a[i * 4 + k] * b[i * 4 + k];
  return (Math.acos(Math.min(1, Math.max(-1, (trace - 1) / 2))) * 180) / Math.PI;
}

const w = { wall: median(wasm.wall), engine: median(wasm.engine) };
const n = native ? { wall: median(native.wall), engine: median(native.engine) } : { wall: NaN, engine: NaN };
console.log(`bench-wasm: ${pairs.length} pairs from ${path.relative(root, pairsDir) || "."}, ${reps} runs each, ${starts ? `starts ${starts}` : "default options"}`);
console.log("median ms/pair      wasm (Node)   native   wasm/native");
console.log(`  read+register   ${fmt(w.wall)}    ${fmt(n.wall)}    ${native ? (w.wall / n.wall).toFixed(2).padStart(6) : "     -"}`);
console.log(`  engine only     ${fmt(w.engine)}    ${fmt(n.engine)}    ${native ? (w.engine / n.engine).toFixed(2).padStart(6) : "     -"}`);
const stageMedian = (runs, k) => median(runs.map((t) => t[k] ?? NaN));
for (const k of STAGE_KEYS) {
  const a = stageMedian(wasm.stages, k);
  const b = native ? stageMedian(native.stages, k) : NaN;
  const ratio = native && b > 0 ? (a / b).toFixed(2).padStart(6) : "     -";
  console.log(`    ${k.replace(/Ms$/, "").padEnd(12)} ${fmt(a)}    ${fmt(b)}    ${ratio}`);
}
if (native) console.log(`largest rotation difference between the builds' answers: ${native.rotDiff.toFixed(4)} deg`);
if (nativeNote) console.log(nativeNote);
console.log(
  JSON.stringify({
    pairs: pairs.length,
    reps,
    starts: starts ?? "default",
    wasm_median_ms: w.wall,
    wasm_engine_median_ms: w.engine,
    native_median_ms: native ? n.wall : null,
    native_engine_median_ms: native ? n.engine : null,
    ratio: native ? w.wall / n.wall : null,
    engine_ratio: native ? w.engine / n.engine : null,
  }),
);
registrar.free();
