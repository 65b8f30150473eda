#!/usr/bin/env bash
# Command-line behaviour of lsqt-cl: help, flag and input errors (exit 2, nothing
# written), outputs and their names, continuation, determinism, stdin, missing device.
# usage: test_cli.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir

cp "$EX/tutorial/Lambertian.lsqt" L.lsqt

# Help.
expect 0 "usage: lsqt-cl" -- "$BIN"
expect 0 "--path-count" -- "$BIN" -h
expect 0 "--list-devices" -- "$BIN" --help

# Flag errors: exit 2 and nothing written.
while IFS='|' read -r args text; do
  [ -z "$args" ] && continue
  # shellcheck disable=SC2086
  expect 2 "$text" -- "$BIN" $args L.lsqt
  if ls L.lsqt.* >/dev/null 2>&1; then bad "[$args] wrote output"; rm -f L.lsqt.*; fi
done <<'TABLE'
-p 0|bad value '0' for -p
-p 1.5|bad value '1.5' for -p
-p 1e7x|bad value '1e7x' for -p
-p nan|bad value 'nan' for -p
-p 1e16|bad value '1e16' for -p: expected an integer path count from 1 to 9e15
-wo 3|bad value '3' for -wo: expected an integer in 4-1024
-wo=1025|bad value '1025' for -wo
-wi 15|bad value '15' for -wi: expected an integer in 16-1024
-wi=2000|bad value '2000' for -wi
-rx 9|bad value '9' for -rx
-rp 0|bad value '0' for -rp
-s -1|bad value '-1' for -s
-s 18446744073709551616|bad value '18446744073709551616' for -s: expected an integer in 0-18446744073709551615
-s 1e3|bad value '1e3' for -s
-t 0|bad value '0' for -t
--time-limit -3|bad value '-3' for --time-limit
--wo-angles=10,95|bad value '10,95' for --wo-angles
--bogus|unknown option '--bogus' (see --help)
--wi-cont 80|unknown option '--wi-cont' (did you mean '--wi-count'? see --help)
--pathcount 80|unknown option '--pathcount' (did you mean '--path-count'? see --help)
--time-limt 80|unknown option '--time-limt' (did you mean '--time-limit'? see --help)
-R=1|-R takes no value
--wi-spread --wi-file x.txt|--wi-spread and --wi-file both choose the incident directions: give one of them
-rx 3 --wi-file x.txt|-rx sets RRSS's pilot, and --wi-file chooses the directions without RRSS
-rp 0.5 --wi-spread|-rp sets RRSS's pilot, and --wi-spread chooses the directions without RRSS
TABLE
expect 2 "needs a value" -- "$BIN" L.lsqt -p
expect 2 "more than one input file" -- "$BIN" L.lsqt L.lsqt
expect 2 "no OpenCL device matches 'nosuchdevice'" -- "$BIN" -d nosuchdevice L.lsqt
expect 2 "cannot open 'missing.lsqt'" -- "$BIN" missing.lsqt

# Input errors: message with file, line and token; exit 2; nothing written.
while IFS='|' read -r input text; do
  [ -z "$input" ] && continue
  printf "$input" > bad.lsqt
  expect 2 "$text" -- "$BIN" bad.lsqt
  if ls bad.lsqt.* >/dev/null 2>&1; then bad "[$input] wrote output"; rm -f bad.lsqt.*; fi
