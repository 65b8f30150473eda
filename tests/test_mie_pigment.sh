#!/usr/bin/env bash
# tools/mie_pigment.py (miepython from PyPI, label "clients") against formulas written
# here, and the committed tables of examples/tio2-paint.lsqt against the tool:
#  1. the Rayleigh limit: spheres of one radius, 1 nm (--sigma-g 1; x = 2 pi r n_binder /
#     lam <= 0.021), of index 2.25 + 0.03i in a binder of index 1.5 (relative index 1.5 +
#     0.02i): mus = fv 3 qsca / (4 r) with qsca = 8/3 x^4 |K|^2 and the particles' mua =
#     fv 3 qabs / (4 r) with qabs = 4 x Im K, K = (m^2 - 1)/(m^2 + 2) (Bohren and Huffman
#     1983, 5.8; both to 1e-3, their first corrections being of order x^2 < 5e-4), g -> 0
#     (|g| < 1e-3); a wrong size parameter (the vacuum wavelength) or the absolute index
#     fails;
#  1b. the Rayleigh limit of lognormal sizes, volume-median radius r_v 1 nm, sigma_g 1.6,
#     from the moments by number, written here: ln r normal (s = ln sigma_g), number-median
#     r_n = r_v exp(-3 s^2), <r^j> = r_n^j exp(j^2 s^2 / 2); with k = 2 pi n_binder / lam,
#     Csca = 8/3 pi k^4 |K|^2 r^6 and Cabs = 4 pi k Im K r^3, mus = fv <Csca> / <V> =
#     2 fv k^4 |K|^2 <r^6> / <r^3> and the particles' mua = fv <Cabs> / <V> = 3 fv k Im K
#     (to 1e-3; the largest spheres that count, r^6-weighted, are near 4 nm: corrections
#     < 4e-4); and, as one sphere's g is c x^2 to first order (c from check 1's 1 nm
#     spheres, g1), g = <g Csca> / <Csca> = g1 <r^8> / (<r^6> r_v^2) (to 2e-3). Radii
#     averaged by volume where by number (or the radius taken as the number-median) are
#     7.3 times off, g weighted by qsca where by Csca 1.56 times;
#  2. a sphere with k = 0: mua is the binder's alone, (1 - fv) binder_mua, to 1e-6;
#  2b. --sigma-g 1 is the one-radius formulas exactly: the tool's values (17 digits) equal
#     fv 3 qsca / (4 r), fv 3 (qext - qsca) / (4 r) + (1 - fv) binder_mua and g computed
#     here from miepython (pure Python, MIEPYTHON_USE_JIT=0, in both) for index 2.1 +
#     0.05i, radius 0.12 um, bit for bit; and --sigma-g 1.001 is within 1e-4 of them (the
#     quadrature's weights and radii tend to the one radius);
#  3. the built-in rutile index equals --index-table of DeVore's formula (written here)
#     and --m equals a table of the same constant index (the same values to 1e-6);
#  4. the committed examples/tables/tio2_{mus,mua,g}.txt: 400 to 2500 nm every 1 nm, the
#     tool's defaults in their header (sigma_g 1.4, 801 nodes), and the tool's values at
#     six wavelengths (edges, visible, infrared, one past DeVore's fitted range) to 2e-6
#     relative (the 6th digit), the tool run as a user runs it (numba's compiled miepython
#     where the venv has numba; the other runs here use miepython's pure Python, faster to
#     start for a few wavelengths);
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
export MIEPYTHON_USE_JIT=0

# 1, 2: the Rayleigh limit; k = 0.
"$PY" "$TOOL" --m 2.25+0.03j --binder-index 1.5 --radius-um 0.001 --sigma-g 1 --volume-fraction 0.1 \
  --binder-mua 0.02 --wavelengths 450,800,2000 ray >/dev/null && ok || bad "mie_pigment.py (Rayleigh) failed"
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

# 1b: the Rayleigh limit of lognormal sizes, from the moments by number.
"$PY" "$TOOL" --m 2.25+0.03j --binder-index 1.5 --radius-um 0.001 --sigma-g 1.6 --volume-fraction 0.1 \
  --binder-mua 0.02 --wavelengths 450,800,2000 logn >/dev/null && ok || bad "mie_pigment.py (lognormal Rayleigh) failed"
python3 - <<'PY' && ok || bad "the Rayleigh limit of lognormal sizes"
import math, sys

def table(path):
    return [tuple(float(v) for v in l.split()) for l in open(path) if l.strip() and not l.startswith("#")]

bad = []
r_v, sigma_g, fv, nb, mua_b = 0.001e-3, 1.6, 0.1, 1.5, 0.02  # r_v in mm
s2 = math.log(sigma_g) ** 2
r_n = r_v * math.exp(-3 * s2)  # the number-median of a lognormal whose volume-median is r_v


def moment(j):  # <r^j> by number
    return r_n ** j * math.exp(j * j * s2 / 2)


