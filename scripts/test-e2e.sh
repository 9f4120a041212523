#!/usr/bin/env bash
# End-to-end test of the demo page (www/) in Debian's headless Chromium through playwright-core
# (tests/e2e/): uploads two scans with a known transform, aligns, checks #result; a malformed file
# and too few points show #error; the view is not blank; a georeferenced LAZ survey aligns onto a
# moved copy of itself in map-grid coordinates as the package does in Node, and downloads in
# doubles; a scan in metres aligns onto one in millimetres once the units are said; a 1M-point
# pair loads, fits and aligns
# with no main-thread task over 200 ms. Builds pkg/ first when it is missing or older than the
# sources (scripts/test.sh runs scripts/test-wasm.sh, which has just built it).
# Screenshots: target/e2e/demo.png, example.png, survey.png, big-1400x860.png, big-390x844.png.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
if [ ! -f pkg/arps_bg.wasm ] || [ ! -f pkg/worker-client.js ] ||
  [ -n "$(find src js models Cargo.toml Cargo.lock -newer pkg/arps_bg.wasm -print -quit)" ]; then
  scripts/build-pkg.sh
fi
node --test --test-reporter=spec tests/e2e/
