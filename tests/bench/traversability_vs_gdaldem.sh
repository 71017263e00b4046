#!/usr/bin/env bash
# Benchmark (issue: terrain layers): `roverplan traversability` against `gdaldem slope` on the same
# 8192×8192 float32 GeoTIFF, each timed as a whole process (read, compute, write), one run side by
# side; prints wall times, the ratio, and peak memory against the raster's float32 size.
#   tests/bench/traversability_vs_gdaldem.sh [SIZE] [ROVERPLAN]
set -euo pipefail
size=${1:-8192}
root=$(cd "$(dirname "$0")/../.." && pwd)
roverplan=${2:-$root/build/bin/roverplan}
command -v gdaldem >/dev/null || { echo "gdaldem not found (Debian gdal-bin)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "/usr/bin/time not found (Debian time)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "generating a ${size}x${size} float32 GeoTIFF (mars preset, 0.25 m)..."
"$roverplan" terrain --preset mars --size "$size" --cell 0.25 --seed 1 --out "$work/dem.tif" >/dev/null
raster_mib=$(( size * size * 4 / 1048576 ))

measure() {  # prints "seconds peak_kib"
  /usr/bin/time -f '%e %M' -o "$work/t" "$@" >/dev/null 2>&1
  cat "$work/t"
}
read -r ours_s ours_kib < <(measure "$roverplan" traversability "$work/dem.tif" --out "$work/classes.tif" --json)
read -r gdal_s gdal_kib < <(measure gdaldem slope -q "$work/dem.tif" "$work/slope.tif")

awk -v o="$ours_s" -v g="$gdal_s" -v ok="$ours_kib" -v gk="$gdal_kib" -v mib="$raster_mib" -v n="$size" 'BEGIN {
  printf "raster            %dx%d float32 = %d MiB\n", n, n, mib
  printf "%-34s %8s %12s\n", "command", "wall s", "peak MiB"
  printf "%-34s %8.2f %12.0f\n", "roverplan traversability --out", o, ok / 1024
  printf "%-34s %8.2f %12.0f\n", "gdaldem slope", g, gk / 1024
  printf "speed ratio gdaldem/roverplan  x%.2f (>= 1 means roverplan is at least as fast)\n", g / o
  printf "peak memory / raster size      %.2f (target <= 4)\n", ok / 1024 / mib
}'
