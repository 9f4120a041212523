#!/usr/bin/env node
// The wasm build's side of `scripts/bench-peers.sh`: registers every pair of the given sets with
// the Node build of pkg/ (default options) and writes, per pair, the milliseconds `register()`
// took (wall clock, the clouds already parsed) and the answer, as JSON on stdout.
//
//   node scripts/bench-peers.mjs [--pkg DIR] [--label NAME] [--options JSON] SET_NAME=DIR [SET_NAME=DIR ...] > arps.json
//
// --pkg: the package directory whose node/index.mjs is loaded (default pkg/; e.g. a copy of an
// older build, for before/after timings). --label: the engine's name in the output. --options:
// the registration options as JSON (e.g. '{"up": [0, 0, 1]}'; default: none, the defaults).
// DIR holds pairs.tsv (name, source, target, overlap_threshold, note, T_target_source row-major)
// and the clouds it names. Each set starts with one untimed registration of its first pair (the
// engine's tiers compile, its memory grows to the set's size); then each pair is timed once.
import { readFileSync, existsSync } from "node:fs";
import path from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const args = process.argv.slice(2);
const option = (name) => {
  const i = args.indexOf(name);
  return i >= 0 ? args.splice(i, 2)[1] : null;
};
const pkgDir = path.resolve(option("--pkg") ?? path.join(root, "pkg"));
const label = option("--label");
const optionsJson = option("--options");
const options = optionsJson ? JSON.parse(optionsJson) : {};
const sets = args.map((a) => {
  const i = a.indexOf("=");
  if (i < 1) throw new Error(`bench-peers: expected SET_NAME=DIR, got ${a}`);
  return { name: a.slice(0, i), dir: path.resolve(a.slice(i + 1)) };
});

const entry = path.join(pkgDir, "node", "index.mjs");
if (!existsSync(entry)) {
  console.error(`bench-peers: ${entry} not found; run scripts/build-pkg.sh first`);
  process.exit(1);
}
const arps = await import(pathToFileURL(entry).href);
await arps.default();
const registrar = arps.Registrar.withDefaultModel();

const out = { engine: label ?? `arps wasm (Node ${process.versions.node})`, options: optionsJson ? options : "default", sets: {} };
for (const set of sets) {
  const lines = readFileSync(path.join(set.dir, "pairs.tsv"), "utf8").trim().split("\n");
  const pairs = lines
    .filter((l, k) => l.trim() && !l.startsWith("#") && !(k === 0 && l.startsWith("name\t")))
    .map((l) => l.split("\t"))
    .map((f) => ({ name: f[0], source: path.join(set.dir, f[1]), target: path.join(set.dir, f[2]) }));
  const load = (p) => [
    arps.parsePointCloud(readFileSync(p.source), path.basename(p.source)),
    arps.parsePointCloud(readFileSync(p.target), path.basename(p.target)),
  ];
  if (pairs.length) registrar.register(...load(pairs[0]), options); // warm-up, untimed
  const rows = [];
  for (const p of pairs) {
    const [s, t] = load(p);
    // a registrar keeps the last target it prepared: forgotten first, so that each timed call
    // prepares its target, as Open3D's do (builds older than `forgetTarget` keep none)
    registrar.forgetTarget?.();
    const t0 = performance.now();
    const r = registrar.register(s, t, options);
    const ms = performance.now() - t0;
    rows.push({
      name: p.name,
      ms,
      timingsMs: r.timings ?? r.timingsMs, // (timingsMs: builds before the generated contract)
      start: r.start,
      confidence: r.confidence,
      startsRefined: r.startsRefined,
      matrixColumnMajor: Array.from(r.T_target_source ?? r.matrix64),
    });
    console.error(`bench-peers: arps ${set.name} ${p.name} ${ms.toFixed(1)} ms`);
  }
  out.sets[set.name] = rows;
}
registrar.free();
console.log(JSON.stringify(out));
