#!/usr/bin/env bash
# lsqt-cl export --rgl: the tutorial's Rough and Substr on an --rgl-grid, written as RGL
# tensor files and loaded by a real client, Mitsuba 3's `measured` BSDF (PyPI mitsuba,
# variants scalar_rgb for --rgl and scalar_spectral for --rgl-spectral). Checks:
#  1. at every node of every slice Mitsuba's eval equals lsqt-cl's own value there
#     (info --json --bsdf: f times the cosine of the incident direction, found by
#     geometry from the parameterisation of Dupuy and Jakob 2018, not by the exporter's
#     index arithmetic) to float32 rounding; the extra field `stderr`, read by an
#     independent reader written here, equals info's standard errors;
#  2. at 64 direction pairs per stack off the nodes (slices between and on the tensor's
#     theta_i, 16 directions from a --wi-file), Mitsuba's interpolated value agrees with
#     an independent run (another seed, --wi-file) within 4 standard errors (both runs)
#     plus the interpolation error: for the reader's trilinear interpolation in (theta_i,
#     v, u), sum over the three axes of max |second difference| / 8 over the cell's
#     corners (the bound h^2 |f''| / 8 of linear interpolation, f'' from the tensor);
#  3. Mitsuba's importance sampling of the luminance table is unbiased: the albedo it
#     estimates equals the one from uniform hemisphere sampling of eval (z < 4);
#  4. runs with bands (the example paint, R, G, B; the example gold at seven wavelengths):
#     rgb holds R, G, B, or the linear sRGB of each node's spectrum (recomputed from
#     Mitsuba's CIE tables, not lsqt-cl's), spectra the bands at the run's wavelengths,
#     stderr each band's error, and Mitsuba's eval returns them; what a file cannot hold
#     (--rgl-spectral without wavelengths, two unnamed bands) is refused, exit 2.
# Mitsuba comes from the venv LSQT_CLIENT_VENV (default BUILD/client-venv) or
# BUILD/validate-venv when one has it, else it is installed into the first (pip install
# mitsuba numpy); the test is skipped (77) only where that cannot be done.
# usage: test_rgl.sh LSQT_CL EXAMPLES_DIR BUILD_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX BUILD -- "$@"
cli_tmpdir

VENV=${LSQT_CLIENT_VENV:-$BUILD/client-venv}
PY=
for v in "$VENV" "$BUILD/validate-venv"; do
  if "$v/bin/python" -c 'import mitsuba, numpy' 2>/dev/null; then PY=$v/bin/python; break; fi
done
if [ -z "$PY" ]; then
  echo "test_rgl: installing mitsuba and numpy from PyPI into $VENV"
  if ! { python3 -m venv "$VENV" && "$VENV/bin/python" -m pip install -q mitsuba numpy; } > "$T/pip.log" 2>&1; then
    tail -5 "$T/pip.log"
    echo "test_rgl: skipped: mitsuba cannot be installed from PyPI here (no network or no python3-venv)"
    exit 77
  fi
  PY=$VENV/bin/python
fi
cd "$T"

cp "$EX/tutorial/Rough.lsqt" R.lsqt
cp "$EX/tutorial/Substr.lsqt" S.lsqt
# 16 incident directions (theta, phi in degrees) spread over the hemisphere, off the nodes.
for t in 8 27 43 61; do for p in 17 71 133 166; do echo "$((t + p % 5)) $p"; done; done > dirs.txt

# tensor.py: an independent reader of the tensor file format (check.py, bands.py).
cat > tensor.py <<'PY'
import struct, sys
import numpy as np

def read_tensor(path, p):
    """The fields of the file at path: name -> numpy array; problems appended to p."""
    b = open(path, "rb").read()
    if b[:12] != b"tensor_file\0": sys.exit("%s: no tensor_file header" % path)
    n = struct.unpack_from("<I", b, 14)[0]
    at, out = 18, {}
    for _ in range(n):
        ln = struct.unpack_from("<H", b, at)[0]; name = b[at + 2:at + 2 + ln].decode(); at += 2 + ln
        nd, dt, off = struct.unpack_from("<HBQ", b, at); at += 11
        shape = struct.unpack_from("<%dQ" % nd, b, at); at += 8 * nd
        dtype = {1: np.uint8, 10: np.float32}[dt]
        if off % 8: p.append("%s: field %s not 8-byte aligned" % (path, name))
        out[name] = np.frombuffer(b, dtype, int(np.prod(shape)), off).reshape(shape)
    return out
