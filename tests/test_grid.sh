#!/usr/bin/env bash
# --grid NO,NI,NPHI: a regular grid of slices and incident directions (the one Eradiate's
# tabulated BSDF takes). The RAW's slices and directions are exactly the grid, computed
# here on their own from its definition (cos theta on linspace(0, 1, N) with the horizon
# node at cos 0.001, azimuths 2 pi m / NPHI for m = 0 .. NPHI/2, below the horizon too
# when the stack transmits); a Lambertian layer gives fR/pi and fT/pi there; --grid N is
# N,N,4(N-1); the LSS and `info` name the grid; a continued LSS keeps it (another grid or
# another method is an error); shards of a grid merge to the one-process bytes; flags
# that choose the directions too, bad values and grids of more than 1024 directions are
# errors (exit 2).
# usage: test_grid.sh LSQT_CL
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN -- "$@"
cli_workdir

printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n' > L.lsqt
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.3 fT=0.5\nMedium\n' > t.lsqt

expect 0 "--grid NO,NI,NPHI" -- "$BIN" --help

# check.py RAW NO NI NPHI FR FT: the header's theta_o are acos of the grid nodes (theta
# ascending), and per slice the line pairs are the grid's directions in the documented
# order (above, then below when FT > 0; theta_i ascending; azimuth m = 0 .. NPHI/2), each
# written at (x, y, z) and (x, -y, z); values fR/pi above and fT/pi below (a Lambertian
# layer's point estimate is exact per path: float rounding only).
cat > check.py <<'PY'
import math, sys
raw, no, ni, nphi, fr, ft = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5]), float(sys.argv[6])
def node(k, n):  # cos theta of node k of linspace(0, 1, n); the horizon simulated at 0.001
    return 0.001 if k == 0 else k / (n - 1)
