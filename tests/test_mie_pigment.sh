#!/usr/bin/env bash
# tools/mie_pigment.py (miepython from PyPI, label "clients") against formulas written
# here, and the committed tables of examples/tio2-paint.lsqt against the tool:
#  1. the Rayleigh limit: spheres of radius 1 nm (x = 2 pi r n_binder / lam <= 0.021) of
#     index 2.25 + 0.03i in a binder of index 1.5 (relative index 1.5 + 0.02i): mus =
#     fv 3 qsca / (4 r) with qsca = 8/3 x^4 |K|^2 and the particles' mua = fv 3 qabs /
#     (4 r) with qabs = 4 x Im K, K = (m^2 - 1)/(m^2 + 2) (Bohren and Huffman 1983, 5.8;
#     both to 1e-3, their first corrections being of order x^2 < 5e-4), g -> 0 (|g| <
#     1e-3); a wrong size parameter (the vacuum wavelength) or the absolute index fails;
#  2. a sphere with k = 0: mua is the binder's alone, (1 - fv) binder_mua, to 1e-6;
#  3. the built-in rutile index equals --index-table of DeVore's formula (written here)
#     and --m equals a table of the same constant index (the same values to 1e-6);
#  4. the committed examples/tables/tio2_{mus,mua,g}.txt: 400 to 2500 nm every 1 nm, the
#     tool's defaults in their header, and the tool's values at six wavelengths (edges,
#     visible, infrared, one past DeVore's fitted range) to 2e-6 relative (the 6th digit);
#  5. bad arguments refused (exit status not 0, a message naming them).
# miepython comes from the venv LSQT_CLIENT_VENV (default BUILD/client-venv) or
# BUILD/validate-venv when one has it, else it is installed into the first (pip install
# miepython); the test is skipped (77) only where that cannot be done.
# usage: test_mie_pigment.sh SOURCE_DIR BUILD_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args SRC BUILD -- "$@"
cli_tmpdir

VENV=${LSQT_CLIENT_VENV:-$BUILD/client-venv}
PY=
for v in "$VENV" "$BUILD/validate-venv"; do
  if "$v/bin/python" -c 'import miepython, numpy' 2>/dev/null; then PY=$v/bin/python; break; fi
