#!/usr/bin/env bash
# Builds everything (C and lssview's C++) with clang under AddressSanitizer + UBSan (and the libFuzzer targets),
# runs the whole ctest suite in that build (OpenCL tests included, on the default
# device), then fuzzes the LSQT parser, the LSS reader and the --wi-file parser for
# SECONDS in all (default 60), starting from the seed corpora.
set -euo pipefail
cd "$(dirname "$0")/../.."
BUDGET=${1:-60}
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DLSQT_FUZZ=ON -DLSQT_SANITIZE=ON \
  -DLSQT_WERROR=ON >/dev/null
cmake --build build-fuzz -j "$(nproc)"
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
(cd build-fuzz && ctest --output-on-failure -j 2) || { bash tools/ctest_tail.sh build-fuzz; exit 8; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/lsqt" "$work/lss" "$work/wi"
cp tools/fuzz/corpus/* "$work/lsqt/"
cp tools/fuzz/corpus_wi/* "$work/wi/"
# A real LSS as the reader's seed (the release build from tools/test.sh writes it).
if [ -x build/lsqt-cl ]; then
  build/lsqt-cl -q -R -p 256 -wo 4 -wi 16 --lss "$work/lss/seed.lss" -o "$work/seed.raw" \
    examples/tutorial/Lambertian.lsqt || true
fi
for target in lsqt lss wi; do
  echo "fuzzing $target for $((BUDGET / 3)) s"
  if ! ./build-fuzz/fuzz_$target -max_total_time=$((BUDGET / 3)) -print_final_stats=1 \
      -artifact_prefix="$work/" "$work/$target" >"$work/$target.log" 2>&1; then
    tail -n 40 "$work/$target.log"
    echo "fuzz_$target found a crash" >&2
    exit 1
  fi
  grep -E "stat::number_of_executed_units|stat::new_units_added" "$work/$target.log"
done
