#!/usr/bin/env bash
# Runs every test: native (unit, integration, CLI), the wasm32 build of the core, and (once set up)
# the wasm tests in headless Node and the browser end-to-end test. Installs what it needs first.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n== %s\n' "$*"; }

if [ -x scripts/setup.sh ]; then
  step "set-up"
  scripts/setup.sh
else
  rustup target add wasm32-unknown-unknown >/dev/null
fi

step "format and lints"
cargo fmt --check
cargo clippy --quiet --all-targets --features train -- -D warnings

step "native tests (cargo test --features train)"
cargo test --features train

step "core builds for wasm32 (no cli, no trainer)"
cargo build --quiet --lib --target wasm32-unknown-unknown --release

for extra in scripts/test-wasm.sh scripts/test-e2e.sh; do
  if [ -x "$extra" ]; then
    step "$extra"
    "$extra"
  fi
done