PY

cat > check.py <<'PY'
import json, math, sys
import numpy as np
import mitsuba as mi
from tensor import read_tensor

tensor, tensor_s, info_path, wi_path, nt, nu = sys.argv[1:5] + [int(a) for a in sys.argv[5:7]]
p = []

tf = read_tensor(tensor, p)
theta_nodes = [math.pi / 2 * k / (nt - 1) for k in range(nt)]
theta_nodes[-1] = math.acos(0.001)  # the horizon, simulated there
if not np.allclose(tf["theta_i"], theta_nodes, rtol=0, atol=1e-6): p.append("theta_i %s" % tf["theta_i"])
info = json.load(open(info_path))
slices = [s for s in info["slices"] if not s["from_below"]]

def node_dirs(theta, j, l):
    """wi (the slice, Mitsuba's si.wi), m, and the reflection wo of node (j, l)."""
    u, v = l / (nu - 1), j / (nu - 1)
    tm, pm = u * u * math.pi / 2, (2 * v - 1) * math.pi
    m = np.array([math.sin(tm) * math.cos(pm), math.sin(tm) * math.sin(pm), math.cos(tm)])
    wi = np.array([math.sin(theta), 0.0, math.cos(theta)])
    return wi, m, 2 * wi.dot(m) * m - wi

def mitsuba_bsdf(variant, path):
    mi.set_variant(variant)
    return mi.load_dict({"type": "measured", "filename": path})

def ev(bsdf, variant, wi, wo):
    si = mi.SurfaceInteraction3f()
    # At the pole the azimuth of wi is undefined and Mitsuba takes it as pi (it rotates the
    # table by pi); lsqt-cl measures azimuths from wo's, 0: the limit from phi = 0.
    si.wi = mi.Vector3f(*wi) if wi[0] != 0 else mi.Vector3f(1e-20, wi[1], wi[2])
    if variant == "scalar_spectral": si.wavelengths = [400, 500, 600, 700]
    return [float(x) for x in bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*wo))]

# 1. every node: Mitsuba's eval = info's f cos(theta_i), and stderr = info's error
checked = 0
V0 = tf["rgb"][0, :, 0]
for variant, path in (("scalar_rgb", tensor), ("scalar_spectral", tensor_s)):
    b = mitsuba_bsdf(variant, path)
    for k, s in enumerate(slices):
        if abs(s["theta_o"] - theta_nodes[k]) > 1e-12: p.append("slice %d at %g" % (k, s["theta_o"]))
        for j in range(nu):
            for l in range(nu):
                wi, m, wo = node_dirs(s["theta_o"], j, l)
                if wi.dot(m) <= 0 or wo[2] < 1e-4: continue
                hit = [h for h in s["bsdf"] if abs(h[0] - wo[0]) < 2e-6 and abs(h[1] - abs(wo[1])) < 2e-6 and abs(h[2] - wo[2]) < 2e-6]
                if not hit: p.append("slice %d node (%d, %d): direction %s not simulated" % (k, j, l, wo)); continue
                want, werr = hit[0][3] * hit[0][2], hit[0][4]
                got = ev(b, variant, wi, wo)
                # Mitsuba finds the node's (u, v) in float32 (u = sqrt(theta_m / (pi/2)) is
                # steep at 0): allow 1 % of the step to a neighbouring node.
                nb = [V0[k2, j2, l2] for k2, j2, l2 in ((k - 1, j, l), (k + 1, j, l), (k, j - 1, l), (k, j + 1, l),
                      (k, j, l - 1), (k, j, l + 1)) if 0 <= k2 < nt and 0 <= j2 < nu and 0 <= l2 < nu]
                step = max(abs(x - V0[k, j, l]) for x in nb)
                if any(abs(g - want) > 3e-5 * abs(want) + 0.01 * step + 1e-9 for g in got):
                    p.append("%s slice %d node (%d, %d): mitsuba %s, lsqt-cl %g" % (variant, k, j, l, got, want))
                se = float(tf["stderr"][0, k, j, l])
                if variant == "scalar_rgb" and not (werr is None and math.isnan(se)) and \
                        abs(se - (werr or 0) * hit[0][2]) > 1e-5 * abs(werr or 0) * hit[0][2] + 1e-12:
                    p.append("stderr slice %d node (%d, %d): %g, info %s" % (k, j, l, se, werr))
                checked += 1
