#!/usr/bin/env bash
# The demo page: installs what the build needs (scripts/setup.sh), builds the npm package into pkg/
# (scripts/build-pkg.sh; skipped when pkg/ is newer than every source, unless --rebuild), then
# serves the repository on 127.0.0.1 and prints the page's URL (www/). Ctrl-C stops the server.
# Any static server of the repository root does the same: the page needs no special headers.
# Usage: scripts/demo.sh [--rebuild] [--port N]     (port default 8080, or $PORT)
set -euo pipefail
cd "$(dirname "$0")/.."

rebuild=0
port=${PORT:-8080}
while [ $# -gt 0 ]; do
  case "$1" in
    --rebuild) rebuild=1 ;;
    --port) port=$2; shift ;;
    *) echo "usage: scripts/demo.sh [--rebuild] [--port N]" >&2; exit 2 ;;
  esac
  shift
done

scripts/setup.sh
if [ "$rebuild" = 1 ] || [ ! -f pkg/arps_bg.wasm ] || [ ! -f pkg/worker-client.js ] ||
  [ -n "$(find src js models Cargo.toml Cargo.lock -newer pkg/arps_bg.wasm -print -quit)" ]; then
  scripts/build-pkg.sh
else
  echo "demo: pkg/ is up to date (scripts/demo.sh --rebuild forces a build)"
fi
exec node scripts/serve.mjs --port "$port"
