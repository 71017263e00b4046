#!/usr/bin/env bash
# Installs every Debian package the build and the tests need. Idempotent: when all are present it
# does nothing (no apt-get update, no network). Used by the README's commands, CI and the Dockerfile.
#   install-deps.sh            build + test packages
#   install-deps.sh --build    only what building roverplan needs (the container's build stage)
#   install-deps.sh --runtime  only what the roverplan binary needs at run time (container image)
#   install-deps.sh --bench    the benchmark tools (wrk, nginx)
set -euo pipefail

build_pkgs=(
  g++ make cmake ninja-build ccache pkg-config git ca-certificates
  libeigen3-dev libompl-dev
  # Debian's libompl-dev needs these Boost components for its CMake config to resolve.
  libboost-dev libboost-system-dev libboost-serialization-dev libboost-filesystem-dev
  libboost-program-options-dev
  nlohmann-json3-dev libgdal-dev libsqlite3-dev doctest-dev
  libssl-dev   # SHA-256 of a map's grid (maps/dem_digest)
  libopenmpi-dev openmpi-bin   # `mpirun -np N roverplan study run` (server/studies/study_mpi.cpp)
  libzstd-dev zlib1g-dev   # MCAP replays: zstd chunks and CRC-32 (server/exports/mcap_writer.cpp)
  libdeflate-dev   # PNG tiles and layers: deflate, CRC-32, Adler-32 (maps/png_encode.cpp)
)
test_pkgs=(
  gdal-bin   # gdaldem/gdalinfo/ogrinfo: reference outputs the tests compare against
  time       # /usr/bin/time: peak memory in the benchmark scripts
  chromium   # the browser tests drive Debian's Chromium through playwright-core
  curl python3
  clang libclang-rt-14-dev   # libFuzzer harnesses (tests/fuzz/run.sh)
  bubblewrap   # the import jail the server parses uploads in (server/jail/import_jail.hpp)
  stress-ng    # CPU load for tests/server/hostile_ws_under_load.sh (the hostile WebSocket tests, 20 runs)
)
# curl: HEALTHCHECK; bubblewrap: the import jail (without it imports run with rlimits only, and
# netCDF-4 is refused; `serve` says which at start).
runtime_pkgs=(libompl16 libgdal32 libsqlite3-0 libssl3 libopenmpi3 libzstd1 zlib1g libdeflate0 gdal-data curl ca-certificates bubblewrap)
bench_pkgs=(wrk nginx-light time curl)  # tests/bench/*: load generator and the nginx baseline

mode=${1:-all}
case "$mode" in
  all) want=("${build_pkgs[@]}" "${test_pkgs[@]}") ;;
  --build) want=("${build_pkgs[@]}") ;;
  --runtime) want=("${runtime_pkgs[@]}") ;;
  --bench) want=("${bench_pkgs[@]}") ;;
  *) echo "install-deps.sh: unknown option '$mode' (use --build, --runtime, --bench or nothing)" >&2; exit 2 ;;
esac

missing=()
for p in "${want[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
