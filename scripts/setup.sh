#!/usr/bin/env bash
# Installs what the wasm build and its tests need, pinned, on a fresh machine; takes seconds when
# everything is already there. Safe to run again.
#   - the wasm32-unknown-unknown Rust target
#   - wasm-pack (WASM_PACK_VERSION below)
#   - wasm-bindgen-cli at exactly the version Cargo.toml pins for the wasm-bindgen crate
#   - npm dev dependencies from package-lock.json (binaryen's wasm-opt, used by build-pkg.sh;
#     three, bunny, playwright-core, pngjs for the demo page www/ and its end-to-end test; vite and
#     @types/node for the consumer test of the packed package, scripts/test-consumer.sh)
#   - Debian's Chromium (apt) for the end-to-end test, when /usr/bin/chromium is missing
set -euo pipefail
cd "$(dirname "$0")/.."

WASM_PACK_VERSION=0.15.1
# The wasm-bindgen CLI must match the crate exactly; read the `=X.Y.Z` pin from Cargo.toml.
WASM_BINDGEN_VERSION=$(sed -n 's/^wasm-bindgen = "=\([0-9.]*\)".*/\1/p' Cargo.toml | head -n1)
if [ -z "$WASM_BINDGEN_VERSION" ]; then
  echo "setup.sh: no wasm-bindgen = \"=X.Y.Z\" pin found in Cargo.toml" >&2
  exit 1
fi

say() { printf 'setup: %s\n' "$*"; }

if rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
  say "wasm32-unknown-unknown target present"
else
  say "adding the wasm32-unknown-unknown target"
  rustup target add wasm32-unknown-unknown
fi

# `cargo install --locked` fails for these crates here; plain `cargo install` of an exact version.
installed_version() { "$1" --version 2>/dev/null | awk '{print $2}' || true; }

if [ "$(installed_version wasm-bindgen)" = "$WASM_BINDGEN_VERSION" ]; then
  say "wasm-bindgen-cli $WASM_BINDGEN_VERSION present"
else
  say "installing wasm-bindgen-cli $WASM_BINDGEN_VERSION (several minutes)"
  cargo install wasm-bindgen-cli --version "$WASM_BINDGEN_VERSION" --force
fi

if [ "$(installed_version wasm-pack)" = "$WASM_PACK_VERSION" ]; then
  say "wasm-pack $WASM_PACK_VERSION present"
else
  say "installing wasm-pack $WASM_PACK_VERSION (several minutes)"
  cargo install wasm-pack --version "$WASM_PACK_VERSION" --force
fi

if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  say "installing Node.js and npm (Debian)"
  apt-get update -qq && apt-get install -y -qq nodejs npm
fi
node_major=$(node -p 'process.versions.node.split(".")[0]')
if [ "$node_major" -lt 18 ]; then
  echo "setup.sh: Node.js >= 18 is needed (found $(node --version))" >&2
  exit 1
fi

if [ -x /usr/bin/chromium ]; then
  say "chromium present"
else
  say "installing Debian's chromium (apt) for the browser end-to-end test"
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium
fi

# npm ci only when node_modules does not hold exactly what package-lock.json lists.
npm_in_sync() {
  node -e '
    const fs = require("fs");
    const want = JSON.parse(fs.readFileSync("package-lock.json", "utf8")).packages;
    const have = JSON.parse(fs.readFileSync("node_modules/.package-lock.json", "utf8")).packages;
    for (const [k, v] of Object.entries(want)) {
      if (k && (!have[k] || have[k].version !== v.version)) process.exit(1);
    }' 2>/dev/null
}
if npm_in_sync; then
  say "npm dev dependencies present"
else
  say "installing npm dev dependencies (npm ci)"
  npm ci --no-audit --no-fund --loglevel=error
fi
# cargo-fuzz for the fuzz smoke run in scripts/test.sh; only where a nightly toolchain is installed.
CARGO_FUZZ_VERSION=0.13.1
if cargo +nightly --version >/dev/null 2>&1; then
  if [ "$(cargo +nightly fuzz --version 2>/dev/null | awk '{print $2}')" = "$CARGO_FUZZ_VERSION" ]; then
    say "cargo-fuzz $CARGO_FUZZ_VERSION present"
  else
    say "installing cargo-fuzz $CARGO_FUZZ_VERSION (nightly is installed; a few minutes)"
    cargo install cargo-fuzz --version "$CARGO_FUZZ_VERSION" --locked
  fi
fi
say "done"
