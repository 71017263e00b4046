#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, and runs every test —
# the Release build's full CTest suite, the unit tests again under AddressSanitizer +
# UndefinedBehaviorSanitizer (clang's build-fuzz/, failing on any report), every libFuzzer harness
# for a bounded time from that build (tests/fuzz/run.sh), the browser tests in Debian's Chromium, and the
# container smoke test (podman). ROVERPLAN_SKIP_CONTAINER=1 skips the
# last one for quick local runs; CI runs everything.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
# ccache keyed on paths relative to the checkout, so every clone on a machine shares one cache.
export CCACHE_BASEDIR="$root" CCACHE_NOHASHDIR=1

bash docker/install-deps.sh
bash docker/setup-web.sh web tests/browser tests/contract tests/mcap
jobs=$(nproc)
# Each stage prints the seconds since the start, so a slow CI run says where its time went.
start=$SECONDS
stage() { echo "== [$((SECONDS - start)) s] $*"; }

stage "Release build (build/)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
ninja -C build
stage "Tests (Release)"
ctest --test-dir build --output-on-failure -j "$jobs"

# One sanitized build serves two stages: clang with ASan + UBSan and libFuzzer's coverage
# instrumentation (build-fuzz/, as tests/fuzz/run.sh configures it) makes the unit-test binaries,
# run here under the sanitizers, and then the fuzz harnesses link against the same libraries. (Two
# separate builds, GCC's ASan and clang's fuzzing, were half of a fresh machine's test time.)
# The script tests that start the roverplan binary (label "binary": serve-restart, disk-full, exports,
# study-launcher, contract-lint) run in the Release pass only: this build makes the unit-test
# binaries, not roverplan. -gline-tables-only: what a sanitizer's stack trace shows, at about half
# the compile time of -g.
stage "Sanitizer build (build-fuzz/: clang, ASan + UBSan, fuzzer instrumentation)"
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DROVER_FUZZ=ON \
  -DROVER_WERROR=OFF -DCMAKE_CXX_FLAGS_DEBUG="-O1 -gline-tables-only" >/dev/null
ninja -C build-fuzz test_core test_maps test_server
stage "Unit tests under sanitizers"
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir build-fuzz --output-on-failure -j "$jobs" -R '^(core|maps|server)/' -LE binary

stage "Fuzzing (libFuzzer, ${ROVERPLAN_FUZZ_SECONDS:-30} s per target)"
bash tests/fuzz/run.sh "${ROVERPLAN_FUZZ_SECONDS:-30}"

stage "Browser tests (Chromium via playwright-core)"
ROVERPLAN_BIN="$root/build/bin/roverplan" node --test tests/browser/

if [ "${ROVERPLAN_SKIP_CONTAINER:-0}" != 1 ]; then
  stage "Container smoke test (podman)"
  bash tests/container/smoke_test.sh
fi
stage "all tests passed"
