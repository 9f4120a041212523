#!/usr/bin/env bash
# The WebAssembly package's tests (scripts/test.sh runs this):
#   1. wasm-pack test --node: tests/wasm_*.rs through the JS-facing binding (ground-truth
#      registration, options, readers, every error case, instance reuse)
#   2. scripts/build-pkg.sh: the npm package in pkg/
#   3. scripts/check-wasm.sh: size budget and SIMD instructions
#   4. node --test js/test/: the built package from JavaScript (both builds, exports, the worker,
#      cancellation and worker restarts, and js/test/catalogue.test.mjs: every class of hostile
#      input, each followed by a correct registration on the same instance, large coordinates,
#      and recovery from a real trap)
#   5. tsc: the .d.ts type-checks typical use and rejects misspelled options
#   6. the package's examples/node-register.mjs (js/examples/) on the fixture pair
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n== wasm: %s\n' "$*"; }

scripts/setup.sh

step "wasm-pack test --node"
wasm-pack test --node -- --test "wasm_*"

step "build the package"
scripts/build-pkg.sh

step "size and SIMD checks"
scripts/check-wasm.sh

step "the package from JavaScript (node --test js/test/*.test.mjs)"
node --test js/test/*.test.mjs

step "TypeScript declarations (tsc -p js/test)"
node_modules/.bin/tsc -p js/test

step "pkg/examples/node-register.mjs"
node pkg/examples/node-register.mjs fixtures/wasm/source.ply fixtures/wasm/target.ply
# a mesh read as its surface, in other units (the example's reading flags)
node pkg/examples/node-register.mjs fixtures/formats/angle_block_binary_solid.stl fixtures/formats/angle_block_binary_solid.stl \
  --surface-points 5000 --source-scale 1 --drop-non-finite --json > /dev/null
