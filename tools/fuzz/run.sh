#!/usr/bin/env bash
# Fuzzes the LSQT parser, the LSS reader and the --wi-file parser for SECONDS in all
# (default 30), under ASan+UBSan with libFuzzer (clang), starting from the seed corpora.
# Builds only the three fuzz targets, in build-fuzz/ (the sanitizer suite,
# tools/sanitize.sh, builds the rest of that directory).
set -euo pipefail
cd "$(dirname "$0")/../.."
BUDGET=${1:-30}
bash tools/sanitize.sh --configure
cmake --build build-fuzz -j "$(nproc)" --target fuzz_lsqt fuzz_lss fuzz_wi
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/lsqt" "$work/lss" "$work/wi"
cp tools/fuzz/corpus/* "$work/lsqt/"
cp tools/fuzz/corpus_wi/* "$work/wi/"
# A real LSS as the reader's seed (the release build, when there is one, writes it).
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
