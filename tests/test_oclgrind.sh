#!/usr/bin/env bash
# test_oclgrind: the GPU code path (LSQT_GPU_PATH=1: vector width 2, work-groups of 64,
# one RNG block) on oclgrind's simulated OpenCL 1.2 device, with its memory checks (every
# out-of-bounds or unaligned access to global, local, constant or private memory; on by
# default), its data-race checks (--data-races: unsynchronised accesses of two work-items
# to one local or global location, atomics excepted) and its API checks (--check-api).
# Small runs of a slab, Rough and Substr (with their RRSS pilot: the candidate-walk
# kernel), a two-sided transmitting stack (--from-below), and Substr again with the
# next-event records' budget so small that launches are cut into parts (walk.cl), and three
# bands in one block (paint-rgb, double: byte-identical to PoCL's CPU path); then
# the CPU code path's slab, and its refusal on a device with too little local memory:
#   - oclgrind reports nothing (any "Invalid ...", "data race" or error line fails);
#   - in double the RAW is byte-identical to PoCL's CPU code path at the same vector
#     width (2): the tallies are integers, so work-group size, the RNG form and where the
#     estimates are summed change no bit, and oclgrind's double builtins round as PoCL's;
#   - in float every RAW value is within 3e-4 relative (+1e-7 absolute) of PoCL's: the
#     two implementations' float builtins (exp, log, sqrt) may round differently, and a
#     path that takes another branch on one rounding would move a value by far more.
# oclgrind's --uninitialized plugin is not used: on these kernels it crashes oclgrind
# 21.10 itself (a segmentation fault in the simulator, before the first kernel runs).
# usage: test_oclgrind.sh LSQT_CL EXAMPLES_DIR. Exit 77 (skipped) without oclgrind.
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
if ! command -v oclgrind >/dev/null; then
  echo "test_oclgrind: SKIPPED: oclgrind is not installed (bash tools/setup.sh installs it)"
  exit 77
fi
cli_workdir
cp "$EX/slab.lsqt" slab.lsqt
cp "$EX/tutorial/Rough.lsqt" Rough.lsqt
cp "$EX/tutorial/Substr.lsqt" Substr.lsqt
printf 'Medium\nLayer z=1 LambertianBsdf fR=0.3 fT=0.5\nMedium\nLayer z=0 LambertianBsdf fR=0.2 fT=0.6\nMedium\n' > two.lsqt

# compare.py A B TOL: every number of two RAWs (same lines) within TOL relative.
cat > compare.py <<'EOF'
import sys
a, b, tol = open(sys.argv[1]).read().split(), open(sys.argv[2]).read().split(), float(sys.argv[3])
if len(a) != len(b) or a[0] != b[0]:
    sys.exit("different RAW shapes: %d and %d words" % (len(a), len(b)))
worst = 0.0
for x, y in zip(a[2:], b[2:]):
    x, y = float(x), float(y)
    worst = max(worst, abs(x - y) / (abs(y) + 1e-3))
    if abs(x - y) > tol * abs(y) + 1e-7:
        sys.exit("%r and %r differ by more than %g relative" % (x, y, tol))
print("largest relative difference %.2e over %d numbers" % (worst, len(a) - 2))
EOF

# run NAME FILE FLAGS...: oclgrind on the GPU path, PoCL on the CPU path, float and double.
run() {
  local name=$1 file=$2
  shift 2
  for prec in float double; do
    local extra=()
    [ "$prec" = double ] && extra=(--double)
    if ! LSQT_GPU_PATH=1 timeout -k 5 600 oclgrind --data-races --check-api "$BIN" -R -q "$file" \
        -o "$name.$prec.og.raw" --lss "$name.$prec.og.lss" "${extra[@]}" "$@" > "$name.$prec.log" 2>&1; then
      bad "$name $prec: lsqt-cl under oclgrind failed: $(tail -5 "$name.$prec.log")"
      continue
    fi
    if grep -q -E -i 'invalid|data race|uninitiali|error|warning' "$name.$prec.log"; then
      bad "$name $prec: oclgrind reports: $(grep -m 5 -E -i 'invalid|data race|uninitiali|error|warning' "$name.$prec.log")"
    else
      ok
    fi
    if ! LSQT_GPU_PATH=0 LSQT_VECTOR_WIDTH=2 "$BIN" -R -q "$file" -o "$name.$prec.pocl.raw" --lss "$name.$prec.pocl.lss" \
        "${extra[@]}" "$@"; then
      bad "$name $prec: the PoCL run failed"
      continue
    fi
    for side in "" .below; do # --from-below writes OUT.below.raw beside OUT.raw
      local og=$name.$prec.og$side.raw pocl=$name.$prec.pocl$side.raw
      [ -n "$side" ] && [ ! -f "$pocl" ] && continue
      if [ "$prec" = double ]; then
        if cmp -s "$og" "$pocl"; then ok; else bad "$name double$side: the RAW differs from PoCL's"; fi
      else
        local out
        if out=$(python3 compare.py "$og" "$pocl" 3e-4); then
          ok
          echo "$name float$side: $out"
        else
          bad "$name float$side: $out"
        fi
      fi
    done
  done
}

