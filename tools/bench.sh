#!/usr/bin/env bash
# Paths per second of lsqt-cl on the examples (default device, or pass -d ...), with
# wall and CPU seconds (user + sys: the machine is shared, so CPU time is the fair
# measure) and the efficiency 1 / (max rel err^2 * s).
# usage: tools/bench.sh [PATHS] [lsqt-cl options...]; prints one line per example.
#        tools/bench.sh micro [lsqt-cl options...]: the microsurface examples at the issue's
#        settings (-p 1e4; Rough -wi 320, Substr -wi 600), multiple scattering on and off.
#        tools/bench.sh phases [PATHS] [lsqt-cl options...]: a slab of optical thickness 1
#        between null layers with each phase function (default -p 1e6), and the slab over
#        a Lambertian and an Oren-Nayar floor.
#        tools/bench.sh lssview [lsqt-cl options...]: wall and CPU seconds of a 512x512 lssview
#        render (PNG, the default lights) of LSS files of the tutorial (-p 1e4, default -wo/-wi
#        unless given), the best of 3.
#        tools/bench.sh targets [--csv PATH] [--doc] [-- lsqt-cl options...]: the four speed
#        speed targets (tools/bench_targets.py): CPU-seconds, events per CPU-second; with
#        --doc it rewrites docs/performance.md (tools/bench_doc.py) when every workload ran
#        (on another device: tools/bench.sh targets --doc -- -d gpu).
#        tools/bench.sh study [--quick] [--doc] [--seeds N] [--out DIR] [-- lsqt-cl options...]:
#        the speed/accuracy study (tools/bench_study.py): error against a known answer
#        and CPU time over -p, float/double, iter_count, multiple scattering, -wi, -rp;
#        CSV and plots in build/study, or with --doc docs/speed-accuracy.md and its plots.
#        tools/bench.sh original ORIGINAL_BIN [--doc]: beside the original layered-sqt (built by
#        tools/original/build.sh DEST; tools/bench_original.py): CPU-s per path and error per
#        CPU-second on the tutorial and a slab; --doc adds its section to docs/speed-accuracy.md.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = targets ]; then
  shift
  if [ ! -x ./build/lsqt-cl ]; then
    # the page describes the build measured: --doc measures build/lsqt-cl as it is or not at all
    for a in "$@"; do
      [ "$a" = -- ] && break
      if [ "$a" = --doc ]; then
        echo "bench.sh targets --doc: build/lsqt-cl is missing: build it first (bash tools/build.sh)" >&2
        exit 1
      fi
    done
    bash tools/build.sh
  fi
  exec python3 tools/bench_targets.py ./build/lsqt-cl "$@"
fi
if [ "${1:-}" = study ]; then
  shift
  [ -x ./build/lsqt-cl ] || bash tools/build.sh
  exec /usr/bin/python3 tools/bench_study.py "$@"
