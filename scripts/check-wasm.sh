#!/usr/bin/env bash
# Checks the built package (scripts/build-pkg.sh first):
#   1. size budgets, each on its own: the engine (the package's one .wasm, built without the
#      embedded model) and the default model (pkg/models/arps-web.safetensors, a separate
#      file), raw and gzip -9;
#   2. SIMD: simd128 instructions are really in the code, and f32x4 arithmetic (add/sub/mul/fma:
#      what the network's kernels compute with) is among them, not just lane moves; counted with
#      npm binaryen's disassembler.
# Budgets (bytes), overridable from the environment:
#   ARPS_ENGINE_BUDGET     engine .wasm, raw              default 1,407,000
#   ARPS_ENGINE_GZ_BUDGET  engine .wasm, gzip -9          default   576,500
#   ARPS_MODEL_BUDGET      default model, raw             default 1,260,000
#   ARPS_MODEL_GZ_BUDGET   default model, gzip -9         default 1,200,000
#   ARPS_SIMD_MIN          SIMD instructions, at least    default       200
#   ARPS_SIMD_F32_MIN      f32x4 add/sub/mul/fma, at least default        16
# Usage: scripts/check-wasm.sh [FILE.wasm ...]   (default: pkg/arps_bg.wasm)
set -euo pipefail
cd "$(dirname "$0")/.."

engine_budget=${ARPS_ENGINE_BUDGET:-1407000}
engine_gz_budget=${ARPS_ENGINE_GZ_BUDGET:-576500}
model_budget=${ARPS_MODEL_BUDGET:-1260000}
model_gz_budget=${ARPS_MODEL_GZ_BUDGET:-1200000}
simd_min=${ARPS_SIMD_MIN:-200}
simd_f32_min=${ARPS_SIMD_F32_MIN:-16}
model=pkg/models/arps-web.safetensors

files=("$@")
[ ${#files[@]} -eq 0 ] && files=(pkg/arps_bg.wasm)

fail=0
# check_size WHAT FILE RAW_BUDGET GZ_BUDGET: prints the file's raw and gzip -9 sizes against its
# budgets; a missing file stops the check, a size over budget sets fail=1.
check_size() {
  local what=$1 f=$2 raw_budget=$3 gz_budget=$4 raw gz
  if [ ! -f "$f" ]; then
    echo "check-wasm: $f not found (run scripts/build-pkg.sh)" >&2
    exit 1
  fi
  raw=$(stat -c %s "$f")
  gz=$(gzip -9 -c "$f" | wc -c)
  printf 'check-wasm: %s %s: %d bytes raw (budget %d), %d gzip -9 (budget %d)\n' \
    "$what" "$f" "$raw" "$raw_budget" "$gz" "$gz_budget"
  [ "$raw" -le "$raw_budget" ] || { echo "check-wasm: FAIL $f: the $what is over its raw size budget" >&2; fail=1; }
  [ "$gz" -le "$gz_budget" ] || { echo "check-wasm: FAIL $f: the $what is over its gzip size budget" >&2; fail=1; }
}
check_size model "$model" "$model_budget" "$model_gz_budget"
for f in "${files[@]}"; do
  check_size engine "$f" "$engine_budget" "$engine_gz_budget"
  node --input-type=module - "$f" "$simd_min" "$simd_f32_min" <<'JS' || fail=1
import { readFileSync } from "node:fs";
import binaryen from "binaryen";
const [file, min, f32min] = process.argv.slice(2);
const mod = binaryen.readBinary(readFileSync(file));
mod.setFeatures(binaryen.Features.All);
// Text of the code only (the data segments are dropped first).
const text = mod.emitText().split("\n").filter((l) => !l.trimStart().startsWith("(data ")).join("\n");
mod.dispose();
const ops = text.match(/\b(v128|[if](8x16|16x8|32x4|64x2)|i8x16|i16x8|i32x4|i64x2|f32x4|f64x2)\.[a-z_0-9]+/g) ?? [];
const byOp = {};
for (const op of ops) byOp[op] = (byOp[op] ?? 0) + 1;
const top = Object.entries(byOp).sort((a, b) => b[1] - a[1]).slice(0, 8).map(([k, v]) => `${k} ${v}`).join(", ");
const f32 = ops.filter((o) => /^f32x4\.(add|sub|mul|relaxed_madd|relaxed_nmadd)$/.test(o)).length;
console.log(`check-wasm: ${file}: ${ops.length} SIMD instructions, ${f32} of them f32x4 add/sub/mul/fma; most used: ${top || "none"}`);
if (ops.length < Number(min)) {
  console.error(`check-wasm: FAIL ${file}: fewer than ${min} SIMD instructions (is +simd128 on? see .cargo/config.toml)`);
  process.exit(1);
}
if (f32 < Number(f32min)) {
  console.error(`check-wasm: FAIL ${file}: fewer than ${f32min} f32x4 add/sub/mul/fma instructions: the kernels compute in scalar`);
  process.exit(1);
}
JS
done
[ "$fail" -eq 0 ] && echo "check-wasm: ok" || { echo "check-wasm: FAILED" >&2; exit 1; }
