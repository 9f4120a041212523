#!/usr/bin/env node
// Registers two point-cloud files in Node and prints T_target_source.
//   node node_modules/arps/examples/node-register.mjs SOURCE TARGET [--icp plane|point|off] [--search adaptive|exhaustive]
//     [--surface-points N] [--source-scale F] [--up X,Y,Z] [--drop-non-finite] [--json] [--aligned OUT]
// SOURCE and TARGET are any format the readers know (PLY, PCD, LAS/LAZ, E57, XYZ/PTS/CSV, OBJ,
// OFF, STL, glTF), read with their coordinates kept (map-grid surveys too: `readPointCloud`).
// --surface-points N reads a mesh (a CAD model) as N points drawn over its surface, not its
// vertices; --source-scale F is the `sourceScale` option (a scan in metres onto a model in
// millimetres: 1000); --up is the `up` option; --drop-non-finite drops NaN points (an organised
// PCD's "no return" points) where they are an error by default.
// --aligned OUT writes the source moved into the target's frame: the source file itself, moved
// (`transformFile`: every attribute kept), when OUT has the source's extension, else its points as binary PLY (`transformPointCloud`, `writePly`).
// It imports "arps" as an app that installed the package does (inside the package, Node resolves
// the package's own name to itself).
import { readFileSync, writeFileSync } from "node:fs";
import path from "node:path";
import init, { canTransform, Registrar, readPointCloud, transformFile, transformPointCloud, writePly } from "arps";

function usage(message) {
  if (message) console.error(`node-register: ${message}`);
  console.error("usage: node examples/node-register.mjs SOURCE TARGET [--icp plane|point|off] [--search adaptive|exhaustive] " +
    "[--surface-points N] [--source-scale F] [--up X,Y,Z] [--drop-non-finite] [--json] [--aligned OUT]");
  process.exit(2);
}

const args = process.argv.slice(2);
const files = [];
const options = {};
let json = false;
let aligned = null;
let surfacePoints = null;
const number = (flag, value) => {
  const v = Number(value ?? usage(`${flag} needs a value`));
  return Number.isFinite(v) && v > 0 ? v : usage(`${flag} must be a positive number, got ${value}`);
};
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--json") json = true;
  else if (args[i] === "--icp") options.icp = args[++i] ?? usage("--icp needs a value");
  else if (args[i] === "--search") options.search = args[++i] ?? usage("--search needs a value");
  else if (args[i] === "--aligned") aligned = args[++i] ?? usage("--aligned needs a path");
  else if (args[i] === "--surface-points") surfacePoints = number("--surface-points", args[++i]);
  else if (args[i] === "--source-scale") options.sourceScale = number("--source-scale", args[++i]);
  else if (args[i] === "--up") options.up = (args[++i] ?? usage("--up needs X,Y,Z")).split(",").map(Number);
  else if (args[i] === "--drop-non-finite") options.nonFinite = "drop";
  else if (args[i].startsWith("--")) usage(`unknown flag ${args[i]}`);
  else files.push(args[i]);
}
if (files.length !== 2) usage();
// --aligned: the source's own format (moved as it is; scaled too with --source-scale) or .ply (its
// points), said before registering
const ext = (f) => path.extname(f).slice(1).toLowerCase();
const own = aligned !== null && canTransform(files[0]) && ext(aligned) === ext(files[0]);
if (aligned !== null && !own && ext(aligned) !== "ply") {
  const moved = canTransform(files[0]) ? ` or .${ext(files[0])} (the source moved as it is)` : "";
  usage(`--aligned: name ${aligned} .ply (the source's points)${moved}`);
}

try {
  await init(); // a no-op under Node; loads the .wasm in a browser
  // { points, origin }: float32 offsets from a float64 origin, which register takes as is; the
  // answer is in the files' own frames
  const read = { surfacePoints };
  const [source, target] = files.map((f) => readPointCloud(readFileSync(f), path.basename(f), read));
  const registrar = Registrar.withDefaultModel();
  const t0 = performance.now();
  const r = registrar.register(source, target, options);
  const ms = performance.now() - t0;
  // r.T_target_source is column-major (three.js); print row-major rows, as people read matrices.
  const rows = [0, 1, 2, 3].map((row) => [0, 1, 2, 3].map((col) => r.T_target_source[col * 4 + row]));
  if (json) {
    // The result as it is: the same object `arps register --json` prints.
    console.log(JSON.stringify(r));
  } else {
    console.log(`source ${files[0]}: ${source.points.length / 3} points; target ${files[1]}: ${target.points.length / 3} points`);
    console.log("T_target_source (maps source points into the target frame):");
    for (const row of rows) console.log("  " + row.map((v) => v.toFixed(12).padStart(20)).join(" "));
    console.log(`confidence ${r.confidence.toFixed(3)} (the engine's estimate that the answer is right; below 0.5 it warns)`);
    console.log(`fitness ${r.fitness.toFixed(4)}  inlier RMSE ${r.inlierRmse.toPrecision(4)}  ` +
      `(max correspondence distance ${r.maxCorrespondenceDistance.toPrecision(4)})`);
    console.log(`ICP iterations ${r.icpIterations}${r.icpConverged ? ", converged" : ""}`);
    const t = r.timings;
    console.log(`time ${ms.toFixed(1)} ms (preprocess ${t.preprocessMs.toFixed(1)}, network ${t.networkMs.toFixed(1)}, ` +
      `GMR ${t.gmrMs.toFixed(1)}, ICP ${t.icpMs.toFixed(1)}, global ${t.globalMs.toFixed(1)}); ` +
      `best of ${r.startsRefined} start${r.startsRefined === 1 ? "" : "s"} refined: ${r.start}`);
    for (const w of r.warnings) console.log(`warning: ${w}`);
    if (registrar.provenance?.kind === "random") console.log("note: the loaded model is an untrained placeholder (random weights)");
  }
  registrar.free();
  if (aligned) {
    // the source file itself moved when OUT names its own format, else its points as PLY
    // (with --source-scale the answer maps the file's own points, in their unit, as well)
    const bytes = own
      ? transformFile(readFileSync(files[0]), path.basename(files[0]), r.T_target_source)
      : writePly(transformPointCloud(source, r.T_target_source));
    writeFileSync(aligned, bytes);
    if (!json) console.log(`wrote the aligned source to ${aligned} (${own ? "the source file moved" : "its points, as PLY"})`);
  }
} catch (e) {
  console.error(`node-register: ${e.message}`);
  process.exit(1);
}
