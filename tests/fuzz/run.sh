#!/usr/bin/env bash
# Builds the libFuzzer harnesses with clang (build-fuzz/) and runs each for a bounded time.
#   tests/fuzz/run.sh [SECONDS_PER_TARGET=30] [TARGET...]
# Each target starts from its seed corpus (tests/fuzz/corpus/NAME/, read only: new inputs go to a
# scratch copy). A crash leaves its input in build-fuzz/crashes/NAME/ and fails the run; turn it into
# a regression test (a unit test, and a file in the seed corpus). The seed is explicit
# (ROVER_FUZZ_SEED, default 1) so a run can be repeated; other seeds explore other inputs.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
secs=${1:-30}
seed=${ROVER_FUZZ_SEED:-1}
shift || true
export CCACHE_BASEDIR="$root" CCACHE_NOHASHDIR=1
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DROVER_FUZZ=ON \
  -DROVER_WERROR=OFF -DCMAKE_CXX_FLAGS_DEBUG="-O1 -gline-tables-only" >/dev/null
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  shopt -s nullglob
  for f in tests/fuzz/fuzz_*.cpp; do targets+=("$(basename "$f" .cpp)"); done
  if [ ${#targets[@]} -eq 0 ]; then echo "fuzz: no harnesses"; exit 0; fi
fi
ninja -C build-fuzz "${targets[@]}"
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
status=0
for t in "${targets[@]}"; do
  name=${t#fuzz_}
  work=build-fuzz/corpus/$name crashes=build-fuzz/crashes/$name
  rm -rf "$work"; mkdir -p "$work" "$crashes"
  seeds=tests/fuzz/corpus/$name
  dict=(); [ -f "tests/fuzz/$name.dict" ] && dict=(-dict="tests/fuzz/$name.dict")
  echo "== fuzz $t for ${secs}s, seed $seed"
  if ! build-fuzz/bin/"$t" "$work" $( [ -d "$seeds" ] && echo "$seeds" ) "${dict[@]}" \
       -max_total_time="$secs" -seed="$seed" -rss_limit_mb=2048 -timeout=10 -artifact_prefix="$crashes/" \
       -print_final_stats=1 2>build-fuzz/"$t".log; then
    echo "FAIL: $t found a crash (input in $crashes/)"; tail -40 build-fuzz/"$t".log; status=1
  fi
  grep -E '^stat::number_of_executed_units|^stat::peak_rss_mb' build-fuzz/"$t".log | sed "s/^/  $t /" || true
done
exit $status
