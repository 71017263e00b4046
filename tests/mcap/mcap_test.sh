#!/usr/bin/env bash
# CTest entry of tests/mcap: runs replay.test.mjs with node against the built roverplan. Skipped
# (77) when node or the pinned npm packages are missing (bash docker/setup-web.sh tests/mcap, which
# tests/run.sh runs). Usage: mcap_test.sh path/to/roverplan
set -u
BIN=$1
HERE=$(cd "$(dirname "$0")" && pwd)
command -v node >/dev/null 2>&1 && [ -d "$HERE/node_modules/@mcap/core" ] && [ -d "$HERE/node_modules/fzstd" ] ||
  { echo "skipped: run bash docker/setup-web.sh tests/mcap"; exit 77; }
ROVERPLAN_BIN=$BIN exec node --test "$HERE/replay.test.mjs"
