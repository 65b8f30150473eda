#!/usr/bin/env bash
# lssplot (tools/lssplot): non-empty PNG and SVG plots whose plotted values (its CSV) are
# exactly lsqt-cl info's; a truncated or foreign file is refused with exit 2.
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

# Bad input: a truncated LSS, no LSS, a bad output name.
head -c 300 S.lss >cut.lss
expect 2 "truncated" -- "$PLOT" cut.lss -o c.png --lsqt-cl "$BIN"
[ ! -e c.png ] && ok || bad "a refused file still got a plot"
expect 2 "not an LSS file" -- "$PLOT" S.lsqt -o c.png --lsqt-cl "$BIN"
expect 2 "must end in .png or .svg" -- "$PLOT" S.lss -o c.jpg --lsqt-cl "$BIN"
finish test_lssplot
