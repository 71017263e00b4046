#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, and runs every test —
# the Release build's full CTest suite, then the unit tests again under
# AddressSanitizer + UndefinedBehaviorSanitizer (a second build directory), failing on any report.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

bash docker/install-deps.sh
jobs=$(nproc)

echo "== Release build (build/)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
ninja -C build
echo "== Tests (Release)"
ctest --test-dir build --output-on-failure -j "$jobs"

echo "== Sanitizer build (build-asan/: ASan + UBSan)"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DROVER_SANITIZE=ON \
  -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" >/dev/null
ninja -C build-asan test_core test_server
echo "== Unit tests under sanitizers"
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir build-asan --output-on-failure -j "$jobs" -R '^(core|server)/'