done <<'TABLE'
|bad.lsqt
Medium\n|bad.lsqt:
Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0.6\nMedium\n|bad.lsqt:2:
Medium\nLayer z=0 LambertianBsdf fR=0.5x\nMedium\n|0.5x
Medium\nLayer z=0 LambertianBsdf fR=nan\nMedium\n|nan
Medium foo=1\nLayer z=0 LambertianBsdf\nMedium\n|bad.lsqt:1:
Medium eta=0.5\nLayer z=0 LambertianBsdf\nMedium\n|bad.lsqt:1:
Medium mus=1\nLayer z=0 LambertianBsdf\nMedium\n|bad.lsqt:1:
Medium\nLayer LambertianBsdf\nMedium\n|bad.lsqt:2:
Medium\nLayer z=0 FancyBsdf\nMedium\n|FancyBsdf
Medium\nLayer z=0 LambertianBdsf\nMedium\n|bad.lsqt:2: error: unknown word at 'LambertianBdsf'; expected one of: z or a BSDF model
Medium\nLayer z=0 LambertianBdsf\nMedium\n|did you mean 'LambertianBsdf'?
Medium\nLayer z=0 LambertianBsdf fr=0.5\nMedium\n|keys of LambertianBsdf); did you mean 'fR'?
Medium mus=1 HenyeyGreenstienPhase\nLayer z=0 LambertianBsdf\nMedium\n|did you mean 'HenyeyGreensteinPhase'?
Medium\nLayer z=0 Lambertain\nMedium\n|did you mean 'Lambertian'?
Medium\nLayer z=0 LambertianBsdf fR=0.5 fR=0.5\nMedium\n|fR
Medium\nLayer z=0 NullBsdf\nMedium\nLayer z=1 LambertianBsdf\nMedium\n|bad.lsqt:4:
Medium\nLayer z=0 MicrosurfaceLambertianBrdf iter_count=0\nMedium\n|iter_count
Medium\nLayer z=0 MicrosurfaceDielectricBsdf use_multiple_scattering=yes\nMedium\n|use_multiple_scattering
Medium\nLayer z=0 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=1\nLayer z=-1 NullBsdf\nMedium\n|bad.lsqt:3:
TABLE

# A slip far from every flag gets no guess (a wrong guess misleads more than none).
"$BIN" --zzzzz L.lsqt 2>&1 | grep -q "did you mean" && bad "--zzzzz got a guess" || ok

# --version: the version and the commit on every program, and lsqt-cl's devices.
expect 0 "lsqt-cl 0.1.0 (git " -- "$BIN" --version
expect 0 "OpenCL devices (float on every one; --double on those marked fp64):" -- "$BIN" --version
expect 0 "lsqt-cl info 0.1.0 (git " -- "$BIN" info --version
expect 0 "lsqt-cl merge 0.1.0 (git " -- "$BIN" merge --version
expect 0 "lsqt-cl export 0.1.0 (git " -- "$BIN" export --version
LSQT_CL="$BIN" expect 0 "lssplot 0.1.0 (git " -- python3 "$(dirname "${BASH_SOURCE[0]}")/../tools/lssplot" --version
for prog in lssinfo lssmerge lssview; do
  p="$(dirname "$BIN")/$prog"
  [ -x "$p" ] || p="$(dirname "$BIN")/tools/$prog/$prog"
  if [ -x "$p" ]; then expect 0 "$prog 0.1.0 (git " -- "$p" --version; fi
done

# A file the programs write, given where LSQT text belongs: what it is and what reads it.
"$BIN" -q -R -p 300 -wo 4 -wi 16 --wi-spread -o w.raw --lss w.lss L.lsqt && ok || bad "run for the wrong-input checks"
expect 2 "w.lss is an LSS file (the state of a run), not an LSQT input: 'lsqt-cl info w.lss'" -- "$BIN" w.lss
expect 2 "<stdin> is an LSS file" -- bash -c "\"$BIN\" - < w.lss"
expect 2 "w.raw is a RAW file" -- "$BIN" w.raw
printf 'CDF\001\000\000\000\000' > w.nc
expect 2 "w.nc is a NetCDF file (what 'lsqt-cl export' writes)" -- "$BIN" w.nc
ls w.lss.* w.raw.* w.nc.* >/dev/null 2>&1 && bad "a refused input wrote output" || ok

