#!/usr/bin/env bash
# --wi-file: incident directions given by the user (one per line, 'x y z' or
# 'theta_deg phi_deg', the same for every slice). The RAW holds exactly those directions
# (each as given and as its mirror image in y), a Lambertian layer gives fR/pi at all of
# them, counts of 1, 3 and 17 run (the kernels pad to fours), the two forms agree, a file
# of the -wi spread's own directions reproduces that run, every bad line is an error with
# its line number (exit 2, nothing written), and a continued LSS keeps its directions.
# usage: test_wi_file.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir

printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n' > L.lsqt
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.3 fT=0.5\nMedium\n' > t.lsqt
cp "$EX/slab.lsqt" S.lsqt

expect 0 "--wi-file FILE" -- "$BIN" --help
expect 0 "y < 0 is simulated at (x, -y, z)" -- "$BIN" --help

# check.py RAW WIFILE SLICES FR FT: the RAW's header counts, and per slice its line pairs
# are the file's directions in order (computed here on their own: normalised x y z, or
# (sin t cos p, sin t sin p, cos t) with phi from +x), first with y >= 0 and then mirrored,
# one of the two being the direction as written; values fR/pi above the horizon and fT/pi
# below. A Lambertian layer's point estimate is exact per path, so the values are exact
# up to float rounding (the 1e-5 of test_cli).
cat > check.py <<'PY'
import math, sys
raw, wifile, slices, fr, ft = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
dirs = []
for line in open(wifile):
    t = line.split("#")[0].split()
    if not t:
        continue
    v = [float(x) for x in t]
    if len(v) == 3:
        n = math.sqrt(sum(c * c for c in v))
        dirs.append([c / n for c in v])
    else:
        th, ph = math.radians(v[0]), math.radians(v[1])
        dirs.append([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
lines = open(raw).read().splitlines()
problems = []
want_head = "RAWB" + ("S" if ft > 0 else "H") + "10A Layered-SQT"
if lines[0] != want_head or lines[1] != "1 0.5" or int(lines[2].split()[0]) != slices:
    problems.append("header %r" % lines[:3])
rows = [[float(x) for x in l.split()] for l in lines[3:]]
if len(rows) != 2 * slices * len(dirs):
    problems.append("%d estimate lines, expected %d" % (len(rows), 2 * slices * len(dirs)))
for i, (a, b) in enumerate(zip(rows[0::2], rows[1::2])):
    s, k = divmod(i, len(dirs))
    d = dirs[k]
    if a[0] != s or b[0] != s:
        problems.append("line pair %d: slice %g/%g, expected %d" % (i, a[0], b[0], s))
    if not (a[2] >= 0 and a[1] == b[1] and a[2] == -b[2] and a[3] == b[3] and a[4] == b[4]):
        problems.append("line pair %d is not (x, y, z), (x, -y, z) with y >= 0: %s / %s" % (i, a, b))
    if not any(max(abs(p[j + 1] - d[j]) for j in range(3)) < 2e-7 for p in (a, b)):
        problems.append("slice %d direction %d: %s, expected %s" % (s, k, a[1:4], d))
    want = (fr if d[2] > 0 else ft) / math.pi
    if abs(a[4] / want - 1) > 1e-5:
        problems.append("slice %d direction %d: value %.9g, expected %.9g" % (s, k, a[4], want))
if problems:
    sys.exit("\n".join(problems[:10]))
PY

# Both forms, comments, blank lines, CRLF, y < 0, odd count (3).
printf '# three directions\n\n0 0 1\r\n  30 -45   # theta phi, y < 0\n1 -2 2\n' > three.txt
expect 0 "note: 2 directions of three.txt with y < 0" -- "$BIN" -p 1000 -wo 4 --wi-file three.txt L.lsqt
python3 check.py L.lsqt.raw three.txt 4 0.5 0 && ok || bad "3 directions: RAW"
# One direction, and 17 (every slice the same; a count that is neither even nor a multiple
# of 4), with --wo-angles.
printf '45 180\n' > one.txt
"$BIN" -q -R -p 500 -wo 4 --wi-file one.txt -o one.raw --lss one.lss L.lsqt && python3 check.py one.raw one.txt 4 0.5 0 && ok \
  || bad "1 direction"
python3 - > seventeen.txt <<'PY'
import math
for k in range(17):
    th, ph = 5 + 5 * k, -170 + 21 * k
    if k % 2:
        print("%.3f %.3f" % (th, ph))
    else:
        t, p = math.radians(th), math.radians(ph)
        print("%.12g %.12g %.12g" % (3 * math.sin(t) * math.cos(p), 3 * math.sin(t) * math.sin(p), 3 * math.cos(t)))
PY
"$BIN" -q -R -p 500 --wo-angles=0,40,80 --wi-file seventeen.txt -o s17.raw --lss s17.lss L.lsqt && python3 check.py s17.raw seventeen.txt 3 0.5 0 \
  && ok || bad "17 directions"
# A transmitting stack: directions below the horizon too (3 of them: an odd count is fine,
# none is on the horizon), RAWBS, fT/pi there; -H splits them as usual.
printf '0 0 1\n120 30\n1 -1 -1\n' > t3.txt
"$BIN" -q -p 1000 -wo 4 --wi-file t3.txt t.lsqt && python3 check.py t.lsqt.raw t3.txt 4 0.3 0.5 && ok \
  || bad "transmitting stack, 3 directions"
"$BIN" -q -R -H -p 1000 -wo 4 --wi-file t3.txt -o h.raw t.lsqt && [ "$(wc -l < h.R.raw)" = $((3 + 4 * 2)) ] \
  && [ "$(wc -l < h.T.raw)" = $((3 + 4 * 2 * 2)) ] && ok || bad "-H with --wi-file"

# The same directions as x y z and as theta phi give the same RAW (up to the rounding of
# the angle conversion), on the slab, whose values depend on the random paths.
printf '10 20\n120 -100\n75 300\n' > ang.txt
python3 - ang.txt > xyz.txt <<'PY'
import math, sys
for line in open(sys.argv[1]):
    t, p = (math.radians(float(v)) for v in line.split())
    print("%.17g %.17g %.17g" % (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)))
PY
"$BIN" -q -R -p 2000 -wo 4 --wi-file ang.txt -o ang.raw --lss ang.lss S.lsqt && \
"$BIN" -q -R -p 2000 -wo 4 --wi-file xyz.txt -o xyz.raw --lss xyz.lss S.lsqt && ok || bad "slab runs"
# same.py A B TOL: the same lines, numbers within TOL (relative to max(1, |value|)).
cat > same.py <<'PY'
import sys
a, b, tol = open(sys.argv[1]).read().splitlines(), open(sys.argv[2]).read().splitlines(), float(sys.argv[3])
if len(a) != len(b) or a[:3] != b[:3]:
    sys.exit("headers or line counts differ")
for la, lb in zip(a[3:], b[3:]):
    va, vb = [float(x) for x in la.split()], [float(x) for x in lb.split()]
    if len(va) != len(vb) or any(abs(x - y) > tol * max(1.0, abs(y)) for x, y in zip(va, vb)):
        sys.exit("differ: %s / %s" % (la, lb))
PY
python3 same.py ang.raw xyz.raw 1e-6 && ok || bad "theta/phi and x y z give different RAW: $(python3 same.py ang.raw xyz.raw 1e-6 2>&1)"
# The -wi spread's own directions, written to a file, reproduce that run (again up to the
# float rounding of the directions: the paths do not depend on them).
"$BIN" -q -R -p 2000 -wo 4 -wi 16 --wi-spread -o spread.raw --lss spread.lss S.lsqt && \
awk 'NR > 3 && $1 == 0 && NR % 2 == 0 { print $2, $3, $4 }' spread.raw > spread.txt && \
"$BIN" -q -R -p 2000 -wo 4 --wi-file spread.txt -o fromfile.raw --lss fromfile.lss S.lsqt && ok || bad "spread runs"
[ "$(wc -l < spread.txt)" = 16 ] && python3 same.py fromfile.raw spread.raw 1e-6 && ok \
  || bad "the spread's directions from a file give another RAW: $(python3 same.py fromfile.raw spread.raw 1e-6 2>&1)"

# Other models through odd counts (media, microsurfaces, --double): finite non-negative
# values at every direction of every slice.
for ex in tutorial/Rough tutorial/Dusty; do
  n=$(basename "$ex")
  out=$(timeout -k 5 120 "$BIN" -p 500 -wo 4 --wi-file three.txt -o "$n.raw" --lss "$n.lss" "$EX/$ex.lsqt" 2>&1)
  rc=$?
  [ "$rc" = 0 ] && ! grep -q "non-finite" <<<"$out" && ok || bad "$n: exit $rc: $out"
  awk 'NR > 3 { if (!($5 >= 0 && $5 < 1e30)) bad++; n++ } END { exit !(n == 4 * 3 * 2 && bad == 0) }' "$n.raw" && ok \
    || bad "$n RAW with 3 directions"
done
"$BIN" -q -R --double -p 500 -wo 4 --wi-file seventeen.txt -o d17.raw --lss d17.lss L.lsqt \
  && python3 check.py d17.raw seventeen.txt 4 0.5 0 && ok || bad "--double, 17 directions"

# Bad lines: exit 2, the file's name and line number and the token, nothing written.
# Each case is a line 3 after two good ones (and a comment line before them).
while IFS='|' read -r line stack text; do
  [ -z "$stack" ] && continue
  printf '# c\n0 0 1\n45 0\n%b\n' "$line" > w.txt
  expect 2 "w.txt:4: error: $text" -- "$BIN" -p 100 -o w.raw --lss w.lss --wi-file w.txt "$stack.lsqt"
  if ls w.raw w.lss >/dev/null 2>&1; then bad "[$line] wrote output"; rm -f w.raw w.lss; fi
done <<'TABLE'
0 0 0|L|the zero vector at '0 0 0'
0.0 -0 0e5|t|the zero vector at '0.0 -0 0e5'
1 0 0|L|a direction on the horizon (z = 0
1 -1 0|t|a direction on the horizon (z = 0
1 0 1e-300|L|a direction on the horizon
90 10|L|a direction on the horizon (z = 0
90 0|t|a direction on the horizon
1 0 -1|L|a direction below the horizon (z < 0), but the stack transmits nothing
120 0|L|a direction below the horizon
5|L|a single number at '5'
1 2 3 4|L|trailing text after the direction at '4'
1 0 1x|L|not a finite number at '1x'
0 0 1 junk|L|trailing text after the direction at 'junk'
x 1 1|L|not a finite number at 'x'
1 nan 1|L|not a finite number at 'nan'
1 1 inf|L|not a finite number at 'inf'
0x1 0 1|L|not a finite number at '0x1'
1e400 1 1|L|not a finite number at '1e400'
1,0,1|L|not a finite number at '1,0,1'
1 0 \x01|L|not a finite number at '?'
190 0|L|theta out of range at '190'
-1 0|L|theta out of range at '-1'
180.0001 0|t|theta out of range at '180.0001'
TABLE
# A comment may follow a direction.
printf '0 0 1\n1 2 3 # ok 4\n' > w.txt
"$BIN" -q -R -p 100 -o w.raw --lss w.lss --wi-file w.txt L.lsqt && [ "$(wc -l < w.raw)" = $((3 + 12 * 2 * 2)) ] \
  && ok || bad "a comment after a direction"
rm -f w.raw w.lss
# A NUL byte is a bad character, not the end of the file.
printf '0 0 1\n1 0\0001\n' > w.txt
expect 2 "w.txt:2: error: not a finite number at '0?1'" -- "$BIN" -p 100 -o w.raw --lss w.lss --wi-file w.txt L.lsqt
# No directions, too many, no such file, no value, and -wi with --wi-file.
: > w.txt
expect 2 "w.txt: error: no directions" -- "$BIN" -p 100 -o w.raw --lss w.lss --wi-file w.txt L.lsqt
printf '# only\n\n   \t\n# comments\n' > w.txt
expect 2 "w.txt: error: no directions" -- "$BIN" -p 100 -o w.raw --lss w.lss --wi-file w.txt L.lsqt
python3 -c 'print("# 1025"); [print("0 0 1") for _ in range(1025)]' > w.txt
expect 2 "w.txt:1026: error: too many directions" -- "$BIN" -p 100 -o w.raw --lss w.lss --wi-file w.txt L.lsqt
python3 -c '[print("%d %d" % (1 + k % 89, k)) for k in range(1024)]' > w.txt
"$BIN" -q -R -p 256 -wo 4 -o w.raw --lss w.lss --wi-file w.txt L.lsqt && [ "$(wc -l < w.raw)" = $((3 + 4 * 1024 * 2)) ] \
  && ok || bad "1024 directions"
rm -f w.raw w.lss
expect 2 "cannot open 'nosuch.txt'" -- "$BIN" -p 100 -o w.raw --lss w.lss --wi-file nosuch.txt L.lsqt
expect 2 "bad value '' for --wi-file" -- "$BIN" -p 100 --wi-file= L.lsqt
expect 2 "--wi-file needs a value" -- "$BIN" L.lsqt --wi-file
expect 2 "-wi and --wi-file both set the incident directions" -- "$BIN" -wi 20 --wi-file three.txt L.lsqt
expect 2 "--wi-count and --wi-file both set" -- "$BIN" --wi-file three.txt --wi-count=20 L.lsqt
expect 2 "cannot both be read from stdin" -- "$BIN" --wi-file - - <L.lsqt
ls w.raw w.lss >/dev/null 2>&1 && bad "a refused run wrote output" || ok
# The directions may come from stdin.
"$BIN" -q -R -p 500 -wo 4 --wi-file - -o in.raw --lss in.lss L.lsqt <three.txt && python3 check.py in.raw three.txt 4 0.5 0 \
  && ok || bad "--wi-file - (stdin)"

# A continued LSS keeps its directions: another --wi-file, or -wi, contradicts it (exit 2,
# nothing changed); the same file is fine and says the LSS keeps its own; a bad file is
# still an error.
cp L.lsqt.lss keep0.lss
expect 2 "--wi-file seventeen.txt contradicts 'L.lsqt.lss' (it holds 3 incident directions per slice, the file 17)" -- \
  "$BIN" -p 1000 --wi-file seventeen.txt L.lsqt
expect 2 "-wi 16 contradicts 'L.lsqt.lss' (it holds 3 incident directions per slice)" -- "$BIN" -p 1000 -wi 16 L.lsqt
cmp -s keep0.lss L.lsqt.lss && ok || bad "a refused continuation changed the LSS"
expect 0 "note: --wi-file: 'L.lsqt.lss' keeps the 3 directions it was started with" -- "$BIN" -p 1000 --wi-file three.txt L.lsqt
grep -q "paths: 1000 added per slice (3000 per slice in all)" <("$BIN" -p 1000 L.lsqt 2>&1) && ok || bad "continue"
python3 check.py L.lsqt.raw three.txt 4 0.5 0 && ok || bad "the continued LSS lost its directions"
printf '0 0 0\n' > w.txt
cp L.lsqt.lss keep.lss
expect 2 "w.txt:1: error: the zero vector" -- "$BIN" -p 100 --wi-file w.txt L.lsqt
cmp -s keep.lss L.lsqt.lss && ok || bad "a refused continuation changed the LSS"

# A path's point estimate above 2^63 fixed-point units (8.4e6), where a work-item's sums
# need their high words: a smooth conductor's specular peak at normal incidence, single
# scattering, weight 1, the same value on every path: f = F D / 4 = F / (4 pi alpha^2)
# with F = ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2), n = 1.5, k = 3, alpha = 5e-5
# (1.9307321e7; float rounding 1e-6). 2000 paths sum to 4e10, 2^35 times 2^63 units.
printf 'Medium\nLayer z=0 MicrosurfaceConductiveBrdf alpha=5e-5 use_multiple_scattering=false\nMedium eta=1.5 mua=3\n' > C.lsqt
printf '0 0 1\n' > up.txt
"$BIN" -q -R -p 2000 -wo 4 --wi-file up.txt -o C.raw --lss C.lss C.lsqt && python3 - C.raw <<'PY' && ok || bad "the specular peak above 2^63 units per path"
import math, sys
n, k, a = 1.5, 3.0, 5e-5
f = ((n - 1) ** 2 + k * k) / ((n + 1) ** 2 + k * k) / (4 * math.pi * a * a)
row = [float(x) for x in open(sys.argv[1]).read().split("\n")[3].split()]
assert row[:4] == [0, 0, 0, 1], row
assert abs(row[4] / f - 1) < 1e-6, (row[4], f)
PY

finish test_wi_file
