#!/usr/bin/env bash
# Builds the npm package into pkg/ with wasm-pack:
#   pkg/            --target web: `import init, { Registrar } from "arps"`; `await init()` fetches
#                   arps_bg.wasm next to arps.js (browsers, bundlers, workers)
#   pkg/node/       --target nodejs (CommonJS, loads its .wasm from disk), plus node/index.mjs,
#                   the ESM entry with the same API; package.json "exports" picks it under Node
#   pkg/worker.js, pkg/worker-client.js (+ .d.ts): the worker and its promise API
#   pkg/package.json from js/package.json, version from Cargo.toml
# wasm-opt: wasm-pack's own is off (Cargo.toml); the pinned npm binaryen's wasm-opt runs here when
# `npm ci` has installed it (scripts/setup.sh), else the .wasm ships as rustc + wasm-bindgen left
# it. ARPS_WASM_OPT=0 skips it.
# Usage: scripts/build-pkg.sh [--dev]
set -euo pipefail
cd "$(dirname "$0")/.."

profile=--release
[ "${1:-}" = "--dev" ] && profile=--dev

say() { printf 'build-pkg: %s\n' "$*"; }

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

say "wasm-pack build --target web"
rm -rf pkg
wasm-pack build $profile --target web --out-dir pkg --out-name arps --no-pack
say "wasm-pack build --target nodejs"
wasm-pack build $profile --target nodejs --out-dir "$tmp/node" --out-name arps --no-pack
mkdir -p pkg/node
cp "$tmp"/node/arps.js "$tmp"/node/arps.d.ts "$tmp"/node/arps_bg.wasm "$tmp"/node/arps_bg.wasm.d.ts pkg/node/
cp js/node-index.mjs pkg/node/index.mjs
printf '{\n  "type": "commonjs"\n}\n' > pkg/node/package.json
rm -f pkg/.gitignore

wasm_opt=node_modules/.bin/wasm-opt
if [ "${ARPS_WASM_OPT:-1}" != "0" ] && [ "$profile" = --release ] && [ -x "$wasm_opt" ]; then
  for f in pkg/arps_bg.wasm pkg/node/arps_bg.wasm; do
    before=$(stat -c %s "$f")
    # Features as rustc emitted them (its target_features section); -O3 for speed.
    "$wasm_opt" "$f" -O3 --enable-simd --enable-bulk-memory --enable-nontrapping-float-to-int \
      --enable-sign-ext --enable-mutable-globals --enable-reference-types --enable-multivalue \
      -o "$f.opt"
    mv "$f.opt" "$f"
    say "wasm-opt -O3 $f: $before -> $(stat -c %s "$f") bytes"
  done
else
  say "wasm-opt skipped (npm binaryen not installed, ARPS_WASM_OPT=0, or --dev)"
fi

cp js/worker.js js/worker-client.js js/worker-client.d.ts pkg/
[ -f js/README.md ] && cp js/README.md pkg/README.md
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n1)
node -e '
  const fs = require("fs");
  const p = JSON.parse(fs.readFileSync("js/package.json", "utf8"));
  p.version = process.argv[1];
  fs.writeFileSync("pkg/package.json", JSON.stringify(p, null, 2) + "\n");
' "$version"
say "pkg/ ready (arps $version): $(stat -c %s pkg/arps_bg.wasm) bytes wasm"
