#!/usr/bin/env bash
# Paths per second of lsqt-cl on the examples (default device, or pass -d ...).
# usage: tools/bench.sh [PATHS] [lsqt-cl options...]; prints one line per example.
set -euo pipefail
cd "$(dirname "$0")/.."
P=${1:-1e6}
shift || true
BIN=./build/lsqt-cl
[ -x "$BIN" ] || bash tools/build.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# efficiency = 1 / (max rel err^2 * seconds): how fast error falls; higher is better.
printf "%-34s %10s %12s %10s %12s %12s\n" example paths/slice "paths/s" seconds "max rel err" efficiency
for ex in examples/tutorial/Lambertian.lsqt examples/tutorial/Dust.lsqt examples/slab.lsqt examples/two-lambertian.lsqt; do
  "$BIN" -q -R -p "$P" --lss "$work/b.lss" -o "$work/b.raw" --json "$work/b.json" "$@" "$ex"
  python3 - "$ex" "$P" "$work/b.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
err = max(s["max_rel_err"] for s in j["slices"])
eff = 1.0 / (err * err * j["seconds"]) if err > 0 and j["seconds"] > 0 else float("inf")
print("%-34s %10s %12.4g %10.3f %12.3g %12.4g" % (sys.argv[1], sys.argv[2], j["paths_per_second"], j["seconds"], err, eff))
PY
done