print("nodes: %d evaluations, %d differ from lsqt-cl's values" % (checked, len(p)))

# 2. off the nodes: Mitsuba's interpolation against an independent --wi-file run
b = mitsuba_bsdf("scalar_rgb", tensor)
V, E = tf["rgb"][0, :, 0], tf["stderr"][0]   # [theta_i][v][u]
w = json.load(open(wi_path))
theta = np.array(theta_nodes)
def cell(x, n):  # the interpolation cell of coordinate x in [0, n-1] and its weights' corners
    i = min(int(math.floor(x)), n - 2)
    return [i, i + 1]
def d2(a, axis, idx):  # |second difference| at idx along axis (one-sided at an edge)
    n = a.shape[axis]; i = idx[axis]
    if n < 3: return 0.0
    c = min(max(i, 1), n - 2)
    g = lambda t: a[tuple(t if ax == axis else idx[ax] for ax in range(3))]
    return abs(g(c - 1) - 2 * g(c) + g(c + 1))
pairs, worst, zmax, outside, rel_i, rel_d, rels = 0, 0.0, 0.0, 0, 0.0, 0.0, []
for s in w["slices"]:
    th = s["theta_o"]
    ks = cell(np.interp(th, theta, np.arange(nt)), nt)
    for h in s["bsdf"]:
        wo = np.array(h[:3]); wi = np.array([math.sin(th), 0.0, math.cos(th)])
        m = (wi + wo) / np.linalg.norm(wi + wo)
        tm = 2 * math.asin(min(1.0, 0.5 * math.sqrt(m[0] ** 2 + m[1] ** 2 + (m[2] - 1) ** 2)))
        u, v = math.sqrt(tm / (math.pi / 2)), (math.atan2(m[1], m[0]) + math.pi) / (2 * math.pi)
        js, ls = cell(v * (nu - 1), nu), cell(u * (nu - 1), nu)
        corners = [(a, c, d) for a in ks for c in js for d in ls]
        interp = sum(max(d2(V, ax, q) for q in corners) for ax in range(3)) / 4
        sig_c = max(E[q] for q in corners)
        got = ev(b, "scalar_rgb", wi, wo)[0]
        want, werr = h[3] * wo[2], h[4] * wo[2]
        tol = 4 * math.hypot(werr, sig_c) + interp
        if abs(got - want) > tol:
            outside += 1
            p.append("theta_i %.2f deg, wo %s: mitsuba %g, lsqt-cl %g +- %g (tolerance %g, interpolation %g)"
                     % (math.degrees(th), np.round(wo, 4), got, want, werr, tol, interp))
        zmax = max(zmax, abs(got - want) / math.hypot(werr, sig_c))
        worst = max(worst, abs(got - want) / tol)
        rel_i, rel_d = max(rel_i, interp / abs(want)), max(rel_d, abs(got - want) / abs(want))
        rels.append(abs(got - want) / abs(want))
        pairs += 1
if pairs < 50: p.append("only %d pairs" % pairs)
print("pairs: %d off the nodes, %d outside the tolerance (largest |difference| / tolerance %.2f, / s.e. %.1f, "
      "/ value %.3f, median %.3f; largest interpolation bound / value %.3f)"
      % (pairs, outside, worst, zmax, rel_d, float(np.median(rels)), rel_i))

