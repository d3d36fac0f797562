#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) with clang, ASan and UBSan, replays
# every committed regression input, then fuzzes each target for a bounded time.
#
#   scripts/fuzz.sh [SECONDS]     total fuzzing time, split over the targets (60)
#
# A crash fails the script after every target has run (one target's crash does
# not hide another's); libFuzzer leaves the input as crash-* in the build
# folder: add it under tests/fuzz/regressions/<target>/ with the fix.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds="${1:-60}"
build="${DACPO_FUZZ_BUILD_DIR:-$root/build-fuzz}"
command -v clang >/dev/null && command -v clang++ >/dev/null ||
  { echo "fuzz: clang not found (scripts/install_deps.sh installs it)" >&2; exit 1; }

CC=clang CXX=clang++ cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DDACPO_BUILD_FUZZERS=ON -DDACPO_BUILD_TESTS=OFF -DDACPO_BUILD_SAMPLES=OFF \
  -DDACPO_BUILD_TOOLS=OFF -DDACPO_BUILD_PYTHON=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target fuzz_orient fuzz_file_checks fuzz_units fuzz_point_files >/dev/null

targets=(file_checks orient units point_files)
per=$((seconds / ${#targets[@]}))
[ "$per" -ge 1 ] || per=1
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
failed=()
for t in "${targets[@]}"; do
  bin="$build/tests/fuzz/fuzz_$t"
  regressions="$root/tests/fuzz/regressions/$t"
  if [ -d "$regressions" ] && [ -n "$(ls -A "$regressions")" ]; then
    "$bin" "$regressions"/* >"$build/fuzz_$t.regressions.log" 2>&1 ||
      { tail -40 "$build/fuzz_$t.regressions.log" >&2; echo "fuzz: $t regression input fails" >&2
        failed+=("$t (regression)"); continue; }
  fi
  corpus="$build/corpus/$t"
  mkdir -p "$corpus"
  (cd "$build" && "$bin" -max_total_time="$per" -timeout=30 -rss_limit_mb=2048 \
      -print_final_stats=1 "$corpus" "$root/tests/fuzz/corpus/$t" >"$build/fuzz_$t.log" 2>&1) ||
    { tail -60 "$build/fuzz_$t.log" >&2; echo "fuzz: $t found a crash (input in $build)" >&2
      failed+=("$t"); continue; }
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$build/fuzz_$t.log" | tail -1)
  echo "fuzz: $t: ${runs:-?} inputs in ${per} s, no crash"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: FAILED: ${failed[*]}" >&2
  exit 1
fi