fi
if [ "${1:-}" = original ]; then
  [ $# -ge 2 ] || { echo "usage: tools/bench.sh original ORIGINAL_BIN [--doc]" >&2; exit 2; }
  [ -x ./build/lsqt-cl ] || bash tools/build.sh
  exec python3 tools/bench_original.py "$2" ./build/lsqt-cl "${@:3}"
fi
P=${1:-1e6}
shift || true
MICRO=0 PHASES=0
if [ "$P" = micro ]; then MICRO=1; P=1e4; fi
if [ "$P" = phases ]; then
  PHASES=1 P=1e6
  if [[ ${1:-} =~ ^[0-9.e]+$ ]]; then P=$1; shift; fi
fi
BIN=./build/lsqt-cl
[ -x "$BIN" ] && [ -x ./build/lssview ] || bash tools/build.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [ "$P" = lssview ]; then
  printf "%-34s %9s %9s %9s\n" "lssview 512x512" n_wi wall_s cpu_s
  for ex in examples/tutorial/Lambertian.lsqt examples/tutorial/Silver.lsqt examples/tutorial/Substr.lsqt; do
    "$BIN" -q -R -p 1e4 --lss "$work/v.lss" -o "$work/v.raw" "$@" "$ex"
    best=""
    for _ in 1 2 3; do
      TIMEFORMAT='%R %U %S'
      { time ./build/lssview -q "$work/v.lss" -o "$work/v.png" ; } 2>"$work/t"
      read -r w u s < "$work/t"
      line=$(python3 -c "print('%.3f %.3f' % ($w, $u + $s))")
      if [ -z "$best" ] || python3 -c "import sys; sys.exit(0 if ${line% *} < ${best% *} else 1)"; then best=$line; fi
    done
    nwi=$(python3 - "$work/v.raw" <<'PY'
import sys
lines = open(sys.argv[1]).read().splitlines()[3:]
print(sum(1 for l in lines if l.split()[0] == "0") // 2)
PY
)
    printf "%-34s %9s %9s %9s\n" "$(basename "$ex") $*" "$nwi" ${best}
  done
  exit 0
fi
# wall_s: the simulation (launch loop); cpu_s: the whole process, user + sys
printf "%-34s %10s %12s %9s %9s %12s %12s\n" example paths/slice "paths/s" wall_s cpu_s "max rel err" efficiency
if [ "$MICRO" = 1 ]; then
  # "file|options": each also as a copy with use_multiple_scattering flipped off/on
  cases=()
  for c in "examples/tutorial/Rough.lsqt|-wi 320" "examples/tutorial/Substr.lsqt|-wi 600" \
           "examples/tutorial/Dusty.lsqt|" "examples/tutorial/Silver.lsqt|"; do
    f=${c%%|*} o=${c#*|} b=$(basename "$f" .lsqt)
    sed -E '/^(#|$)/d; s/use_multiple_scattering=[a-z]+//; s/^(Layer .*Microsurface[A-Za-z]*)/\1 use_multiple_scattering=true/' "$f" > "$work/$b-ms.lsqt"
    sed -E '/^(#|$)/d; s/use_multiple_scattering=[a-z]+//; s/^(Layer .*Microsurface[A-Za-z]*)/\1 use_multiple_scattering=false/' "$f" > "$work/$b-ss.lsqt"
    cases+=("$work/$b-ms.lsqt|$o" "$work/$b-ss.lsqt|$o")
  done
elif [ "$PHASES" = 1 ]; then
  cases=()
  slab() { printf 'Medium\nLayer z=1 NullBsdf\nMedium mus=1 %s\nLayer z=0 %s\nMedium\n' "$2" "$3" > "$work/$1.lsqt"
           cases+=("$work/$1.lsqt|"); }
  slab hg-0 "HenyeyGreensteinPhase g=0" NullBsdf
  slab hg-0.8 "HenyeyGreensteinPhase g=0.8" NullBsdf
  slab hg2 "HenyeyGreenstein2Phase g0=0.8 g1=-0.3 b=0.3" NullBsdf
  slab rayleigh "RayleighPhase rho=-0.5" NullBsdf
  slab sggx-specular "SggxPhase Apara=0.3 type=Specular" NullBsdf
  slab sggx-diffuse "SggxPhase Apara=0.3 type=Diffuse" NullBsdf
  slab hg-0-lambertian "HenyeyGreensteinPhase g=0" "LambertianBsdf fR=0.5"
  slab hg-0-oren-nayar "HenyeyGreensteinPhase g=0" "OrenNayarDiffuseBrdf fR=0.5 sigma=0.5"
else
  cases=()
  for f in examples/tutorial/Lambertian.lsqt examples/tutorial/Dust.lsqt examples/tutorial/Silver.lsqt \
           examples/slab.lsqt examples/two-lambertian.lsqt; do cases+=("$f|"); done
fi
for c in "${cases[@]}"; do
  ex=${c%%|*}
  read -r -a opts <<< "${c#*|}"
  name="$(basename "$ex") ${c#*|}"
  # a short run first, so the kernel build is not timed
  "$BIN" -q -R -p 1000 --lss "$work/b.lss" -o "$work/b.raw" "${opts[@]}" "$@" "$ex"
  TIMEFORMAT='%U %S'
  { time "$BIN" -q -R -p "$P" --lss "$work/b.lss" -o "$work/b.raw" --json "$work/b.json" "${opts[@]}" "$@" "$ex" ; } 2>"$work/t"
  python3 - "$name" "$P" "$work/b.json" "$work/t" <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
user, sys_ = (float(x) for x in open(sys.argv[4]).read().split()[-2:])
err = max(s["max_rel_err"] for s in j["slices"])
eff = 1.0 / (err * err * j["seconds"]) if err > 0 and j["seconds"] > 0 else float("inf")
print("%-34s %10s %12.4g %9.3f %9.3f %12.3g %12.4g" % (sys.argv[1], sys.argv[2], j["paths_per_second"], j["seconds"],
                                                      user + sys_, err, eff))
PY
done