# The tutorial example: RAW header, line count, 0.6/pi everywhere, and an LSS.
expect 0 "R +- 1 s.e." -- "$BIN" -p 2000 -wo 4 -wi 16 L.lsqt
if [ -f L.lsqt.raw ] && [ -f L.lsqt.lss ]; then ok; else bad "no L.lsqt.raw / L.lsqt.lss"; fi
[ "$(head -c 20 L.lsqt.raw)" = "RAWBH10A Layered-SQT" ] && ok || bad "RAW header: $(head -1 L.lsqt.raw)"
[ "$(sed -n 2p L.lsqt.raw)" = "1 0.5" ] && ok || bad "RAW band line"
[ "$(sed -n 3p L.lsqt.raw | awk '{print $1, NF}')" = "4 5" ] && ok || bad "RAW slice line: $(sed -n 3p L.lsqt.raw)"
[ "$(wc -l < L.lsqt.raw)" = "$((3 + 4 * 16 * 2))" ] && ok || bad "RAW has $(wc -l < L.lsqt.raw) lines"
awk 'NR > 3 { d = $5 / (0.6 / 3.14159265358979) - 1; if (d > 1e-5 || d < -1e-5) bad++ } END { exit bad > 0 }' L.lsqt.raw \
  && ok || bad "RAW values are not 0.6/pi"

# Continuation adds paths; the split run equals the single run byte for byte (with the
# even spread: RRSS takes its pilot from the first run's -p, see below). The slab's RAW
# depends on the random paths (another seed changes it, checked), so these can fail.
expect 0 "continuing L.lsqt.lss (2000 paths per slice so far)" -- "$BIN" -p 3000 L.lsqt
cp "$EX/slab.lsqt" S.lsqt
"$BIN" -q -p 2000 -wo 4 -wi 16 --wi-spread S.lsqt && ok || bad "slab run"
expect 0 "continuing S.lsqt.lss (2000 paths per slice so far)" -- "$BIN" -p 3000 S.lsqt
"$BIN" -q -R -p 5000 -wo 4 -wi 16 --wi-spread -o once.raw --lss once.lss S.lsqt && ok || bad "single run"
cmp -s once.raw S.lsqt.raw && ok || bad "split run RAW differs from single run"
cmp -s once.lss S.lsqt.lss && ok || bad "split run LSS differs from single run"
"$BIN" -q -R -p 5000 -wo 4 -wi 16 --wi-spread -o again.raw --lss again.lss S.lsqt && cmp -s once.raw again.raw && ok \
  || bad "same seed and -p give different RAW"
"$BIN" -q -R -p 5000 -wo 4 -wi 16 --wi-spread -s 1 -o seed1.raw --lss seed1.lss S.lsqt && ! cmp -s once.raw seed1.raw && ok \
  || bad "another seed gives the same RAW: the determinism checks above could not fail"
# --total-paths N brings the LSS to N paths per slice: fresh it is -p N; continued it adds
# what is missing (the bytes of one -p N run); holding N it adds none and says so.
"$BIN" -q -R -wo 4 -wi 16 --wi-spread --total-paths 2000 -o tp.raw --lss tp.lss S.lsqt &&
  "$BIN" -q -R -wo 4 -wi 16 --wi-spread -p 2000 -o tq.raw --lss tq.lss S.lsqt && cmp -s tp.lss tq.lss && ok ||
  bad "fresh --total-paths 2000 is not -p 2000"
"$BIN" -q --total-paths 5000 -o tp.raw --lss tp.lss S.lsqt && cmp -s tp.lss once.lss && cmp -s tp.raw once.raw && ok ||
  bad "--total-paths 5000 after 2000 is not one run of 5000"
expect 0 "note: 'tp.lss' holds 5000 paths per slice, --total-paths 5000: none to add" -- \
  "$BIN" --total-paths 5000 -o tp.raw --lss tp.lss S.lsqt
expect 0 "paths: 0 added per slice (5000 per slice in all)" -- "$BIN" --total-paths 3000 -o tp.raw --lss tp.lss S.lsqt
cmp -s tp.lss once.lss && ok || bad "--total-paths below what the LSS holds changed it"
expect 2 "--total-paths sets how many paths the LSS is to hold, and -p how many to add: give one of them" -- \
  "$BIN" --total-paths 5000 -p 10 S.lsqt
expect 2 "--total-paths sets how many paths the LSS is to hold, and --shard splits a run of -p paths" -- \
  "$BIN" --total-paths 5000 --shard 0/2 S.lsqt
expect 2 "bad value '0' for --total-paths" -- "$BIN" --total-paths 0 S.lsqt