# 3. Mitsuba's sampling of the table against uniform sampling of its eval (the albedo)
rng = np.random.default_rng(7)
for th in (0.3, 0.9):
    wi = [math.sin(th), 0.0, math.cos(th)]
    si = mi.SurfaceInteraction3f(); si.wi = mi.Vector3f(*wi)
    n = 4000
    imp = [float(b.sample(mi.BSDFContext(), si, float(rng.random()), mi.Point2f(*rng.random(2)))[1][0]) for _ in range(n)]
    uni = []
    for _ in range(n):
        z, ph = rng.random(), 2 * math.pi * rng.random()
        r = math.sqrt(1 - z * z)
        uni.append(ev(b, "scalar_rgb", wi, [r * math.cos(ph), r * math.sin(ph), z])[0] * 2 * math.pi)
    a, sa = np.mean(imp), np.std(imp) / math.sqrt(n)
    c, sc = np.mean(uni), np.std(uni) / math.sqrt(n)
    z = (a - c) / math.hypot(sa, sc)
    print("albedo at theta_i %.2f: sampled %.4f +- %.4f, uniform %.4f +- %.4f (z %.2f)" % (th, a, sa, c, sc, z))
    if abs(z) > 4: p.append("sampling biased at theta_i %.2f: z %.2f" % (th, z))
if p: sys.exit("%d problems:\n" % len(p) + "\n".join(p[:6] + p[-6:]))
PY

# One stack: NAME FILE PATHS. The tensor run (seed 1), the --wi-file run (seed 2) on slices
# at the tensor's theta_i and between them.
one() {
  local n=$1 f=$2 paths=$3
  "$BIN" -q -s 1 -p "$paths" --rgl-grid 9,15 "$f" && ok || bad "$n: --rgl-grid run"
  "$BIN" export "$f.lss" -o "$n.bsdf" --rgl -q && "$BIN" export "$f.lss" -o "$n.s.bsdf" --rgl-spectral -q \
    && ok || bad "$n: export --rgl"
  "$BIN" info "$f.lss" --json "$n.json" --bsdf > /dev/null
  "$BIN" -q -s 2 -p "$paths" --wo-angles=0,5.625,16.875,33.75,50.625,73.125 --wi-file dirs.txt --lss "$n.w.lss" \
    -o "$n.w.raw" "$f" && "$BIN" info "$n.w.lss" --json "$n.w.json" --bsdf > /dev/null && ok || bad "$n: --wi-file run"
  "$PY" check.py "$n.bsdf" "$n.s.bsdf" "$n.json" "$n.w.json" 9 15 > "$n.out" 2>&1 && ok || bad "$n in Mitsuba: $(cat "$n.out")"
  sed "s/^/  $n: /" "$n.out"
}
one Rough R.lsqt 20000
one Substr S.lsqt 20000

# bands.py RGB_TENSOR SPECTRAL_TENSOR|- INFO_JSON NT NU: a run with bands. At every node the
# rgb field holds R, G, B as they are (unnamed bands), or the linear sRGB of the node's
# spectrum, recomputed here from Mitsuba's own CIE 1931 and D65 tables (the spectrum
# linear between the bands, its end values held; the white corrected to grey); spectra
# holds each band at the run's wavelengths; stderr each band's error; the values from info
# (f times the cosine of the incident direction). Then Mitsuba's eval at the nodes: rgb
# (scalar_rgb) and, at four of the bands' wavelengths, the spectra (scalar_spectral).
cat > bands.py <<'PY'
import json, math, sys
import numpy as np
import mitsuba as mi
from tensor import read_tensor

rgb_path, spec_path, info_path, nt, nu = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
p = []
info = json.load(open(info_path))
nb, wl = info["bands"], info["wavelengths"]
tf = read_tensor(rgb_path, p)
ts = read_tensor(spec_path, p) if spec_path != "-" else None
mi.set_variant("scalar_spectral")
L = np.arange(360.0, 831.0)
E = np.array([float(mi.cie_d65(float(x))) for x in L])
CMF = np.array([[float(c) for c in mi.cie1931_xyz(float(x))] for x in L])
W = (E[:, None] * CMF).sum(0)
def srgb(x): return np.array([float(c) for c in mi.xyz_to_srgb(mi.Color3f(*x))])
WHITE = srgb(W / W[1])
def colour(v):  # a spectrum at wl as linear sRGB, independently of lsqt-cl's colour.c
    return srgb(((np.interp(L, wl, v) * E)[:, None] * CMF).sum(0) / W[1]) / WHITE

