#!/usr/bin/env bash
# After a failed ctest in BUILD_DIR: prints the last lines of each failed test's output,
# so that the end of a long CI log names what failed (a check's message, a sanitizer's
# report) even where the middle of the log is cut.
set -uo pipefail
dir=$1/Testing/Temporary
lines=${2:-25}
[ -f "$dir/LastTestsFailed.log" ] || exit 0
while IFS=: read -r _ name; do
  echo "=== the end of $name's output (from $dir/LastTest.log) ==="
  awk -v t="$name" '
    $0 ~ "^[0-9]+/[0-9]+ Test: " t "$" { on = 1; next }
    on && /^Output:/ { grab = 1; n = 0; next }
    grab && /^<end of output>/ { exit }
    grab { buf[n++ % L] = $0 }
    END { s = n > L ? n - L : 0; for (i = s; i < n; i++) print buf[i % L] }' L="$lines" "$dir/LastTest.log"
done <"$dir/LastTestsFailed.log"
