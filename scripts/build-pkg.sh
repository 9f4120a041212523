#!/usr/bin/env bash
# Builds the npm package into pkg/: one cargo build for wasm32, then wasm-bindgen twice (the web
# and the Node glue) with --experimental-reset-state-function, so that the facade can
# re-instantiate the module after a trap (js/facade.js).
#   pkg/arps.js     the public web entry (js/web-index.js): init(), Registrar, parsePointCloud,
#                   version; the facade (pkg/facade.js) over the raw glue (pkg/arps_glue.js);
#                   `await init()` fetches arps_bg.wasm next to them (browsers, bundlers, workers)
#   pkg/node/       the Node build: node/arps.js (CommonJS entry: the facade, node/facade.cjs, over
#                   node/arps_glue.js, which loads ../arps_bg.wasm, the same file, from disk) and
#                   node/index.mjs (ESM entry, same API); package.json "exports" picks it under Node
#   pkg/models/arps-web.safetensors  the default model (models/web.safetensors), its own file:
#                   the engine is built without the embedded model (no feature embed-model)
#   pkg/worker.js, pkg/worker-client.js (+ .d.ts): the worker and its promise API
#   pkg/arps.d.ts   the generated declarations (the facade has the glue's API) + js/arps-types.d.ts,
#                   with init/initSync and Registrar.withDefaultModel/fromUrl from js/arps-entry.d.ts
#   pkg/package.json from js/package.json, version and repository links from Cargo.toml
#   pkg/LICENSE-MIT, pkg/LICENSE-APACHE, pkg/CHANGELOG.md, pkg/examples/ (from js/examples/)
# wasm-opt: the pinned npm binaryen's wasm-opt runs here when `npm ci` has installed it
# (scripts/setup.sh), else the .wasm ships as rustc + wasm-bindgen left it. ARPS_WASM_OPT=0 skips it.
# Usage: scripts/build-pkg.sh [--dev]
set -euo pipefail
cd "$(dirname "$0")/.."

profile=release
cargo_profile=(--release)
bindgen_debug=()
if [ "${1:-}" = "--dev" ]; then
  profile=debug
  cargo_profile=()
  bindgen_debug=(--debug)
fi

say() { printf 'build-pkg: %s\n' "$*"; }

# Without the embedded model (feature embed-model): the package ships it as its own file.
say "cargo build --lib --no-default-features --target wasm32-unknown-unknown ($profile)"
cargo build --lib --no-default-features "${cargo_profile[@]}" --target wasm32-unknown-unknown
target_dir=$(cargo metadata --format-version 1 --no-deps | node -e 'let s="";process.stdin.on("data",d=>s+=d).on("end",()=>console.log(JSON.parse(s).target_directory))')
wasm="$target_dir/wasm32-unknown-unknown/$profile/arps.wasm"

rm -rf pkg
mkdir -p pkg/node
bindgen() {
  wasm-bindgen "$wasm" --out-dir "$1" --out-name arps --target "$2" --typescript \
    --experimental-reset-state-function "${bindgen_debug[@]}"
}
say "wasm-bindgen --target web"
bindgen pkg web
say "wasm-bindgen --target nodejs"
bindgen pkg/node nodejs

# The raw glue becomes arps_glue.js; the public entries are the facade's.
mv pkg/arps.js pkg/arps_glue.js
mv pkg/node/arps.js pkg/node/arps_glue.js
rm -f pkg/node/arps.d.ts
# One .wasm in the package: the Node glue loads the web build's (the two are the same file).
node -e '
  const fs = require("fs");
  const f = "pkg/node/arps_glue.js";
  const from = "const wasmPath = `${__dirname}/arps_bg.wasm`;";
  const s = fs.readFileSync(f, "utf8");
  if (!s.includes(from)) { console.error("build-pkg: " + f + " does not load its .wasm as expected: " + from); process.exit(1); }
  fs.writeFileSync(f, s.replace(from, "const wasmPath = require(\"path\").join(__dirname, \"..\", \"arps_bg.wasm\");"));