# Each estimate is written twice, at (x, y, z) with y >= 0 and then at (x, -y, z), same value.
awk 'NR > 3 && NR % 2 == 0 { s = $1; x = $2; y = $3; z = $4; v = $5 }
     NR > 3 && NR % 2 == 1 { if ($1 != s || $2 != x || $3 + y != 0 || $4 != z || $5 != v || y < 0) bad++; n++ }
     END { exit !(n == 4 * 16 && bad == 0) }' once.raw && ok || bad "RAW lines are not (x, y, z), (x, -y, z) pairs"

# An LSS of another assembly, or a damaged one, is an error that leaves it untouched.
cp L.lsqt.lss keep.lss
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n' > L.lsqt
expect 2 "was made for a different assembly: its layers or values differ; to keep it, give this run a state of its own (--lss OTHER.lss); -R would discard" -- "$BIN" L.lsqt
cmp -s keep.lss L.lsqt.lss && ok || bad "LSS changed after a refused run"
head -c 1000 keep.lss > L.lsqt.lss
expect 2 "truncated at byte 1000" -- "$BIN" L.lsqt
[ "$(wc -c < L.lsqt.lss)" = 1000 ] && ok || bad "damaged LSS was replaced"
expect 0 "wrote L.lsqt.raw" -- "$BIN" -R -p 1000 L.lsqt

