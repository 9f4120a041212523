#!/usr/bin/env node
// Many scans onto one model, in WebAssembly (the Node build of pkg/): how much a registrar that
// kept the model from the scan before saves against one that prepares it anew, on the same scans.
//
//   scripts/build-pkg.sh
//   node scripts/bench-target-reuse.mjs [--points N] [--scans K] [--rounds R]
//
// The model: fixtures/formats/angle_block_binary_solid.stl read as N points over its surface
// (default 1,000,000). The scans: K close-ups (default 6): other points of its surface (28,572,
// seeded) within 40% of its half-extent of one of them, turned up to 30 degrees about each axis
// and moved. Each scan is registered by registrar A, which keeps the model between calls, and by
// registrar B, which forgets it before each (`forgetTarget`: the model is prepared anew); A and B
// alternate, R rounds (default 2). Prints the median ms per call of each (wall clock, and the
// engine's preparation), their ratio, and whether A and B gave the same answers.
import { readFileSync, existsSync } from "node:fs";
import path from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..");
const args = process.argv.slice(2);
const flag = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 ? Number(args[i + 1]) : fallback;
};
const points = flag("--points", 1_000_000);
const count = flag("--scans", 6);
const rounds = flag("--rounds", 2);

const entry = path.join(root, "pkg", "node", "index.mjs");
if (!existsSync(entry)) {
  console.error("bench-target-reuse: pkg/node not found; run scripts/build-pkg.sh first");
  process.exit(1);
}
const arps = await import(pathToFileURL(entry).href);
await arps.default();

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  const m = s.length >> 1;
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
};
// a small seeded generator (mulberry32), so the scans are the same on every run
let state = 11;
const random = () => {
  state = (state + 0x6d2b79f5) | 0;
  let t = Math.imul(state ^ (state >>> 15), 1 | state);
  t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
  return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
};
const uniform = (a, b) => a + (b - a) * random();

const name = "angle_block_binary_solid.stl";
const bytes = readFileSync(path.join(root, "fixtures", "formats", name));
const model = arps.parsePointCloud(bytes, name, { surfacePoints: points, seed: 0 });

// R = Rx(a) Ry(b) Rz(c), applied to each point, plus a shift
const turn = (cloud, [a, b, c], shift) => {
  const [ca, sa, cb, sb, cc, sc] = [Math.cos(a), Math.sin(a), Math.cos(b), Math.sin(b), Math.cos(c), Math.sin(c)];
  const r = [
    [cb * cc, -cb * sc, sb],
    [ca * sc + sa * sb * cc, ca * cc - sa * sb * sc, -sa * cb],
    [sa * sc - ca * sb * cc, sa * cc + ca * sb * sc, ca * cb],
  ];
  const out = new Float32Array(cloud.length);
  for (let i = 0; i < cloud.length; i += 3) {
    for (let k = 0; k < 3; k++) {
      out[i + k] = r[k][0] * cloud[i] + r[k][1] * cloud[i + 1] + r[k][2] * cloud[i + 2] + shift[k];
    }
  }
  return out;
};
const halfExtent = (cloud) => {
  let h = 0;
  for (let k = 0; k < 3; k++) {
    let [lo, hi] = [Infinity, -Infinity];
    for (let i = k; i < cloud.length; i += 3) [lo, hi] = [Math.min(lo, cloud[i]), Math.max(hi, cloud[i])];
    h = Math.max(h, (hi - lo) / 2);
  }
  return h;
};
const scans = [];
for (let k = 0; k < count; k++) {
  const dense = arps.parsePointCloud(bytes, name, { surfacePoints: 28_572, seed: 200 + k });
  const reach = 0.4 * halfExtent(dense);
  const c = 3 * Math.floor(uniform(0, dense.length / 3));
  const near = [];
  for (let i = 0; i < dense.length; i += 3) {
    const d2 = (dense[i] - dense[c]) ** 2 + (dense[i + 1] - dense[c + 1]) ** 2 + (dense[i + 2] - dense[c + 2]) ** 2;
    if (d2 < reach * reach) near.push(dense[i], dense[i + 1], dense[i + 2]);
  }
  const angles = [0, 1, 2].map(() => (uniform(-30, 30) * Math.PI) / 180);
  scans.push(turn(Float32Array.from(near), angles, [0, 1, 2].map(() => uniform(-0.5, 0.5))));
}

const kept = arps.Registrar.withDefaultModel();
const anew = arps.Registrar.withDefaultModel();
kept.register(scans[0], model); // the model is kept from here on
const tally = { kept: { ms: [], prep: [] }, anew: { ms: [], prep: [] } };
let same = 0;
for (let round = 0; round < rounds; round++) {
  for (const [k, scan] of scans.entries()) {
    const order = (round + k) % 2 === 0 ? ["kept", "anew"] : ["anew", "kept"];
    const answers = {};
    for (const which of order) {
      if (which === "anew") anew.forgetTarget();
      const t0 = performance.now();
      const r = (which === "kept" ? kept : anew).register(scan, model);
      tally[which].ms.push(performance.now() - t0);
      tally[which].prep.push(r.timings.preprocessMs);
      answers[which] = JSON.stringify([r.T_target_source, r.confidence]);
    }
    same += answers.kept === answers.anew;
  }
}
const [a, b] = [median(tally.kept.ms), median(tally.anew.ms)];
console.log(
  `model of ${points} points, ${tally.kept.ms.length} close-ups: kept ${a.toFixed(1)} ms ` +
    `(preparation ${median(tally.kept.prep).toFixed(1)}), prepared anew ${b.toFixed(1)} ms ` +
    `(${median(tally.anew.prep).toFixed(1)}); ratio ${(a / b).toFixed(2)}; the same answers on ${same} of ${tally.kept.ms.length}`,
);
