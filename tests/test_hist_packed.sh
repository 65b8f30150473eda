#!/usr/bin/env bash
# Packed histograms (docs/architecture.md, "Paths and estimators", on bands): a run of
# many bands holds its exit histograms packed, and a CPU device's buffer holds a batch of
# them only while a launch adds to it. The bytes must be those of the dense histograms
# (LSQT_PACK_HIST=0) on every way through the engine: an RRSS pilot and its run, spread
# directions, several launches, both sides, double, the GPU code path, a continued LSS, a
# target error, shards and their merge.
# usage: test_hist_packed.sh LSQT_CL rss|no-rss (no-rss: the sanitizer build, whose
# shadow memory and quarantine are not the program's)
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN RSS -- "$@"
cli_workdir

printf 'Medium\nLayer z=0 LambertianBsdf fR=0.6,0.5,0.4 fT=0.1,0.2,0.1\nMedium\n' >x.lsqt
W=(--wavelengths 450,550,650 -wo 4 -wi 16 -s 3 -q)
same() { # same NAME: the dense (d.*) and packed (p.*) files are byte for byte equal
  local f bad=0
  for f in d.*; do cmp -s "$f" "p.${f#d.}" || { bad=1; echo "differs: $f"; }; done
  [ "$bad" = 0 ] && [ -n "$(ls d.* 2>/dev/null)" ] && ok || bad "$1: the packed histograms' files differ from the dense ones"
  rm -f d.* p.*
}
both() { # both ARGS...: the run dense and packed
  LSQT_PACK_HIST=0 "$BIN" "$@" -o d.raw --lss d.lss || bad "dense run: $*"
  LSQT_PACK_HIST=1 "$BIN" "$@" -o p.raw --lss p.lss || bad "packed run: $*"
}

both "${W[@]}" -p 3000 x.lsqt
same "RRSS pilot and run"
# 40 chunks over 32 batches: the first launch (8 chunks) and the next both reach batches
# 0 to 7, so what one launch packed the next unpacks and adds to
both "${W[@]}" -p 10240 --wi-spread x.lsqt
same "spread directions, every batch reached"
both "${W[@]}" -p 2000 --from-below x.lsqt
same "both sides"
both "${W[@]}" -p 2000 --double x.lsqt
same "double"
LSQT_GPU_PATH=1 both "${W[@]}" -p 2000 x.lsqt
same "the GPU code path"
# a continued LSS: dense and packed continue their own first part
both "${W[@]}" -p 2000 x.lsqt
LSQT_PACK_HIST=0 "$BIN" "${W[@]}" -p 3000 x.lsqt -o d.raw --lss d.lss || bad "dense continued"
LSQT_PACK_HIST=1 "$BIN" "${W[@]}" -p 3000 x.lsqt -o p.raw --lss p.lss || bad "packed continued"
same "continued"
both "${W[@]}" -p 100000 --target-error 0.2 --wi-spread x.lsqt
same "target error"
# shards run packed and merged packed against one dense run
LSQT_PACK_HIST=0 "$BIN" "${W[@]}" -p 3000 --wi-spread x.lsqt -o d.raw --lss d.lss || bad "dense whole run"
for k in 0 1 2; do
  LSQT_PACK_HIST=1 "$BIN" "${W[@]}" -p 3000 --wi-spread x.lsqt --lss sh.lss --shard $k/3 || bad "packed shard $k"
done
LSQT_PACK_HIST=1 "$BIN" merge -q p.lss sh.shard-{0,1,2}-of-3.lss -o p.raw || bad "packed merge"
same "shards merged"

# The bound: 200 bands of the default grid at 10^4 paths a slice (every batch reached, the
# histograms' pages all touched: 1.3 GB dense) peak at most at twice the LSS plus 300 MB
# (ru_maxrss of the run; the LSS is 148 MB).
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n' >lam.lsqt
if [ "$RSS" = no-rss ]; then
  echo "skip: the memory bound (a sanitizer build)"
else
  python3 - "$BIN" <<'PY' && ok || bad "the memory bound of a 200-band run"
import os, subprocess, sys
cmd = [sys.argv[1], "lam.lsqt", "--wavelengths", "400:2390:10", "-p", "10000", "--no-raw", "-q", "-s", "0"]
p = subprocess.Popen(cmd)
_, status, ru = os.wait4(p.pid, 0)
if os.waitstatus_to_exitcode(status) != 0: sys.exit("the run failed")
peak, lss = ru.ru_maxrss / 1024, os.path.getsize("lam.lsqt.lss") / 2**20
print("peak %.0f MB, LSS %.0f MB, bound %.0f MB" % (peak, lss, 2 * lss + 300))
if peak > 2 * lss + 300: sys.exit("peak %.0f MB above the bound" % peak)
PY
fi

finish test_hist_packed.sh