if tf["rgb"].shape != (1, nt, 3, nu, nu): p.append("rgb shape %s" % (tf["rgb"].shape,))
if tf["stderr"].shape != (1, nt, nb, nu, nu): p.append("stderr shape %s" % (tf["stderr"].shape,))
if ts is not None:
    if list(ts["wavelengths"]) != [np.float32(w) for w in wl]: p.append("wavelengths %s, run %s" % (ts["wavelengths"], wl))
    if ts["spectra"].shape != (1, nt, nb, nu, nu): p.append("spectra shape %s" % (ts["spectra"].shape,))
if not (np.isfinite(tf["luminance"]).all() and (tf["luminance"] > 0).all()): p.append("luminance not positive")
slices = [s for s in info["slices"] if not s["from_below"]]
nodes = []  # (k, j, l, wi, wo, values per band)
for k, s in enumerate(slices):
    th = s["theta_o"]
    for j in range(nu):
        for l in range(nu):
            u, v = l / (nu - 1), j / (nu - 1)
            tm, pm = u * u * math.pi / 2, (2 * v - 1) * math.pi
            m = np.array([math.sin(tm) * math.cos(pm), math.sin(tm) * math.sin(pm), math.cos(tm)])
            wi = np.array([math.sin(th), 0.0, math.cos(th)])
            wo = 2 * wi.dot(m) * m - wi
            if wi.dot(m) <= 0 or wo[2] < 1e-4: continue
            hit = [h for h in s["bsdf"] if abs(h[0] - wo[0]) < 2e-6 and abs(h[1] - abs(wo[1])) < 2e-6 and abs(h[2] - wo[2]) < 2e-6]
            if not hit: p.append("slice %d node (%d, %d) not simulated" % (k, j, l)); continue
            want = np.array(hit[0][3]) * hit[0][2]
            got = tf["rgb"][0, k, :, j, l].astype(float)
            ref = want if wl is None else colour(want)
            if np.abs(got - ref).max() > (1e-6 if wl is None else 1e-3) * np.abs(ref).max() + 1e-9:
                p.append("rgb slice %d node (%d, %d): %s, expected %s" % (k, j, l, got, ref))
            for b in range(nb):
                e, se = hit[0][4][b], float(tf["stderr"][0, k, b, j, l])
                if (e is None) != math.isnan(se) or (e is not None and abs(se - e * hit[0][2]) > 1e-6 * e * hit[0][2] + 1e-12):
                    p.append("stderr slice %d node (%d, %d) band %d: %g, info %s" % (k, j, l, b, se, e))
                if ts is not None and abs(ts["spectra"][0, k, b, j, l] - want[b]) > 1e-6 * abs(want[b]) + 1e-12:
                    p.append("spectra slice %d node (%d, %d) band %d: %g, info %g" % (k, j, l, b, ts["spectra"][0, k, b, j, l], want[b]))
            nodes.append((k, j, l, wi, wo, want, ref))
if len(nodes) < nt * nu: p.append("only %d nodes" % len(nodes))
print("bands: %d nodes, %d bands (%s): the file's values and errors, %d differ" % (len(nodes), nb, wl or "R, G, B", len(p)))

def evals(variant, path, F, lam=None):  # Mitsuba's eval at every node against the file's own values F[k, c, j, l]
    mi.set_variant(variant)
    bsdf = mi.load_dict({"type": "measured", "filename": path})
    bad, chans = 0, lam if lam is not None else [0, 1, 2]
    for k, j, l, wi, wo, want, ref in nodes:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wi) if wi[0] != 0 else mi.Vector3f(1e-20, wi[1], wi[2])
        if lam is not None: si.wavelengths = [wl[b] for b in lam]
        got = [float(x) for x in bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*wo))]
        exp = ref if lam is None else [want[b] for b in lam]
        # as check.py: Mitsuba's float32 (u, v) may land 1 % of the way to a neighbouring node
        step = [max(abs(F[k2, c, j2, l2] - F[k, c, j, l]) for k2, j2, l2 in ((k - 1, j, l), (k + 1, j, l), (k, j - 1, l),
                    (k, j + 1, l), (k, j, l - 1), (k, j, l + 1)) if 0 <= k2 < nt and 0 <= j2 < nu and 0 <= l2 < nu) for c in chans]
        if any(abs(g - w) > 3e-5 * abs(w) + 0.01 * st + 1e-9 for g, w, st in zip(got, exp, step)):
            bad += 1
            if bad < 4: p.append("%s slice %d node (%d, %d): mitsuba %s, file %s" % (variant, k, j, l, got, list(exp)))
    print("bands: Mitsuba %s at %d nodes, %d differ" % (variant, len(nodes), bad))
