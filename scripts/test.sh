#!/usr/bin/env bash
# Runs every test: native (unit, integration, CLI), the wasm32 build of the core, and (once set up)
# the wasm tests in headless Node, the browser end-to-end test, and the consumer test of the packed
# npm package (scripts/test-consumer.sh). Installs what it needs first.
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
cargo clippy --quiet --all-targets --features train,ts -- -D warnings
# the API docs, trainer and binaries included: no broken links
RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps --features train,cli,ts

# `ts` adds the TypeScript generation of the JS/JSON contract: tests/contract.rs fails when the
# committed js/arps-contract.d.ts differs from what the Rust types generate (scripts/gen-types.sh).
step "native tests (cargo test --features train,ts)"
cargo test --features train,ts

step "PyTorch trainer tests (trainer/tests; where torch is installed)"
if python3 -c "import torch, numpy, safetensors, pytest" 2>/dev/null; then
  # the flow tests run the arps-train that `cargo test` just built (they skip, and say so,
  # when there is none)
  rc=0
  (cd trainer && ARPS_TRAIN_BIN="${ARPS_TRAIN_BIN:-$PWD/../target/debug/arps-train}" python3 -m pytest -q -rs tests) || rc=$?
  if [ "$rc" -eq 5 ]; then
    echo "SKIPPED: no trainer tests were collected"
  elif [ "$rc" -ne 0 ]; then
    exit "$rc"
  fi
else
  echo "SKIPPED: trainer Python tests (torch, numpy, safetensors or pytest not importable; pip install -r trainer/requirements.txt)"
fi

step "core builds for wasm32 (no cli, no trainer)"
cargo build --quiet --lib --target wasm32-unknown-unknown --release

step "fuzz smoke: each target for a few seconds (only where nightly Rust and cargo-fuzz are installed)"
if cargo +nightly --version >/dev/null 2>&1 && cargo +nightly fuzz --version >/dev/null 2>&1; then
  (
    cd fuzz
    # (arps itself is built with debug assertions and overflow checks: fuzz/Cargo.toml)
    for target in read_point_cloud read_e57 read_mesh read_gltf transform_ply transform_las transform_file transform_e57 weights_from_bytes options_json model_config register_clouds; do
      mkdir -p "corpus/$target"
      cargo +nightly fuzz run -O "$target" "corpus/$target" "seeds/$target" -- \
        -max_total_time="${FUZZ_SMOKE_SECONDS:-5}" -max_len=8192 -malloc_limit_mb=256
    done
  )
else
  echo "skipped: no nightly toolchain or no cargo-fuzz (scripts/setup.sh installs cargo-fuzz where nightly exists)"
fi

for extra in scripts/test-wasm.sh scripts/test-e2e.sh scripts/test-consumer.sh; do
  if [ -x "$extra" ]; then
    step "$extra"
    "$extra"
  fi
done
