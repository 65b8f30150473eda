#!/usr/bin/env bash
# lssplot (tools/lssplot): non-empty PNG and SVG plots whose plotted values (its CSV) are
# exactly lsqt-cl info's, band by band for runs with bands (R, G, B; wavelengths), all of
# them or --channel K's; one band's CSV has no band column; a truncated or foreign file, a
# band that is not there, are refused with exit 2.
# usage: test_lssplot.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
PLOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../tools" && pwd)/lssplot"
cli_workdir
cp "$EX/slab.lsqt" S.lsqt
# in-plane directions on both sides, one off the plane, two below the surface
printf '10 0\n30 0\n60 0\n10 180\n30 180\n60 180\n40 90\n120 0\n150 180\n' >ip.txt
"$BIN" -q -p 20000 -wo 4 --wi-file ip.txt --lss S.lss -o S.raw S.lsqt

expect 0 "wrote p.png and p.csv" -- "$PLOT" S.lss -o p.png --csv p.csv --lsqt-cl "$BIN"
[ "$(head -c 8 p.png | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] && [ "$(stat -c %s p.png)" -gt 20000 ] && ok ||
  bad "p.png is not a non-empty PNG"
expect 0 "wrote q.svg" -- "$PLOT" S.lss -o q.svg --log --lsqt-cl "$BIN"
grep -q "<svg" q.svg && ok || bad "q.svg is not an SVG"
expect 0 "wrote S.lss.plot.png" -- env LSQT_CL="$BIN" "$PLOT" S.lss
[ -s S.lss.plot.png ] && ok || bad "no default output S.lss.plot.png"

# Every plotted value is info's, unrounded; the in-plane points are exactly the 8 of 9
# directions per slice that lie in the plane.
"$BIN" info S.lss --json info.json --bsdf >/dev/null
python3 - p.csv info.json <<'PY' && ok || bad "the CSV differs from lsqt-cl info"
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1])))
info = json.load(open(sys.argv[2]))
bsdf = [r for r in rows if r["quantity"] == "bsdf"]
assert len(bsdf) == 8 * len(info["slices"]), len(bsdf)
for r in rows:
    sl = info["slices"][int(r["slice"])]
    if r["quantity"] == "bsdf":
        d = [v for v in sl["bsdf"] if (repr(v[0]), repr(v[1]), repr(v[2])) == (r["x"], r["y"], r["z"])]
        assert len(d) == 1 and float(r["value"]) == d[0][3] and float(r["err"]) == d[0][4], r
        assert abs(d[0][1]) < 1e-6, r
    else:
        assert float(r["value"]) == sl[r["quantity"]] and float(r["err"]) == sl[r["quantity"] + "_err"], r
PY

head -1 p.csv | tr -d '\r' | grep -qx 'quantity,slice,theta_o_deg,angle_deg,x,y,z,value,err' && ok || bad "one band's CSV header: $(head -1 p.csv)"

# Bands: the example paint (R, G, B) and the slab at two wavelengths. cmp.py CSV INFO
# BANDS...: the rows are those of the bands given (by index), each value info's of its band.
cat > cmp.py <<'PY'
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1])))
info = json.load(open(sys.argv[2]))
nb, wl = info["bands"], info["wavelengths"]
labels = ["%.10gnm" % w for w in wl] if wl else ["R", "G", "B"]
want = [int(b) for b in sys.argv[3:]]
assert nb > 1 and [r["band"] for r in rows if r["slice"] == "0" and r["quantity"] == "R"] == [labels[b] for b in want], rows[:3]
n_in = len([r for r in rows if r["quantity"] == "bsdf"]) // len(want)
assert n_in == 6 * len(info["slices"]), n_in  # 6 of 7 directions per slice in the plane
for r in rows:
    b, sl = labels.index(r["band"]), info["slices"][int(r["slice"])]
    if r["quantity"] == "bsdf":
        d = [v for v in sl["bsdf"] if (repr(v[0]), repr(v[1]), repr(v[2])) == (r["x"], r["y"], r["z"])]
        assert len(d) == 1 and float(r["value"]) == d[0][3][b] and float(r["err"]) == d[0][4][b], r
    else:
        assert float(r["value"]) == sl[r["quantity"]][b] and float(r["err"]) == sl[r["quantity"] + "_err"][b], r
print("compared %d rows" % len(rows))
PY
head -7 ip.txt > ip7.txt  # above the surface: the paint transmits nothing
cp "$EX/paint-rgb.lsqt" P.lsqt
"$BIN" -q -p 3000 -wo 4 --wi-file ip7.txt --lss P.lss -o P.raw P.lsqt
"$BIN" info P.lss --json P.json --bsdf >/dev/null
expect 0 "wrote P.png and P.csv" -- "$PLOT" P.lss -o P.png --csv P.csv --lsqt-cl "$BIN"
[ "$(stat -c %s P.png)" -gt 20000 ] && ok || bad "P.png is not a non-empty PNG"
python3 cmp.py P.csv P.json 0 1 2 && ok || bad "the bands' CSV differs from lsqt-cl info"
expect 0 "wrote P1.svg and P1.csv" -- "$PLOT" P.lss -o P1.svg --csv P1.csv --channel 1 --log --lsqt-cl "$BIN"
grep -q "band 1 (G) of 3" P1.svg && ok || bad "P1.svg does not name its band"
python3 cmp.py P1.csv P.json 1 && ok || bad "--channel 1's CSV is not band 1's"
"$BIN" -q -p 3000 -wo 4 --wi-file ip.txt --wavelengths 450,650 --lss W.lss -o W.raw S.lsqt
"$BIN" info W.lss --json W.json --bsdf >/dev/null
expect 0 "wrote W.png and W.csv" -- "$PLOT" W.lss -o W.png --csv W.csv --lsqt-cl "$BIN"
python3 - W.csv W.json <<'PY' && ok || bad "the wavelengths' CSV differs from lsqt-cl info"
import csv, json, sys
rows, info = list(csv.DictReader(open(sys.argv[1]))), json.load(open(sys.argv[2]))
assert {r["band"] for r in rows} == {"450nm", "650nm"}, rows[0]
for r in rows:
    b, sl = ["450nm", "650nm"].index(r["band"]), info["slices"][int(r["slice"])]
    if r["quantity"] != "bsdf":
        assert float(r["value"]) == sl[r["quantity"]][b], r
PY
expect 2 "--channel 3: 'P.lss' has 3 bands: K must be 0 to 2" -- "$PLOT" P.lss -o c.png --channel 3 --lsqt-cl "$BIN"
expect 2 "--channel 1: 'S.lss' has one band: K must be 0" -- "$PLOT" S.lss -o c.png --channel 1 --lsqt-cl "$BIN"

# Bad input: a truncated LSS, no LSS, a bad output name.
head -c 300 S.lss >cut.lss
expect 2 "truncated" -- "$PLOT" cut.lss -o c.png --lsqt-cl "$BIN"
[ ! -e c.png ] && ok || bad "a refused file still got a plot"
expect 2 "not an LSS file" -- "$PLOT" S.lsqt -o c.png --lsqt-cl "$BIN"
expect 2 "must end in .png or .svg" -- "$PLOT" S.lss -o c.jpg --lsqt-cl "$BIN"
finish test_lssplot