dirs = []
for h in ((1, -1) if ft > 0 else (1,)):
    for i in range(ni):
        c = node(ni - 1 - i, ni)
        s = math.sqrt(1 - c * c)
        for m in range(nphi // 2 + 1):
            p = 2 * math.pi * m / nphi
            dirs.append((s * math.cos(p), s * math.sin(p), h * c))
lines = open(raw).read().splitlines()
problems = []
head = lines[2].split()
want_theta = [math.acos(node(no - 1 - s, no)) for s in range(no)]
if int(head[0]) != no or any(abs(float(a) - b) > 1e-8 for a, b in zip(head[1:], want_theta)):
    problems.append("slices %r, expected %r" % (head, want_theta))
rows = [[float(x) for x in l.split()] for l in lines[3:]]
if len(rows) != 2 * no * len(dirs):
    problems.append("%d estimate lines, expected %d" % (len(rows), 2 * no * len(dirs)))
for i, (a, b) in enumerate(zip(rows[0::2], rows[1::2])):
    s, k = divmod(i, len(dirs))
    d = dirs[k]
    if a[0] != s or b[0] != s or a[2] != -b[2]:
        problems.append("line pair %d: %s / %s" % (i, a, b))
    if max(abs(a[j + 1] - d[j]) for j in range(3)) > 2e-7:
        problems.append("slice %d direction %d: %s, expected %s" % (s, k, a[1:4], d))
    want = (fr if d[2] > 0 else ft) / math.pi
    if abs(a[4] / want - 1) > 1e-5:
        problems.append("slice %d direction %d: value %.9g, expected %.9g" % (s, k, a[4], want))
if problems:
    sys.exit("\n".join(problems[:10]))
PY

# A transmitting stack: 3 slices, 4 polar nodes, 8 azimuths (5 simulated), above and below.
"$BIN" -q -p 512 --grid 3,4,8 t.lsqt && python3 check.py t.lsqt.raw 3 4 8 0.3 0.5 && ok || bad "grid 3,4,8, transmitting"
"$BIN" info t.lsqt.lss --json j.json > info.txt
python3 -c 'import json, sys; d = json.load(open("j.json"))["directions"]; n = json.load(open("j.json"))["n_wi"]
sys.exit(not (d["method"] == "grid" and d["grid_ni"] == 4 and d["grid_nphi"] == 8 and n == 40))' && ok \
  || bad "info --json: not the grid 4 x 8 with 40 directions: $(cat j.json | head -c 600)"
grep -q "^directions: grid (--grid: NI 4, NPHI 8)" info.txt && ok || bad "info text: $(grep directions info.txt)"
# --grid N = N,N,4(N-1), a reflecting stack: 5 slices, 5 x 9 directions.
"$BIN" -q -p 256 --grid 5 L.lsqt && python3 check.py L.lsqt.raw 5 5 16 0.5 0 && ok || bad "--grid 5"

# Continuing: the same grid (given again or not) adds paths; another grid or method is an error.
"$BIN" -q -p 256 --grid 3,4,8 t.lsqt && "$BIN" -q -p 256 t.lsqt && ok || bad "continuing the grid"
"$BIN" info t.lsqt.lss | grep -q "^paths: 1024 per slice" && ok || bad "continued grid: not 1024 paths"
expect 2 "--grid 3,4,10 contradicts 't.lsqt.lss' (it is on the grid 3,4,8)" -- "$BIN" -p 256 --grid 3,4,10 t.lsqt
expect 2 "--grid 4,4,8 contradicts" -- "$BIN" -p 256 --grid 4,4,8 t.lsqt
expect 2 "--wi-spread contradicts 't.lsqt.lss' (its incident directions were chosen by --grid)" -- \
  "$BIN" -p 256 --wi-spread t.lsqt
"$BIN" -q -p 256 -wo 4 -wi 16 --wi-spread --lss s.lss -o s.raw L.lsqt
expect 2 "--grid 3,4,8 contradicts 's.lss' (its incident directions were chosen by --wi-spread)" -- \
  "$BIN" -p 256 --grid 3,4,8 --lss s.lss -o s.raw L.lsqt

# Shards of a grid run merge to the bytes of one process.
"$BIN" -q -R -p 1000 --grid 3,3,4 --lss one.lss -o one.raw t.lsqt
for k in 0 1; do "$BIN" -q -R -p 1000 --grid 3,3,4 --shard $k/2 --lss part.lss t.lsqt || bad "shard $k"; done
"$BIN" merge m.lss part.shard-0-of-2.lss part.shard-1-of-2.lss -o m.raw -q && cmp -s m.lss one.lss && cmp -s m.raw one.raw \
  && ok || bad "merged grid shards differ from one process"

# Errors: another choice of directions, bad values, too many directions.
for f in "-wo 4" "-wi 16" "--wi-spread" "-rx 3" "-rp 0.5" "--wo-angles 10,20"; do
  # shellcheck disable=SC2086
  expect 2 "--grid sets the slices and the incident directions, and ${f%% *} chooses" -- "$BIN" --grid 3,4,8 $f L.lsqt
done
printf '0 0 1\n' > one.txt
expect 2 "and --wi-file chooses them too" -- "$BIN" --grid 3,4,8 --wi-file one.txt L.lsqt
for v in 3,4,7 1,4,8 3,1,8 3,4 3,4,8,2 a,b,c 3,4,0 1025,4,8; do
  expect 2 "bad value '$v' for --grid: expected NO,NI,NPHI" -- "$BIN" --grid "$v" L.lsqt
done
expect 2 "2040 incident directions per slice (NI x (NPHI/2 + 1) x 2: this stack transmits), more than the 1024" -- \
  "$BIN" -R --grid 3,20,100 t.lsqt

# --rgl-grid NT,NU: the nodes of an RGL tensor file, computed here from their definition
# (slices at linspace(0, 90 deg, NT), the last at acos 0.001; per slice the reflections of
# wo about the half vectors theta_m = u^2 90 deg, phi_m = (2v - 1) 180 deg, u and v on
# linspace(0, 1, NU), rows v >= 1/2 only (the rest are mirror images), a reflection below
# 1e-4 replaced by wo's mirror direction); a Lambertian's value fR/pi at every one.
cat > rgl.py <<'PY'
import math, sys
raw, nt, nu, fr = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
theta = [math.pi / 2 * k / (nt - 1) for k in range(nt)]
theta[-1] = math.acos(0.001)
lines = open(raw).read().splitlines()
p = []
head = lines[2].split()
if int(head[0]) != nt or any(abs(float(a) - b) > 1e-8 for a, b in zip(head[1:], theta)):
    p.append("slices %r, expected %r" % (head, theta))
rows = [[float(x) for x in l.split()] for l in lines[3:]]
per = (nu - nu // 2) * nu
if len(rows) != 2 * nt * per: p.append("%d lines, expected %d" % (len(rows), 2 * nt * per))
for i, a in enumerate(rows[0::2]):
    s, k = divmod(i, per)
    j, l = nu // 2 + k // nu, k % nu
    u, v = l / (nu - 1), j / (nu - 1)
    tm, pm = u * u * math.pi / 2, (2 * v - 1) * math.pi
    m = (math.sin(tm) * math.cos(pm), math.sin(tm) * math.sin(pm), math.cos(tm))
    wo = (math.sin(theta[s]), 0.0, math.cos(theta[s]))
    c = wo[0] * m[0] + wo[2] * m[2]
    d = [2 * c * m[q] - wo[q] for q in range(3)]
    if not (c > 0 and d[2] >= 1e-4): d = [-wo[0], 0.0, wo[2]]
    d[1] = abs(d[1])
    if max(abs(a[q + 1] - d[q]) for q in range(3)) > 3e-7 or abs(a[4] * math.pi / fr - 1) > 1e-5:
        p.append("slice %d node (%d, %d): %s, expected %s, %g" % (s, j, l, a[1:5], d, fr / math.pi))
if p: sys.exit("\n".join(p[:10]))
PY
"$BIN" -q -p 256 --rgl-grid 4,7 --lss r.lss -o r.raw L.lsqt && python3 rgl.py r.raw 4 7 0.5 && ok || bad "--rgl-grid 4,7"
"$BIN" -q -p 256 --rgl-grid 3,6 --lss r6.lss -o r6.raw t.lsqt && python3 rgl.py r6.raw 3 6 0.3 && ok \
  || bad "--rgl-grid 3,6 (even NU, a transmitting stack: reflection directions only)"
"$BIN" info r.lss --json rj.json > info.txt
python3 -c 'import json, sys; j = json.load(open("rj.json")); d = j["directions"]
sys.exit(not (d["method"] == "rgl_grid" and d["grid_ni"] == 7 and d["grid_nphi"] == 0 and j["n_wi"] == 28))' && ok \
  || bad "info --json: not the RGL grid NU 7 with 28 directions: $(head -c 600 rj.json)"
grep -q "^directions: RGL tensor nodes (--rgl-grid: NU 7)" info.txt && ok || bad "info text: $(grep directions info.txt)"
"$BIN" -q -p 256 --rgl-grid 4,7 --lss r.lss -o r.raw L.lsqt && ok || bad "continuing the RGL grid"
expect 2 "--rgl-grid 4,9 contradicts 'r.lss' (it is on the RGL grid 4,7)" -- "$BIN" --rgl-grid 4,9 --lss r.lss -o r.raw L.lsqt
expect 2 "--grid 4,7,8 contradicts 'r.lss' (it is on the RGL grid 4,7)" -- \
  "$BIN" --grid 4,7,8 --lss r.lss -o r.raw L.lsqt
expect 2 "--rgl-grid 3,4 contradicts 't.lsqt.lss' (it is on the grid 3,4,8)" -- "$BIN" --rgl-grid 3,4 t.lsqt
expect 2 "--grid and --rgl-grid both set" -- "$BIN" --grid 3 --rgl-grid 3,5 L.lsqt
expect 2 "--grid and --rgl-grid both set" -- "$BIN" --rgl-grid 3,5 --grid 3 L.lsqt
for v in 3,45 1,5 3,1 3 3,5,7 a,b 1025,5; do
  expect 2 "bad value '$v' for --rgl-grid: expected NT,NU" -- "$BIN" --rgl-grid "$v" L.lsqt
done
expect 2 "--rgl-grid sets the slices and the incident directions, and -wi chooses them too" -- "$BIN" --rgl-grid 3,5 -wi 20 L.lsqt
# export: each format from its own sampling only, nothing written otherwise
expect 2 "'t.lsqt.lss' is not on the nodes of an RGL tensor (its directions were chosen by --grid)" -- \
  "$BIN" export t.lsqt.lss -o t.bsdf --rgl
expect 2 "'r.lss' is not on a grid (its incident directions were chosen by --rgl-grid)" -- "$BIN" export r.lss -o r.nc
expect 2 "with --rgl the output's name must end in .bsdf" -- "$BIN" export r.lss -o r.nc --rgl
expect 2 "--rgl and --rgl-spectral" -- "$BIN" export r.lss -o r.bsdf --rgl --rgl-spectral
[ -e t.bsdf ] || [ -e r.nc ] || [ -e r.bsdf ] && bad "a refused export wrote a file" || ok
"$BIN" export r.lss -o r.bsdf --rgl > out.txt && grep -q "^wrote r.bsdf: RGL tensor file (rgb), reflection from above at 4 theta_i x 7 x 7" out.txt \
  && head -c 12 r.bsdf | cmp -s - <(printf 'tensor_file\0') && ok || bad "export --rgl: $(cat out.txt)"
ls ./*.tmp.* >/dev/null 2>&1 && bad "temporary files left behind" || ok
finish test_grid