# stdin: RAW defaults to Layered.raw, no LSS unless --lss; -wi=N and -wi N both work.
before=$(ls ./*.lss | wc -l)
cat "$EX/tutorial/Lambertian.lsqt" | "$BIN" -q -p 500 -wo 4 -wi=20 - && [ -f Layered.raw ] && ok || bad "stdin run"
[ "$(ls ./*.lss | wc -l)" = "$before" ] && ok || bad "stdin wrote an LSS"
[ "$(wc -l < Layered.raw)" = "$((3 + 4 * 20 * 2))" ] && ok || bad "-wi=20 not honoured"

# -p 1e3 means 1000 paths (the original read it as 1).
"$BIN" -q -R -p 1e3 -wo 4 -wi 16 --json s.json L.lsqt && grep -q '"paths": 1000,' s.json && ok || bad "-p 1e3: $(cat s.json)"
# The JSON summary, parsed, says what the printed summary says (device, paths, seed, and
# per slice theta_o, R, T, delta_T and their errors, to the printed digits).
"$BIN" -R -p 3000 -wo 4 -wi 16 -s 7 --json sj.json -o sj.raw --lss sj.lss S.lsqt >sj.txt 2>&1 && ok || bad "JSON run"
python3 - sj.json sj.txt <<'PY' && ok || bad "JSON and summary disagree: $(cat sj.json)"
import json, math, re, sys
j = json.load(open(sys.argv[1]))
text = open(sys.argv[2]).read()
rows = [l.split() for l in text.splitlines() if re.match(r"\s*\d+\s+[\d.]+d\s", l)]
problems = []
def near(a, b, rel, absol):
    return abs(a - b) <= rel * abs(b) + absol
if ("\ndevice: " + j["device"] + "\n") not in "\n" + text: problems.append("device")
if j["seed"] != 7 or j["double"] is not False: problems.append("seed/double")
if "paths: 3000 added per slice (3000 per slice in all)" not in text: problems.append("paths line")
if len(rows) != 4 or len(j["slices"]) != 4: problems.append("slice count")
for r, s in zip(rows, j["slices"]):
    # columns: slice theta R +- Rerr T +- Terr delta_T maxrel (printed %.6f, %.2g, %.4g)
    if s["paths"] != 3000: problems.append("paths")
    if not near(math.degrees(s["theta_o"]), float(r[1][:-1]), 0, 6e-4): problems.append("theta_o")
    if not near(s["R"], float(r[2]), 0, 6e-7) or not near(s["T"], float(r[5]), 0, 6e-7): problems.append("R/T")
    if not near(s["R_err"], float(r[4]), 0.05, 0) or not near(s["T_err"], float(r[7]), 0.05, 0): problems.append("errors")
    if not (s["R_err"] > 0 and s["T_err"] > 0): problems.append("zero errors")
    if not near(s["delta_T"], float(r[8]), 6e-4, 1e-12): problems.append("delta_T")
    if not near(s["max_rel_err"], float(r[9]), 6e-3, 1e-12): problems.append("max_rel_err")
    if not near(s["R"] + s["T"], 1.0, 0, 1e-9): problems.append("R+T (lossless slab)")
if problems: sys.exit("JSON vs summary: " + ", ".join(sorted(set(problems))))
PY

# Transmission: RAWBS, with lower-hemisphere directions; -H splits into two files named
# by replacing the final .raw (appending when there is none), T mirrored up.
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.3 fT=0.5\nMedium\n' > t.lsqt
"$BIN" -q -p 1000 -wo 4 -wi 16 t.lsqt && [ "$(head -c 5 t.lsqt.raw)" = "RAWBS" ] && ok || bad "transmitting RAW is not RAWBS"
awk 'NR > 3 && $4 < 0 { n++ } END { exit !(n > 0) }' t.lsqt.raw && ok || bad "no transmission lines"
"$BIN" -q -R -H -p 1000 -wo 4 -wi 16 -o h t.lsqt && [ -f h.R.raw ] && [ -f h.T.raw ] && ok || bad "-H files"
# Their values: the R file holds the upper lines of the full RAW of the same run, the T
# file the lower ones with z -> -z, both RAWBH with the same slice line.
python3 - t.lsqt.raw h.R.raw h.T.raw <<'PY' && ok || bad "-H values differ from the full RAW"
import sys
def read(p):
    lines = open(p).read().splitlines()
    return lines[:3], [tuple(float(v) for v in l.split()) for l in lines[3:]]
(hf, full), (hr, r), (ht, t) = read(sys.argv[1]), read(sys.argv[2]), read(sys.argv[3])
ok = hf[0].startswith("RAWBS") and hr[0].startswith("RAWBH") and ht[0].startswith("RAWBH")
ok = ok and hf[1:] == hr[1:] == ht[1:]
up = [l for l in full if l[3] > 0]
down = [(l[0], l[1], l[2], -l[3], l[4]) for l in full if l[3] < 0]
ok = ok and len(up) > 0 and len(down) > 0 and r == up and t == down
ok = ok and any(l[4] != up[0][4] for l in up + down)  # fR and fT differ: R and T values differ
sys.exit(0 if ok else 1)
PY
"$BIN" -q -R -H -p 1000 -wo 4 -wi 16 -o out.raw t.lsqt && [ -f out.R.raw ] && [ -f out.T.raw ] && [ ! -e out.raw.R.raw ] \
  && ok || bad "-H -o out.raw: $(ls out*)"
"$BIN" -q -R -H -p 1000 -wo 4 -wi 16 t.lsqt && [ -f t.lsqt.R.raw ] && [ -f t.lsqt.T.raw ] && ok || bad "-H default names"
# Nothing transmitted: no T file, and the run says so.
expect 0 "the stack transmits nothing, so -H wrote no T file" -- "$BIN" -R -H -p 1000 -wo 4 -wi 16 -o r.raw L.lsqt
[ -f r.R.raw ] && [ ! -e r.T.raw ] && ok || bad "-H on a reflector: $(ls r.*)"

# Seeds are exact 64-bit integers: 2^53 and 2^53 + 1 are different runs, 2^64 - 1 is fine,
# and the JSON prints the seed as given.
"$BIN" -q -R -p 600 -wo 4 -wi 16 -s 9007199254740992 --lss s0.lss -o s0.raw "$EX/slab.lsqt" && \
"$BIN" -q -R -p 600 -wo 4 -wi 16 -s 9007199254740993 --lss s1.lss -o s1.raw --json s1.json "$EX/slab.lsqt" && ok || bad "seed runs"
cmp -s s0.raw s1.raw && bad "seeds 2^53 and 2^53+1 give the same RAW" || ok
grep -q '"seed": 9007199254740993,' s1.json && ok || bad "JSON seed: $(grep -o '"seed": [0-9]*' s1.json)"
"$BIN" -q -R -p 300 -wo 4 -wi 16 -s 18446744073709551615 --json smax.json -o smax.raw --lss smax.lss L.lsqt \
  && grep -q '"seed": 18446744073709551615,' smax.json && ok || bad "seed 2^64-1"

# -v prints the device and the kernel build options, as the help says.
expect 0 "kernel build options: " -- "$BIN" -v -R -p 300 -wo 4 -wi 16 -o v.raw --lss v.lss L.lsqt
expect 0 "-cl-std=CL1.2" -- "$BIN" -v -R -p 300 -wo 4 -wi 16 -o v.raw --lss v.lss L.lsqt

# RRSS (the default): the pilot is -rp (default 0.3: 1200 of 4000 paths) of the first
# run's -p and chooses the directions,
# which later runs keep; so "-p 4000, then -p 8000" is byte for byte "-p 4000" three times.
# Runs are deterministic; info says how the directions were chosen.
"$BIN" -q -R -p 4000 -wo 4 -wi 16 -o r1.raw --lss r1.lss S.lsqt && "$BIN" -q -p 8000 -o r1.raw --lss r1.lss S.lsqt \
  && ok || bad "RRSS runs"
"$BIN" -q -R -p 4000 -wo 4 -wi 16 -o r3.raw --lss r3.lss S.lsqt && "$BIN" -q -p 4000 -o r3.raw --lss r3.lss S.lsqt \
  && "$BIN" -q -p 4000 -o r3.raw --lss r3.lss S.lsqt && cmp -s r1.lss r3.lss && cmp -s r1.raw r3.raw && ok \
  || bad "RRSS: -p 4000 then -p 8000 differs from -p 4000 three times"
"$BIN" -q -R -p 4000 -wo 4 -wi 16 -o r4.raw --lss r4.lss S.lsqt && "$BIN" -q -R -p 4000 -wo 4 -wi 16 -o r5.raw \
  --lss r5.lss S.lsqt && cmp -s r4.lss r5.lss && ok || bad "RRSS: two runs differ"
expect 0 "directions: RRSS (4 candidates per direction, pilot of 1200 paths)" -- "$BIN" info r4.lss
expect 0 "directions: even spread" -- "$BIN" info once.lss
# A stack that sends nothing back out: the walks give no candidates; the spread fills in,
# and the run says so.
printf 'Medium\nLayer z=0 LambertianBsdf fR=0 fT=0\nMedium\n' > black.lsqt
expect 0 "the even spread filled the rest" -- "$BIN" -R -p 1000 -wo 4 -wi 16 black.lsqt

# An odd direction count of the spread over the sphere would put a direction on the
# horizon: refused (RRSS directions come from exits, never on it).
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5 fT=0.5\nMedium\n' > odd.lsqt
expect 2 "count must be even" -- "$BIN" -p 100 -wi 63 --wi-spread odd.lsqt
expect 0 "wrote" -- "$BIN" -p 100 -wi 63 odd.lsqt

# The microsurface examples, and those of the phase functions and Oren-Nayar (in examples/
# itself), run end to end: RAW values finite and non-negative, every slice and direction
# present (4 slices x 16 directions, mirrored in y; all of them reflect only), and no
# contribution dropped as non-finite or negative (the tallies drop those and only warn, so
# the RAW alone could not show them).
for ex in tutorial/Rough tutorial/Substr tutorial/Dusty tutorial/Silver rayleigh-oren-nayar sggx-dust; do
  n=$(basename "$ex")
  out=$(timeout -k 5 120 "$BIN" -p 1000 -wo 4 -wi 16 -o "$n.raw" --lss "$n.lss" "$EX/$ex.lsqt" 2>&1)
  rc=$?
  [ "$rc" = 0 ] && grep -qF "wrote" <<<"$out" && ! grep -q "non-finite" <<<"$out" && ok || bad "$n: exit $rc: $out"
  awk 'NR > 3 { if (!($5 >= 0 && $5 < 1e30)) bad++; n++ } END { exit !(n == 4 * 16 * 2 && bad == 0) }' "$n.raw" && ok \
    || bad "$n RAW has missing, non-finite or negative values"
done

# A kernel that fails to compile: exit 1 with the compiler's build log.
mkdir -p broken && cp -r "$EX/../kernels" "$EX/../include" broken/
echo "this is not OpenCL C;" >> broken/kernels/walk.cl
expect 1 "OpenCL build log" -- env LSQT_KERNEL_DIR="$T/broken" "$BIN" -p 100 L.lsqt
expect 1 "the OpenCL kernels failed to build" -- env LSQT_KERNEL_DIR="$T/broken" "$BIN" -p 100 L.lsqt

# No OpenCL platform at all: exit 3 and say how to install PoCL.
mkdir -p novendors
expect 3 "pocl-opencl-icd" -- env OCL_ICD_VENDORS="$T/novendors" "$BIN" L.lsqt
expect 0 "" -- "$BIN" --list-devices

# -t limits PoCL's threads and changes nothing in the result.
"$BIN" -q -R -t 1 -p 5000 -wo 4 -wi 16 --wi-spread -o t1.raw --lss t1.lss S.lsqt && cmp -s t1.raw once.raw \
  && cmp -s t1.lss once.lss && ok || bad "-t 1 gives another RAW or LSS"

# The next-event loops' vector width (16 on CPUs, 2 on GPUs; LSQT_VECTOR_WIDTH overrides
# it) changes nothing in the result but a vector builtin's rounding: for a medium, a rough
# dielectric coat and a Lambertian floor with 21 directions (padded to 24 or 32), RRSS
# pilot included, widths 16 and 4 give the same bytes, and the GPU's width 2 on this CPU
# every value within 1e-6 relative (PoCL's 2-lane exp rounds a last bit differently at
# some arguments: 3e-8 here). A width that is not 2, 4, 8 or 16 is refused.
"$BIN" -q -R -p 3000 -wo 4 -wi 21 -o vw16.raw --lss vw16.lss "$EX/tutorial/Dusty.lsqt" &&
  LSQT_VECTOR_WIDTH=4 "$BIN" -q -R -p 3000 -wo 4 -wi 21 -o vw4.raw --lss vw4.lss "$EX/tutorial/Dusty.lsqt" &&
  cmp -s vw16.raw vw4.raw && cmp -s vw16.lss vw4.lss && ok || bad "vector widths 16 and 4 give different RAW or LSS"
LSQT_VECTOR_WIDTH=2 "$BIN" -q -R -p 3000 -wo 4 -wi 21 -o vw2.raw --lss vw2.lss "$EX/tutorial/Dusty.lsqt" && python3 - vw16.raw vw2.raw <<'PY' && ok || bad "vector widths 16 and 2 differ by more than rounding"
import sys
a, b = (open(p).read().split() for p in sys.argv[1:3])
assert len(a) == len(b) and a[:3] == b[:3], "different shapes"
worst = max(abs(float(x) - float(y)) / max(abs(float(x)), 1e-30) for x, y in zip(a[3:], b[3:]))
sys.exit(0 if worst <= 1e-6 else "largest relative difference %.2e" % worst)
PY
expect 1 "LSQT_VECTOR_WIDTH is '3': expected 2, 4, 8 or 16" -- env LSQT_VECTOR_WIDTH=3 "$BIN" -R -p 100 -o vw3.raw L.lsqt
[ ! -e vw3.raw ] && ok || bad "a refused vector width wrote a RAW"

# Ctrl-C: the current launch finishes, LSS and RAW are written, exit status is non-zero.
# The signal is sent as soon as the run reports its kernel build, before any launch: an
# early Ctrl-C must not be lost (the handler comes first) nor kill the run.
# (timeout --foreground passes the SIGINT on once; after 300 s it ends a run that hangs.)
timeout --foreground 300 "$BIN" -v -R -p 1e12 -wo 4 -wi 16 --lss int.lss -o int.raw "$EX/slab.lsqt" 2>int.err >/dev/null &
pid=$!
for _ in $(seq 600); do grep -q "kernel build options" int.err 2>/dev/null && break; sleep 0.1; done
kill -INT $pid
wait $pid
rc=$?
[ "$rc" = 1 ] && [ -s int.lss ] && [ -s int.raw ] && grep -q "interrupted" int.err && ok \
  || bad "Ctrl-C: exit $rc, files: $(ls int.* 2>&1), stderr: $(cat int.err)"
# Interrupted in the RRSS pilot (-p 1e12): the LSS is the pilot so far; another -p chooses
# the directions from it and adds -p paths (the same -p would finish the pilot: test_signals).
pj() { "$BIN" info "$1" --json - 2>/dev/null | python3 -c "import json, sys; j = json.load(sys.stdin); print(j[\"$2\"])"; }
n0=$(pj int.lss paths)
[ "$(pj int.lss stage)" = rrss-pilot ] && ok || bad "Ctrl-C in the RRSS pilot: the LSS is not the pilot"
expect 0 "the directions are chosen from them, then -p 1000 more" -- "$BIN" -p 1000 --lss int.lss -o int2.raw "$EX/slab.lsqt"
[ "$(pj int.lss paths)" = $((n0 + 1000)) ] && [ "$(pj int.lss stage)" = run ] && ok ||
  bad "continuing with another -p: $(pj int.lss paths) paths, not $n0 + 1000"
# While the input is still being read (a stdin that never ends: a FIFO this shell holds
# open), Ctrl-C stops at once.
mkfifo in.fifo
exec 7<>in.fifo
"$BIN" -p 100 - <in.fifo 2>stdin_int.err &
pid=$!
for _ in $(seq 300); do [ "$(ls /proc/$pid/task 2>/dev/null | wc -l)" -ge 2 ] && break; sleep 0.1; done
kill -INT $pid
wait $pid
rc=$?
[ "$rc" = 130 ] && grep -q "lsqt-cl: interrupted: stopping now" stdin_int.err && [ ! -e Layered.raw.tmp* ] && ok \
  || bad "Ctrl-C while reading stdin: exit $rc: $(cat stdin_int.err)"
exec 7>&-

# A continued LSS keeps what it was made with: a flag with its own value is fine, one that
# contradicts it is an error (exit 2, the LSS untouched) naming the flag and the LSS's
# value; -rp says what the LSS keeps.
"$BIN" -q -R -p 300 -wo 4 -wi 16 -s 3 -o c.raw --lss c.lss L.lsqt && ok || bad "a state to continue"
cp c.lss c0.lss
while IFS='|' read -r args text; do
  [ -z "$args" ] && continue
  # shellcheck disable=SC2086
  expect 2 "$text" -- "$BIN" -p 100 $args -o c.raw --lss c.lss L.lsqt
  cmp -s c.lss c0.lss || bad "[$args] changed the LSS"
done <<'TABLE'
-s 7|-s 7 contradicts 'c.lss' (its paths were drawn with -s 3): a continued run keeps what its LSS was made with; drop -s 7, or start over with -R
-wi 32|-wi 32 contradicts 'c.lss' (it holds 16 incident directions per slice)
-wo 8|-wo 8 contradicts 'c.lss' (it holds 4 outgoing directions)
--wo-angles 10,20,30,40|--wo-angles contradicts 'c.lss'
--wi-spread|--wi-spread contradicts 'c.lss' (its incident directions were chosen by RRSS)
-rx 3|-rx 3 contradicts 'c.lss' (its RRSS pilot drew -rx 4 candidates per direction)
--double|--double contradicts 'c.lss' (it is a float state)
TABLE
expect 0 "continuing c.lss (300 paths per slice so far)" -- "$BIN" -p 100 -s 3 -wo 4 -wi 16 -rx 4 -o c.raw --lss c.lss L.lsqt
expect 0 "note: -rp 0.3 is not used: 'c.lss' keeps its RRSS pilot" -- "$BIN" -p 100 -rp 0.3 -o c.raw --lss c.lss L.lsqt
expect 0 "" -- "$BIN" -q -R -p 100 -wi 32 -o c.raw --lss c.lss L.lsqt

# An endless input (an LSQT file or a --wi-file read from a pipe by mistake) is refused
# once it passes 64 MiB, not read until memory runs out.
expect 2 "standard input is larger than 64 MiB" -- bash -c "yes | \"$BIN\" -p 10 -"
expect 2 "--wi-file: standard input is larger than 64 MiB" -- bash -c "yes | \"$BIN\" -p 10 --wi-file - L.lsqt"
finish test_cli
