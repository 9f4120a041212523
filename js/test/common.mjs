// Shared by the JS tests of the built package (node --test js/test/): fixture clouds and the
// ground truth, parsed here independently of the engine.
import { readFileSync } from "node:fs";
import { fileURLToPath } from "node:url";
import path from "node:path";

export const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../..");
export const pkg = path.join(root, "pkg");
export const fixture = (name) => path.join(root, "fixtures", "wasm", name);

export function asciiPlyXyz(bytes) {
  const text = Buffer.from(bytes).toString("utf8");
  const body = text.slice(text.indexOf("end_header\n") + "end_header\n".length);
  return Float32Array.from(body.trim().split(/\s+/).map(Number));
}

export const sourcePly = readFileSync(fixture("source.ply"));
export const targetPly = readFileSync(fixture("target.ply"));
export const source = () => asciiPlyXyz(sourcePly);
export const target = () => asciiPlyXyz(targetPly);
/** Row-major rows of the ground-truth T_target_source. */
export const groundTruth = JSON.parse(readFileSync(fixture("pair.json"), "utf8")).T_target_source;

/** Rotation error (degrees) and translation error of a column-major 4x4 against row-major rows. */
export function errors(colMajor, rows = groundTruth) {
  const m = (r, c) => colMajor[c * 4 + r];
  let trace = 0;
  for (let i = 0; i < 3; i++) for (let k = 0; k < 3; k++) trace += rows[k][i] * m(k, i);
  const cos = Math.min(1, Math.max(-1, (trace - 1) / 2));
  const rot = (Math.acos(cos) * 180) / Math.PI;
  const tr = Math.hypot(m(0, 3) - rows[0][3], m(1, 3) - rows[1][3], m(2, 3) - rows[2][3]);
  return { rot, tr };
}

/** True when the engine's core stages are implemented (set ARPS_CORE_STUBS=1 to skip those tests while it is not). */
export const coreStubbed = process.env.ARPS_CORE_STUBS === "1";
