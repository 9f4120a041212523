// The street pairs of the browser tests, from the committed Velodyne fixture
// (fixtures/scans/velodyne-small.ply, MIT): two half-space crops (85% each), the target moved by
// TRUTH (15 degrees about a near-vertical axis plus (1.0, -0.6, 0.2) m); the large pair densifies
// both crops (every fixture point repeated with independent jitter of about 0.08 m, seeds 11 and
// 12). Used by demo.test.mjs and bench-page.mjs; from the command line it writes the files, to
// register them natively:
//   node tests/e2e/street-pair.mjs DIR [POINTS]   # DIR/source.ply, DIR/target.ply, and with
//                                                 # POINTS DIR/big-source.ply, DIR/big-target.ply
//   target/release/arps register DIR/big-source.ply DIR/big-target.ply --json
import { mkdirSync, readFileSync, writeFileSync } from "node:fs";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { crop, random, rigid, transformPoints, writePly } from "../../www/lib.js";

const ROOT = resolve(dirname(fileURLToPath(import.meta.url)), "../..");

/** T_target_source of the pairs (column-major, as www/lib.js's `rigid` returns it). */
export const TRUTH = rigid([0.1, 0.15, 1], 15, [1.0, -0.6, 0.2]);

/**
 * The points of a binary little-endian PLY with x, y, z only, all float (the fixture's layout; a
 * Float32Array) or all double (a Float64Array).
 */
export function readFloatPly(path) {
  const buf = readFileSync(path);
  const head = buf.indexOf("end_header\n") + "end_header\n".length;
  const header = buf.subarray(0, head).toString("latin1");
  if (!/format binary_little_endian 1\.0/.test(header)) throw new Error(`${path}: not a binary little-endian PLY`);
  const n = Number(header.match(/element vertex (\d+)/)[1]);
  const double = /property double x/.test(header);
  const body = buf.subarray(head, head + n * (double ? 24 : 12));
  const bytes = body.buffer.slice(body.byteOffset, body.byteOffset + body.length);
  return double ? new Float64Array(bytes) : new Float32Array(bytes);
}

/** `n` points: the given ones in turn, each moved by a seeded jitter of about `sigma` per axis. */
export function densify(points, n, sigma, seed) {
  const rand = random(seed);
  const m = points.length / 3;
  const out = new Float32Array(n * 3);
  for (let i = 0; i < n; i++) {
    const j = i % m;
    for (let d = 0; d < 3; d++) out[i * 3 + d] = points[j * 3 + d] + (rand() + rand() + rand() - 1.5) * 2 * sigma;
  }
  return out;
}

/** The two crops of the fixture: `{ source, target }`, the target in the source's frame. */
export function streetCrops() {
  const scan = readFloatPly(join(ROOT, "fixtures/scans/velodyne-small.ply"));
  return { source: crop(scan, [1, 0.2, 0], 0.85).points, target: crop(scan, [-1, 0.3, 0], 0.85).points };
}

/** The pair as PLY bytes: `{ source, target }` as cropped, or densified to `points` each. */
export function streetPair(points) {
  const c = streetCrops();
  const grow = (p, seed) => (points ? densify(p, points, 0.08, seed) : p);
  return {
    source: writePly(grow(c.source, 11), "street pair source"),
    target: writePly(transformPoints(grow(c.target, 12), TRUTH), "street pair target: the source frame moved by TRUTH"),
  };
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const [dir, points] = process.argv.slice(2);
  if (!dir) {
    console.error("usage: node tests/e2e/street-pair.mjs DIR [POINTS]");
    process.exit(2);
  }
  mkdirSync(dir, { recursive: true });
  const small = streetPair();
  writeFileSync(join(dir, "source.ply"), small.source);
  writeFileSync(join(dir, "target.ply"), small.target);
  if (points) {
    const big = streetPair(Number(points));
    writeFileSync(join(dir, "big-source.ply"), big.source);
    writeFileSync(join(dir, "big-target.ply"), big.target);
  }
  console.log(`wrote ${dir}; T_target_source (column-major) ${JSON.stringify(Array.from(TRUTH))}`);
}
