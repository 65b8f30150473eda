#!/usr/bin/env bash
# Builds the sanitizer and fuzzing variants with clang, runs the parser unit tests under
# ASan+UBSan, then fuzzes the LSQT parser for SECONDS (default 60) from the seed corpus.
set -euo pipefail
cd "$(dirname "$0")/../.."
SECONDS_BUDGET=${1:-60}
CC=clang cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DLSQT_FUZZ=ON -DLSQT_SANITIZE=ON \
  -DLSQT_WERROR=ON >/dev/null
cmake --build build-fuzz -j "$(nproc)" --target fuzz_lsqt test_lsqt
UBSAN_OPTIONS=halt_on_error=1 ./build-fuzz/tests/test_lsqt
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp tools/fuzz/corpus/* "$work/"
./build-fuzz/fuzz_lsqt -max_total_time="$SECONDS_BUDGET" -print_final_stats=1 "$work" 2>&1 | tail -n 5
