#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite with ctest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${DACPO_BUILD_DIR:-$root/build}"
"$root/scripts/build.sh" -DDACPO_BUILD_TESTS=ON "$@"
cd "$build"
ctest --output-on-failure -j "$(nproc)"
# A bounded fuzzing run (libFuzzer, ASan + UBSan): committed crash inputs are
# replayed, then 50 s of new inputs over the file checks and dacpo_orient.
"$root/scripts/fuzz.sh" "${DACPO_FUZZ_SECONDS:-50}"
