#!/usr/bin/env bash
# The README's run command: installs what is missing, builds (Release) and runs roverplan on the
# bundled default map — synthetic Mars terrain, 600×600 cells of 0.25 m, generated on first run into
# build/ (generated data is never committed). Until the server lands it prints the map's
# traversability and a coverage plan on it; extra arguments go to `roverplan coverage`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
bash docker/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
ninja -C build roverplan
map=build/default-map.tif
if [ ! -f "$map" ]; then
  build/bin/roverplan terrain --preset mars --size 600 --cell 0.25 --seed 1 --out "$map"
fi
echo "== default map: $map"
build/bin/roverplan traversability "$map"
echo
echo "== roverplan coverage --dem $map (2 rovers, spiral + frontier, every reachable 1 m cell) $*"
build/bin/roverplan coverage --dem "$map" --coverage-cell 1 --rovers 2 --frontier --coverage 1 "$@"