m = complex(2.25, 0.03) / nb
K = (m * m - 1) / (m * m + 2)
rows = list(zip(table("logn_mus.txt"), table("logn_mua.txt"), table("logn_g.txt"), table("ray_g.txt")))
for (nm, s), (_, a), (_, gg), (_, g1) in rows:
    k = 2 * math.pi * nb / (nm * 1e-6)  # per mm, in the binder
    v = 4 / 3 * math.pi * moment(3)
    want_s = fv * (8 / 3 * math.pi * k ** 4 * abs(K) ** 2 * moment(6)) / v
    want_a = fv * (4 * math.pi * k * K.imag * moment(3)) / v + (1 - fv) * mua_b
    want_g = g1 * moment(8) / (moment(6) * r_v ** 2)
    for name, have, want, tol in (("mus", s, want_s, 1e-3), ("mua", a, want_a, 1e-3), ("g", gg, want_g, 2e-3)):
        if abs(have / want - 1) > tol:
            bad.append("%g nm: %s %.6g, lognormal Rayleigh %.6g" % (nm, name, have, want))
if len(rows) != 3:
    bad.append("not three rows")
for b in bad:
    print("FAIL: " + b, file=sys.stderr)
sys.exit(1 if bad else 0)
PY

# 2b: --sigma-g 1 is the one-radius formulas bit for bit; --sigma-g 1.001 near them.
"$PY" "$TOOL" --m 2.1+0.05j --radius-um 0.12 --sigma-g 1 --digits 17 --wavelengths 450,800,2000 one >/dev/null &&
  "$PY" "$TOOL" --m 2.1+0.05j --radius-um 0.12 --sigma-g 1.001 --digits 17 --wavelengths 450,800,2000 near >/dev/null &&
  ok || bad "mie_pigment.py (--sigma-g 1, 1.001) failed"
"$PY" - <<'PY' && ok || bad "--sigma-g 1 is not the one-radius formulas, or --sigma-g 1.001 not near them"
import math, sys
import numpy as np
import miepython

def table(path):
    return [tuple(float(v) for v in l.split()) for l in open(path) if l.strip() and not l.startswith("#")]

bad = []
r_um, fv, nb, mua_b = 0.12, 0.15, 1.5, 0.01
lam = np.array([450.0, 800.0, 2000.0])
m_rel = np.array([complex(2.1, -0.05)] * 3) / nb
x = 2 * math.pi * r_um * 1000.0 * nb / lam
qext, qsca, _, g = miepython.efficiencies_mx(m_rel, x)
r_mm = r_um * 1e-3
want = {"mus": fv * 3 * qsca / (4 * r_mm),
        "mua": fv * 3 * np.maximum(qext - qsca, 0.0) / (4 * r_mm) + (1 - fv) * mua_b,
        "g": g}
for q in ("mus", "mua", "g"):
    one, near = table("one_%s.txt" % q), table("near_%s.txt" % q)
    if [r[0] for r in one] != list(lam) or [r[0] for r in near] != list(lam):
        bad.append("%s: not the three wavelengths" % q)
        continue
    for (nm, v), (_, u), w in zip(one, near, want[q]):
        if v != float(w):
            bad.append("%g nm: --sigma-g 1 %s %r, the one-radius formula %r" % (nm, q, v, float(w)))
        if abs(u / w - 1) > 1e-4:
            bad.append("%g nm: --sigma-g 1.001 %s %.9g, one radius %.9g" % (nm, q, u, w))
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
env -u MIEPYTHON_USE_JIT "$PY" "$TOOL" --wavelengths 400,401,550,1000,1531,2500 now >/dev/null && ok ||
  bad "mie_pigment.py (defaults) failed"
python3 - "$TABLES" <<'PY' && ok || bad "the committed tables differ from the tool's output"
import sys
tables = sys.argv[1]
def table(path):
    return [tuple(float(v) for v in l.split()) for l in open(path) if l.strip() and not l.startswith("#")]
bad = []
for q in ("mus", "mua", "g"):
    path = "%s/tio2_%s.txt" % (tables, q)
    made = [l for l in open(path) if l.startswith("# made by: ")]
    want = ("# made by: python3 tools/mie_pigment.py --radius-um 0.12 --sigma-g 1.4 --nodes 801 --volume-fraction 0.15 "
            "--binder-index 1.5 --binder-mua 0.01 --wavelengths 400:2500:1 examples/tables/tio2\n")
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
expect 1 "--sigma-g out of range" -- "$PY" "$TOOL" --sigma-g 0.9 --wavelengths 550 x
expect 1 "--nodes out of range" -- "$PY" "$TOOL" --nodes 1 --wavelengths 550 x
expect 1 "covers 300 to 3000 nm" -- "$PY" "$TOOL" --index-table const.txt --wavelengths 250,550 x
expect 1 "wavelengths must be positive and increasing" -- "$PY" "$TOOL" --wavelengths 550,450 x
expect 2 "not allowed with argument" -- "$PY" "$TOOL" --m 2+0j --index-table const.txt x
finish test_mie_pigment
