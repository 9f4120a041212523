#!/usr/bin/env bash
# Writes js/arps-contract.d.ts, the TypeScript declarations of the JS/JSON contract, from the Rust
# types (arps::contract::typescript, cargo feature `ts`). Run it after changing an option or
# result type or its docs, and commit the file; tests/contract.rs (scripts/test.sh) fails while it
# is stale. scripts/build-pkg.sh puts the file into pkg/arps.d.ts (via src/wasm.rs).
set -euo pipefail
cd "$(dirname "$0")/.."
ARPS_WRITE_TYPES=1 cargo test --quiet --features ts --test contract generated_typescript_is_current
echo "gen-types: wrote js/arps-contract.d.ts"
