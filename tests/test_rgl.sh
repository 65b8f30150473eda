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
#     estimates equals the one from uniform hemisphere sampling of eval (z < 4).
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

cat > check.py <<'PY'
import json, math, struct, sys
import numpy as np
import mitsuba as mi

tensor, tensor_s, info_path, wi_path, nt, nu = sys.argv[1:5] + [int(a) for a in sys.argv[5:7]]
p = []

def read_tensor(path):
    """An independent reader of the tensor file format: name -> numpy array."""
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

tf = read_tensor(tensor)
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

# A refused export keeps an existing file (the refusals themselves: test_grid).
"$BIN" -q -p 300 --grid 3,3,6 --lss g.lss -o g.raw R.lsqt
cp Rough.bsdf keep.bsdf
expect 2 "'g.lss' is not on the nodes of an RGL tensor (its directions were chosen by --grid)" -- \
  "$BIN" export g.lss -o keep.bsdf --rgl
cmp -s Rough.bsdf keep.bsdf && ok || bad "a refused export changed the existing output"
finish test_rgl
