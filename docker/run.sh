#!/usr/bin/env bash
# The README's run command: installs what is missing, builds (Release) and runs roverplan.
# For now it runs a coverage demo on the default 60×60 world and prints the result; extra
# arguments are passed to `roverplan coverage`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
bash docker/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
ninja -C build roverplan
echo "== roverplan coverage (spiral, paper 002) $*"
build/bin/roverplan coverage "$@"
echo
echo "== roverplan coverage --frontier --coverage 1 (ours: every reachable cell) $*"
build/bin/roverplan coverage --frontier --coverage 1 "$@"
