#!/usr/bin/env bash
# Consumer test of the npm package (tests/consumer/consumer.test.mjs): packs pkg/ with `npm pack`,
# installs the tarball into a fresh app in a temp dir, checks the tarball's content and
# `npm publish --dry-run`, type-checks TypeScript against it (ESM "bundler" and "NodeNext",
# CommonJS with esModuleInterop), runs the Node apps (ESM, CommonJS, the worker client) and the
# package's examples on the fixture pair, and builds the package's browser example with Vite and
# aligns the pair in headless Chromium through the worker. Uses only the package's public API.
# Builds pkg/ first when it is missing or older than its sources (scripts/test.sh runs
# scripts/test-wasm.sh, which has just built it). ARPS_CONSUMER_KEEP=1 keeps the temp app.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
if [ ! -f pkg/package.json ] || [ ! -f pkg/arps_bg.wasm ] ||
  [ -n "$(find src js models Cargo.toml Cargo.lock CHANGELOG.md LICENSE-MIT LICENSE-APACHE scripts/build-pkg.sh \
    -newer pkg/package.json -print -quit)" ]; then
  scripts/build-pkg.sh
fi
node --test --test-reporter=spec tests/consumer/
