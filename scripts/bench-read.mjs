#!/usr/bin/env node
// Median milliseconds to read point-cloud files with the WebAssembly build in Node
// (`readPointCloud`: the file's bytes to `{ points, origin }`), per file, with the points and
// the millions of points per second.
//
//   scripts/build-pkg.sh                                   # the wasm build (pkg/node)
//   node scripts/bench-read.mjs [--reps N] FILE...
//
// Per file, one untimed warm-up read, then N timed reads (default 3; the bytes are read from
// disk once, before). Compare formats by giving the same points in several files.
import { readFileSync, statSync } from "node:fs";
import path from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const args = process.argv.slice(2);
let reps = 3;
const files = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--reps") reps = Number(args[++i]);
  else files.push(args[i]);
}
if (!files.length || !(reps >= 1)) {
  console.error("usage: node scripts/bench-read.mjs [--reps N] FILE...");
  process.exit(2);
}
const { default: init, readPointCloud } = await import(pathToFileURL(path.join(root, "pkg", "node", "index.mjs")).href);
await init({ model: false });

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  const m = s.length >> 1;
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
};

console.log("| file | MB | points | ms (median) | M points/s |");
console.log("|---|---|---|---|---|");
for (const file of files) {
  const bytes = readFileSync(file);
  const name = path.basename(file);
  let points = readPointCloud(bytes, name).points.length / 3;
  const ms = [];
  for (let r = 0; r < reps; r++) {
    const t = performance.now();
    points = readPointCloud(bytes, name).points.length / 3;
    ms.push(performance.now() - t);
  }
  const m = median(ms);
  const mb = statSync(file).size / 1e6;
  console.log(`| ${name} | ${mb.toFixed(1)} | ${points.toLocaleString("en")} | ${m.toFixed(0)} | ${(points / m / 1e3).toFixed(1)} |`);
}