evals("scalar_rgb", rgb_path, tf["rgb"][0].astype(float))
if ts is not None:
    lam = [wl.index(w) for w in wl if w in (400, 500, 600, 700)]
    if len(lam) != 4: p.append("the test wants bands at 400, 500, 600, 700 nm")
    else: evals("scalar_spectral", spec_path, ts["spectra"][0].astype(float), lam)
if p: sys.exit("%d problems:\n" % len(p) + "\n".join(p[:8]))
PY

# Bands: the red paint (R, G, B) and gold under a coat at seven wavelengths.
cp "$EX/paint-rgb.lsqt" P.lsqt
cp "$EX/gold-coat.lsqt" G.lsqt
cp -r "$EX/tables" .
"$BIN" -q -p 2000 --rgl-grid 5,9 P.lsqt && "$BIN" info P.lsqt.lss --json P.json --bsdf > /dev/null && ok || bad "paint: run"
expect 0 "wrote P.bsdf: RGL tensor file (rgb: R, G, B)" -- "$BIN" export P.lsqt.lss -o P.bsdf --rgl
expect 2 "has 3 bands without wavelengths (R, G, B): --rgl-spectral writes a spectrum" -- \
  "$BIN" export P.lsqt.lss -o Ps.bsdf --rgl-spectral
[ ! -e Ps.bsdf ] && ok || bad "a refused --rgl-spectral wrote Ps.bsdf"
"$PY" bands.py P.bsdf - P.json 5 9 > P.out 2>&1 && ok || bad "paint bands: $(cat P.out)"
sed "s/^/  paint: /" P.out
"$BIN" -q -p 2000 --rgl-grid 5,9 --wavelengths 400:700:50 G.lsqt 2>/dev/null &&
  "$BIN" info G.lsqt.lss --json G.json --bsdf > /dev/null && ok || bad "gold: run"
expect 0 "wrote G.bsdf: RGL tensor file (rgb: linear sRGB of the spectrum)" -- "$BIN" export G.lsqt.lss -o G.bsdf --rgl
expect 0 "wrote Gs.bsdf: RGL tensor file (spectral: 7 wavelengths, 400 to 700 nm)" -- \
  "$BIN" export G.lsqt.lss -o Gs.bsdf --rgl-spectral
"$PY" bands.py G.bsdf Gs.bsdf G.json 5 9 > G.out 2>&1 && ok || bad "gold bands: $(cat G.out)"
sed "s/^/  gold: /" G.out
# two unnamed bands have no colour
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5,0.2\nMedium\n' > two.lsqt
"$BIN" -q -p 300 --rgl-grid 3,5 two.lsqt
expect 2 "'two.lsqt.lss' has 2 bands without wavelengths: --rgl writes colour from three" -- \
  "$BIN" export two.lsqt.lss -o two.bsdf --rgl
[ ! -e two.bsdf ] && ok || bad "a refused --rgl wrote two.bsdf"

# A refused export keeps an existing file (the refusals themselves: test_grid).
"$BIN" -q -p 300 --grid 3,3,6 --lss g.lss -o g.raw R.lsqt
cp Rough.bsdf keep.bsdf
expect 2 "'g.lss' is not on the nodes of an RGL tensor (its directions were chosen by --grid)" -- \
  "$BIN" export g.lss -o keep.bsdf --rgl
cmp -s Rough.bsdf keep.bsdf && ok || bad "a refused export changed the existing output"
finish test_rgl