'
cmp -s pkg/arps_bg.wasm pkg/node/arps_bg.wasm || { echo "build-pkg: the web and Node builds' .wasm differ" >&2; exit 1; }
rm pkg/node/arps_bg.wasm pkg/node/arps_bg.wasm.d.ts
# The default model, its own file (cached by browsers like any static asset).
mkdir -p pkg/models
cp models/web.safetensors pkg/models/arps-web.safetensors
# The declarations describe the facade, which has the glue's API but not its reset hook.
node -e '
  const fs = require("fs");
  const f = process.argv[1];
  let s = fs.readFileSync(f, "utf8").replace(/^export function __wbg_reset_state\(\): void;\n/m, "");
  if (/__wbg_reset_state/.test(s)) { console.error("build-pkg: __wbg_reset_state left in " + f); process.exit(1); }
  // init/initSync of the facade (they also take the default model) replace the glue ones (with
  // their doc comments), and Registrar gains withDefaultModel/fromUrl: js/arps-entry.d.ts.
  for (const re of [/\/\*\*[^/]*\*\/\nexport function initSync\(module: [^\n]*\n/, /\/\*\*[^/]*\*\/\nexport default function __wbg_init \([^\n]*\n/]) {
    if (!re.test(s)) { console.error("build-pkg: no " + re + " in " + f); process.exit(1); }
    s = s.replace(re, "");
  }
  fs.writeFileSync(f, s + "\n" + fs.readFileSync("js/arps-entry.d.ts", "utf8"));
' pkg/arps.d.ts
cp pkg/arps.d.ts pkg/node/arps.d.ts
grep -q "__wbg_reset_state" pkg/arps_glue.js || { echo "build-pkg: the glue has no __wbg_reset_state" >&2; exit 1; }
cp js/facade.js pkg/facade.js
cp js/web-index.js pkg/arps.js
# CommonJS copy of the facade for the Node build (it has `export` statements only).
sed -e 's/^export //' js/facade.js > pkg/node/facade.cjs
printf '\nmodule.exports = { makeApi, modelBytes, MAX_POINTS, MAX_FILE_BYTES, MAX_FILE_NAME };\n' >> pkg/node/facade.cjs
cp js/node-index.cjs pkg/node/arps.js
cp js/node-index.mjs pkg/node/index.mjs
printf '{\n  "type": "commonjs"\n}\n' > pkg/node/package.json

wasm_opt=node_modules/.bin/wasm-opt
if [ "${ARPS_WASM_OPT:-1}" != "0" ] && [ "$profile" = release ] && [ -x "$wasm_opt" ]; then
  for f in pkg/arps_bg.wasm; do
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

cp js/worker.js js/node-worker.mjs js/worker-client.js js/worker-client.d.ts pkg/
[ -f js/README.md ] && cp js/README.md pkg/README.md
# Publishing: the licences, the changelog, the package's runnable examples (js/examples/), and
# the repository links, derived from Cargo.toml's `repository` (the one place it is written).
cp LICENSE-MIT LICENSE-APACHE CHANGELOG.md pkg/
cp -R js/examples pkg/examples
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n1)
repository=$(sed -n 's/^repository = "\(.*\)"/\1/p' Cargo.toml | head -n1)
node -e '
  const fs = require("fs");
  const [version, repository] = process.argv.slice(1);
  if (!/^https:\/\/github\.com\/[^/]+\/[^/]+$/.test(repository)) {
    console.error(`build-pkg: Cargo.toml repository "${repository}" is not https://github.com/OWNER/NAME`);
    process.exit(1);
  }
  const p = JSON.parse(fs.readFileSync("js/package.json", "utf8"));
  p.version = version;
  p.repository = { type: "git", url: `git+${repository}.git` };
  p.homepage = `${repository}#readme`;
  p.bugs = { url: `${repository}/issues` };
  fs.writeFileSync("pkg/package.json", JSON.stringify(p, null, 2) + "\n");
' "$version" "$repository"
say "pkg/ ready (arps $version): $(stat -c %s pkg/arps_bg.wasm) bytes wasm"
