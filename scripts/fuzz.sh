#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in build-fuzz/ and runs each for a
# bounded time, starting from the committed seed corpus in tests/fuzz/corpus/.
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET]     (default 60)
#
# Crashes are saved under build-fuzz/artifacts/ and make the script fail; each one becomes a
# regression test (a file in tests/fuzz/corpus/ and a case in the reader's unit tests).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SECONDS_PER_TARGET="${1:-60}"
BUILD="$ROOT/build-fuzz"
JOBS="${QM3D_JOBS:-$(nproc)}"
TARGETS=(fuzz_ply fuzz_mesh fuzz_pcd fuzz_metrics fuzz_grid fuzz_views)

CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DQM3D_BUILD_FUZZERS=ON -DQM3D_BUILD_TESTS=OFF -DQM3D_BUILD_BENCH=OFF >/dev/null
cmake --build "$BUILD" -j "$JOBS" --target "${TARGETS[@]}"

mkdir -p "$BUILD/artifacts"
export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export OMP_NUM_THREADS=1
status=0
for t in "${TARGETS[@]}"; do
  seeds="$ROOT/tests/fuzz/corpus/${t#fuzz_}"
  work="$BUILD/corpus/${t#fuzz_}"
  mkdir -p "$work"
  echo "== $t: ${SECONDS_PER_TARGET}s from $seeds" >&2
  if ! "$BUILD/tests/fuzz/$t" "$work" "$seeds" -max_total_time="$SECONDS_PER_TARGET" \
      -timeout=20 -rss_limit_mb=2048 -max_len=4096 -print_final_stats=1 \
      -artifact_prefix="$BUILD/artifacts/$t-" 2> "$BUILD/$t.log"; then
    echo "$t FAILED: see $BUILD/$t.log and $BUILD/artifacts/" >&2
    tail -40 "$BUILD/$t.log" >&2
    status=1
  else
    grep -E "stat::number_of_executed_units|Done" "$BUILD/$t.log" | tail -2 >&2 || true
  fi
done
exit $status