done
if [ -z "$PY" ]; then
  echo "test_mie_pigment: installing miepython from PyPI into $VENV"
  if ! { { [ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"; } &&
         "$VENV/bin/python" -m pip install -q miepython; } > "$T/pip.log" 2>&1; then
    tail -5 "$T/pip.log"
    echo "test_mie_pigment: skipped: miepython cannot be installed from PyPI here (no network or no python3-venv)"
    exit 77
  fi
  PY=$VENV/bin/python
fi
TOOL=$SRC/tools/mie_pigment.py
TABLES=$SRC/examples/tables
cd "$T" || exit 1

# 1, 2: the Rayleigh limit; k = 0.
"$PY" "$TOOL" --m 2.25+0.03j --binder-index 1.5 --radius-um 0.001 --volume-fraction 0.1 --binder-mua 0.02 \
  --wavelengths 450,800,2000 ray >/dev/null && ok || bad "mie_pigment.py (Rayleigh) failed"
"$PY" "$TOOL" --m 2.25+0j --binder-index 1.5 --radius-um 0.001 --volume-fraction 0.1 --binder-mua 0.02 \
  --wavelengths 450,800,2000 clear >/dev/null && ok || bad "mie_pigment.py (k = 0) failed"
python3 - <<'PY' && ok || bad "the Rayleigh limit or the binder's absorption"
import math, sys

def table(path):
    return [tuple(float(v) for v in l.split()) for l in open(path) if l.strip() and not l.startswith("#")]

bad = []
r_um, fv, nb, mua_b = 0.001, 0.1, 1.5, 0.02
m = complex(2.25, 0.03) / nb
K = (m * m - 1) / (m * m + 2)
r_mm = r_um * 1e-3
mus, mua, g = table("ray_mus.txt"), table("ray_mua.txt"), table("ray_g.txt")
for (nm, s), (_, a), (_, gg) in zip(mus, mua, g):
    x = 2 * math.pi * r_um * nb / (nm / 1000)
    want_s = fv * 3 * (8 / 3 * x ** 4 * abs(K) ** 2) / (4 * r_mm)
    want_a = fv * 3 * (4 * x * K.imag) / (4 * r_mm) + (1 - fv) * mua_b
    for name, have, want in (("mus", s, want_s), ("mua", a, want_a)):
        if abs(have / want - 1) > 1e-3:
            bad.append("%g nm: %s %.6g, Rayleigh %.6g (x %.4g)" % (nm, name, have, want, x))
    if abs(gg) > 1e-3:
        bad.append("%g nm: g %.3g, not near 0" % (nm, gg))
for nm, a in table("clear_mua.txt"):
    if abs(a / ((1 - fv) * mua_b) - 1) > 1e-6:
        bad.append("%g nm: k = 0, mua %.6g, not (1 - fv) binder_mua = %.6g" % (nm, a, (1 - fv) * mua_b))
if len(mus) != 3 or len(table("clear_mua.txt")) != 3:
    bad.append("not three rows")
for b in bad:
    print("FAIL: " + b, file=sys.stderr)
sys.exit(1 if bad else 0)
PY

# 3: the built-in index against DeVore's formula as a table; --m against a table.
NMS=420,700,1900
python3 - "$NMS" <<'PY'
import sys
with open("devore.txt", "w") as f:
    f.write("# rutile, ordinary ray: DeVore, J. Opt. Soc. Am. 41, 416 (1951)\n")
    for nm in (float(v) for v in sys.argv[1].split(",")):
        l2 = (nm / 1000) ** 2
        f.write("%g, %.12g, 0\n" % (nm, (5.913 + 0.2441 / (l2 - 0.0803)) ** 0.5))
open("const.txt", "w").write("300 2.1 0.05\n3000 2.1 0.05\n")
PY
"$PY" "$TOOL" --wavelengths $NMS builtin >/dev/null &&
  "$PY" "$TOOL" --wavelengths $NMS --index-table devore.txt devore >/dev/null &&
  "$PY" "$TOOL" --wavelengths $NMS --m 2.1+0.05j m >/dev/null &&
  "$PY" "$TOOL" --wavelengths $NMS --index-table const.txt const >/dev/null && ok || bad "mie_pigment.py (index) failed"
python3 - <<'PY' && ok || bad "the built-in index or --index-table"
import sys
def table(path):
    return [tuple(float(v) for v in l.split()) for l in open(path) if l.strip() and not l.startswith("#")]
bad = []
for a, b in (("builtin", "devore"), ("m", "const")):
    for q in ("mus", "mua", "g"):
        ta, tb = table("%s_%s.txt" % (a, q)), table("%s_%s.txt" % (b, q))
        if len(ta) != 3 or [r[0] for r in ta] != [r[0] for r in tb] or \
                any(abs(x[1] - y[1]) > 1e-6 * abs(y[1]) for x, y in zip(ta, tb)):
            bad.append("%s_%s %s != %s_%s %s" % (a, q, ta, b, q, tb))
for b in bad:
    print("FAIL: " + b, file=sys.stderr)
sys.exit(1 if bad else 0)
PY

# 4: the committed tables are the tool's output with its defaults.
"$PY" "$TOOL" --wavelengths 400,401,550,1000,1531,2500 now >/dev/null && ok || bad "mie_pigment.py (defaults) failed"
python3 - "$TABLES" <<'PY' && ok || bad "the committed tables differ from the tool's output"
import sys
tables = sys.argv[1]
def table(path):
    return [tuple(float(v) for v in l.split()) for l in open(path) if l.strip() and not l.startswith("#")]
bad = []
for q in ("mus", "mua", "g"):
    path = "%s/tio2_%s.txt" % (tables, q)
    made = [l for l in open(path) if l.startswith("# made by: ")]
    want = ("# made by: python3 tools/mie_pigment.py --radius-um 0.12 --volume-fraction 0.15 --binder-index 1.5 "
            "--binder-mua 0.01 --wavelengths 400:2500:1 examples/tables/tio2\n")
    if made != [want]:
        bad.append("%s: made by %r, not the defaults' command" % (path, made))
    rows = table(path)
    if [r[0] for r in rows] != [float(nm) for nm in range(400, 2501)]:
        bad.append("%s: not 400 to 2500 nm every 1 nm" % path)
    have = dict(rows)
    for nm, v in table("now_%s.txt" % q):
        if nm not in have or abs(have[nm] - v) > 2e-6 * abs(v):
            bad.append("%s at %g nm: %s, the tool now %.6g" % (path, nm, have.get(nm), v))
for b in bad:
    print("FAIL: " + b, file=sys.stderr)
sys.exit(1 if bad else 0)
PY

# 5: bad arguments.
expect 1 "--volume-fraction out of range" -- "$PY" "$TOOL" --volume-fraction 1 --wavelengths 550 x
expect 1 "covers 300 to 3000 nm" -- "$PY" "$TOOL" --index-table const.txt --wavelengths 250,550 x
expect 1 "wavelengths must be positive and increasing" -- "$PY" "$TOOL" --wavelengths 550,450 x
expect 2 "not allowed with argument" -- "$PY" "$TOOL" --m 2+0j --index-table const.txt x
finish test_mie_pigment
