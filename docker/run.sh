#!/usr/bin/env bash
# The README's run command: installs what is missing, builds (Release) and starts the planning
# server on the bundled default map (synthetic Mars, 600×600 cells of 0.25 m, generated into the
# data dir on first start; nothing generated is committed). It prints the URL; Ctrl-C stops it.
# Extra arguments go to `roverplan serve` (e.g. --port 9000 --token T).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
# ccache keyed on paths relative to the checkout, so every clone on a machine shares one cache.
export CCACHE_BASEDIR="$root" CCACHE_NOHASHDIR=1
bash docker/install-deps.sh
bash docker/setup-web.sh web
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
ninja -C build roverplan
exec build/bin/roverplan serve --data "${ROVERPLAN_DATA:-$root/roverplan-data}" --web "$root/web" "$@"