run slab slab.lsqt -p 512 -wo 4 -wi 16 --wi-spread
run Rough Rough.lsqt -p 256 -wo 4 -wi 16
run Substr Substr.lsqt -p 256 -wo 4 -wi 16
run two two.lsqt -p 256 -wo 4 -wi 16 --wi-spread --from-below
# A record budget of 40 parts every launch (and grows the buffer for a path with more):
# the same bytes.
LSQT_NEE_RECORD_CAP=40 run Substr-parts Substr.lsqt -p 256 -wo 4 -wi 16 --wi-spread

# A band block on the GPU path (its per-band state in local memory, a slot a work-item;
# its spread records): nothing reported, and in double PoCL's CPU path's bytes in every band.
if LSQT_GPU_PATH=1 timeout -k 5 600 oclgrind --data-races --check-api "$BIN" -R -q "$EX/paint-rgb.lsqt" -p 256 -wo 4 \
    -wi 16 --wi-spread --double -o rgb.og.raw --lss rgb.og.lss > rgb.log 2>&1 &&
  LSQT_GPU_PATH=0 LSQT_VECTOR_WIDTH=2 "$BIN" -R -q "$EX/paint-rgb.lsqt" -p 256 -wo 4 -wi 16 --wi-spread --double \
    -o rgb.pocl.raw --lss rgb.pocl.lss; then
  if grep -q -E -i 'invalid|data race|uninitiali|error|warning' rgb.log; then
    bad "bands: oclgrind reports: $(grep -m 5 -E -i 'invalid|data race|uninitiali|error|warning' rgb.log)"
  else ok; fi
  for b in R G B; do
    if cmp -s "rgb.og.$b.raw" "rgb.pocl.$b.raw"; then ok; else bad "bands double: band $b's RAW differs from PoCL's CPU path"; fi
  done
else
  bad "bands: a run failed: $(tail -3 rgb.log)"
fi

# The CPU code path keeps each work-item's direction sums in the work-group's local
# memory (walk.cl's LSQT_ITEMS): under oclgrind's checks it reports nothing and gives
# PoCL's bytes (double) ...
if LSQT_GPU_PATH=0 timeout -k 5 300 oclgrind --data-races --check-api "$BIN" -R -q slab.lsqt -p 512 -wo 4 -wi 16 \
    --wi-spread --double -o cpu.og.raw --lss cpu.og.lss > cpu.log 2>&1 &&
  LSQT_GPU_PATH=0 "$BIN" -R -q slab.lsqt -p 512 -wo 4 -wi 16 --wi-spread --double -o cpu.pocl.raw --lss cpu.pocl.lss; then
  if grep -q -E -i 'invalid|data race|uninitiali|error|warning' cpu.log; then
    bad "CPU path: oclgrind reports: $(grep -m 5 -E -i 'invalid|data race|uninitiali|error|warning' cpu.log)"
  else ok; fi
  if cmp -s cpu.og.raw cpu.pocl.raw; then ok; else bad "CPU path double: the RAW differs from PoCL's"; fi
else
  bad "CPU path: a run failed: $(tail -3 cpu.log)"
fi
# ... and on a device with less local memory than those sums need (-wi 1024: 16 KB with the
# scalars' 4.2 KB) the run is refused before any work, naming the kernel, both sizes and
# the way out, and writes nothing.
LSQT_GPU_PATH=0 oclgrind --local-mem-size 8192 "$BIN" -R -q slab.lsqt -p 16 -wo 4 -wi 1024 --wi-spread \
  -o small.raw --lss small.lss > small.log 2>&1
rc=$?
if [ "$rc" = 1 ] && grep -q "lsqt_walk needs 16496 bytes of local memory and Oclgrind Simulator has 8192" small.log &&
  grep -q "LSQT_GPU_PATH=1" small.log && [ ! -e small.raw ] && [ ! -e small.lss ]; then
  ok
else
  bad "CPU path, 8 KB of local memory: exit $rc, $(cat small.log)"
fi
finish test_oclgrind
