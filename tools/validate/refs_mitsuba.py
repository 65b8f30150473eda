#!/usr/bin/env python3
"""Mitsuba 3 references for lsqt-cl's single-scattering GGX microsurfaces.

    /work/venv/bin/python tools/validate/refs_mitsuba.py [--quick] [--paths N]

(needs `pip install mitsuba numpy scipy`; variant scalar_rgb, single precision). Builds the
cases (tools/validate/common.py format) with references computed now by mitsuba's
`roughconductor` and `roughdielectric` (GGX), checks every reference against an
independent float64 closed form written here from Walter et al. 2007 and Heitz 2014,
then runs lsqt-cl on every case and prints the table (exit 1 if a row fails).
DOC below says what is compared and why."""
import math
import os
import sys

import numpy as np
from scipy.special import betaln

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402

GROUP = "mitsuba"

# One-sigma relative tolerance of a reference value (float32 evaluation in mitsuba, float32
# directions); see DOC and check_against_f64 (which asserts the float64 closed form is
# within Z_MAX of it).
REF_REL = 2e-6
# Directions no closer to the horizon than this (|cos theta| >= cos 80 deg): near grazing
# the float32 reference loses digits to cancellation (tan^2 theta, wo.m + e wi.m).
COS_MIN = math.cos(math.radians(80.0))
# Nor facets seen edge-on (|wo.h|, |wi.h| >= 0.1): a small dot product computed in float32
# is the reference's worst cancellation (mitsuba's two adjoint evaluations then differ by
# 2e-4 at wo.h = 0.009, alpha 0.7).
FACET_COS_MIN = 0.1
THETA_O = (0.0, 35.0, 65.0)
ALPHAS = (0.1, 0.3, 0.7)
PATHS = 1000  # single-scattering point estimates are exact: paths only feed R, T

# Half vectors that place the incident directions on each lobe: slope tan(theta_h) = s alpha
# at azimuth phi_h (degrees) from the plane of wo. (s, phi_h)
H_REFLECT = ((0.0, 0.0), (0.5, 0.0), (1.0, 180.0), (1.0, 90.0), (2.0, 0.0))
H_REFRACT = ((0.0, 0.0), (0.5, 180.0), (1.0, 0.0), (1.0, 90.0), (2.0, 180.0), (3.0, 0.0))


# ---- float32 directions that lsqt-cl keeps exactly --------------------------------------

def lsqt_normalise(v):
    """What lsqt-cl's --wi-file reader does (host/input/directions.c): scale by the largest
    component, normalise in double, store as float."""
    v = np.asarray(v, dtype=np.float64)
    v = v / np.max(np.abs(v))
    v = v / math.sqrt(float(np.dot(v, v)))
    return v.astype(np.float32)


def f32_direction(v):
    """A float32 unit vector that lsqt-cl's reader maps to itself, so that lsqt-cl, mitsuba
    and the float64 check all see the same direction."""
    f = lsqt_normalise(v)
    for _ in range(8):
        g = lsqt_normalise(f.astype(np.float64))
        if np.array_equal(f, g):
            return f
        f = g
    raise RuntimeError(f"no fixed point for {v}")


def wo_of(theta_deg):
    t = math.radians(theta_deg)
    return np.array([math.sin(t), 0.0, math.cos(t)])


def half_vector(alpha, s, phi_deg):
    """phi_deg a multiple of 90 here: exact sines and cosines (no 1e-16 y off the plane)."""
    t = math.atan(s * alpha)
    cp, sp = {0: (1.0, 0.0), 90: (0.0, 1.0), 180: (-1.0, 0.0), 270: (0.0, -1.0)}[int(phi_deg) % 360]
    return np.array([math.sin(t) * cp, math.sin(t) * sp, math.cos(t)])


def reflect(wo, h):
    return 2.0 * np.dot(wo, h) * h - wo


def refract(wo, h, e):
    """wo refracted through a facet of normal h into a medium of relative index e, or None
    (total internal reflection)."""
    c = float(np.dot(wo, h))
    k = 1.0 - (1.0 - c * c) / (e * e)
    if c <= 0 or k <= 0:
        return None
    return -wo / e + (c / e - math.sqrt(k)) * h


def lobe_directions(alpha, theta_o, e=None):
    """Incident directions (frame of wo's side, wo in the xz plane) on the reflection lobe
    and, with e, the transmission lobe; y folded to >= 0 (the BSDF is mirror symmetric)."""
    wo = wo_of(theta_o)
    out = []
    for s, p in H_REFLECT:
        h = half_vector(alpha, s, p)
        w = reflect(wo, h)
        if w[2] >= COS_MIN and np.dot(wo, h) >= FACET_COS_MIN:
            out.append(w)
    for s, p in (H_REFRACT if e else ()):
        h = half_vector(alpha, s, p)
        w = refract(wo, h, e)
        if w is not None and w[2] <= -COS_MIN and min(np.dot(wo, h), -np.dot(w, h)) >= FACET_COS_MIN:
            out.append(w)
    dirs = []
    for w in out:
        w = np.array([w[0], abs(w[1]), w[2]])
        f = f32_direction(w)
        if not any(np.array_equal(f, d) for d in dirs):
            dirs.append(f)
    return dirs


# ---- float64 closed forms (Walter, Marschner, Li, Torrance 2007; Heitz 2014) -----------

def lam(alpha, z):
    """GGX Smith Lambda(w) = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2, either hemisphere."""
    z2 = z * z
    return 0.5 * (math.sqrt(1.0 + alpha * alpha * (1.0 - z2) / z2) - 1.0)


def g1(alpha, z):
    return 1.0 / (1.0 + lam(alpha, z))


def g2_corr(alpha, zo, zi, transmit):
    """Height-correlated Smith masking-shadowing (Heitz 2014): reflection
    1 / (1 + Lo + Li); transmission B(1 + Lo, 1 + Li) (Beta function)."""
    lo, li = lam(alpha, zo), lam(alpha, zi)
    if transmit:
        return math.exp(betaln(1.0 + lo, 1.0 + li))
    return 1.0 / (1.0 + lo + li)


def ggx_d(alpha, h):
    c2 = h[2] * h[2]
    t2 = (1.0 - c2) / c2
    return alpha * alpha / (math.pi * c2 * c2 * (alpha * alpha + t2) ** 2)


def fresnel_complex(c, n):
    """Unpolarised Fresnel reflectance for cos(incidence) c into relative index n (complex
    for a metal; real, possibly < 1, for a dielectric), from the amplitude coefficients;
    1 under total internal reflection."""
    n = complex(n)
    s2 = 1.0 - c * c
    if n.imag == 0 and n.real ** 2 < s2:
        return 1.0
    nct = np.sqrt(n * n - s2)  # n cos(theta_t), principal root
    rs = (c - nct) / (c + nct)
    rp = (n * n * c - nct) / (n * n * c + nct)
    return 0.5 * (abs(rs) ** 2 + abs(rp) ** 2)


def f64_bsdf(alpha, n, wo, wi, correlated):
    """BSDF value f(wo -> wi) (1/sr, not cosine weighted), wo.z > 0 in the frame of its
    side, light entering along -wo; n the relative index of the other side (complex: a
    metal that only reflects). Transmission in the flux form (the e^2 of Walter's eq. 21
    with e the index on wi's side, as lsqt-cl and mitsuba's Importance mode)."""
    wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
    wo, wi = wo / np.linalg.norm(wo), wi / np.linalg.norm(wi)
    co, ci = wo[2], wi[2]
    transmit = ci < 0
    if transmit:
        e = float(np.real(n))
        h = -(wo + e * wi)
    else:
        e = None
        h = wo + wi
    h = h / np.linalg.norm(h)
    if h[2] < 0:
        h = -h
    oh, ih = float(np.dot(wo, h)), float(np.dot(wi, h))
    if oh <= 0 or (ih >= 0 if transmit else ih <= 0):
        return 0.0
    g = g2_corr(alpha, co, ci, transmit) if correlated else g1(alpha, co) * g1(alpha, ci)
    d = ggx_d(alpha, h)
    if not transmit:
        return fresnel_complex(oh, n) * d * g / (4.0 * co * ci)
    fr = fresnel_complex(oh, e)
    return abs(ih) * oh / (co * abs(ci)) * e * e * (1.0 - fr) * d * g / (oh + e * ih) ** 2


# ---- mitsuba -----------------------------------------------------------------------------

_MI = None


def mitsuba():
    global _MI
    if _MI is None:
        import mitsuba as mi
        mi.set_variant("scalar_rgb")
        _MI = mi
    return _MI


def mitsuba_bsdf(kind, alpha, **kw):
    mi = mitsuba()
    if kind == "conductor":
        return mi.load_dict({"type": "roughconductor", "distribution": "ggx", "alpha": alpha,
                             "eta": kw["eta"], "k": kw["k"]})
    return mi.load_dict({"type": "roughdielectric", "distribution": "ggx", "alpha": alpha,
                         "int_ior": kw["int_ior"], "ext_ior": kw["ext_ior"]})


def mitsuba_f(bsdf, wo_m, wi_m):
    """mitsuba's BSDF value (1/sr, not cosine weighted) for light arriving along -wo_m
    (its si.wi: the direction towards where the path came from, the role of lsqt-cl's wo)
    and leaving towards wi_m (its wo), in mitsuba's frame (+z the normal, exterior above).
    Importance mode: the transmission keeps eta^2 of the side the light goes into and no
    1/eta^2 radiance rescaling, which is lsqt-cl's flux form. eval returns f |cos| of its
    wo (lsqt-cl's wi), so that cosine is divided out."""
    mi = mitsuba()

    def ev(mode, a, b):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*[float(x) for x in a])
        v = bsdf.eval(mi.BSDFContext(mode), si, mi.Vector3f(*[float(x) for x in b]))
        return float(v[0]) / abs(float(np.float32(b[2])))

    f = ev(mi.TransportMode.Importance, wo_m, wi_m)
    # the adjoint: Radiance mode with the roles swapped (its 1/eta^2 and the e^2 of the
    # reversed refraction) is the same value; mitsuba's conventions checked on themselves
    g = ev(mi.TransportMode.Radiance, wi_m, wo_m)
    if abs(g - f) > common.Z_MAX * REF_REL * abs(f):
        raise AssertionError(f"mitsuba: Importance {f!r} vs Radiance with roles swapped {g!r} at {wo_m}, {wi_m}")
    return f


# ---- cases -------------------------------------------------------------------------------

def _case(name, lsqt, args, wi, checks):
    return {"group": GROUP, "name": name, "lsqt": lsqt, "args": args,
            "wi": [[float(x) for x in w] for w in wi], "paths": PATHS, "fixture_paths": PATHS, "checks": checks}


def _one_mirrored(dirs, mirror):
    """With mirror, the first direction out of the plane of wo given with y < 0 instead:
    lsqt-cl evaluates it at (x, -y, z); mitsuba evaluates it as given."""
    out, done = [], not mirror
    for d in dirs:
        if not done and d[1] > 0:
            d, done = np.array([d[0], -d[1], d[2]], np.float32), True
        out.append(d)
    return out


def _check(slice_, i, ref, note):
    return {"slice": slice_, "q": f"f:{i}", "ref": ref, "ref_err": REF_REL * abs(ref), "limitation": None,
            "_f64": note}


def conductor_case(alpha, eta, k, eta_above=1.0):
    """A GGX conductor under a clear medium of index eta_above: the metal's index
    relative to it is (eta + i k) / eta_above, which is what mitsuba is given."""
    er, kr = eta / eta_above, k / eta_above
    bsdf = mitsuba_bsdf("conductor", alpha, eta=er, k=kr)
    per_slice = [lobe_directions(alpha, t) for t in THETA_O]
    wi, checks = [], []
    for s, dirs in enumerate(per_slice):
        wo = wo_of(THETA_O[s])
        for d in _one_mirrored(dirs, s == 1):
            wi.append(d)
            fm = mitsuba_f(bsdf, wo.astype(np.float32), d)
            conv = g2_corr(alpha, wo[2], float(d[2]), False) / (g1(alpha, wo[2]) * g1(alpha, float(d[2])))
            checks.append(_check(s, len(wi) - 1, fm * conv,
                                 (fm, f64_bsdf(alpha, complex(er, kr), wo, d, False),
                                  f64_bsdf(alpha, complex(er, kr), wo, d, True))))
    above = f"Medium eta={eta_above!r}" if eta_above != 1.0 else "Medium"
    lsqt = (f"{above}\nLayer z=0 MicrosurfaceConductiveBrdf alpha={alpha!r} use_multiple_scattering=false\n"
            f"Medium eta={eta!r} mua={k!r}\n")
    name = f"GGX conductor a={alpha:g} n={eta:g}+{k:g}i" + (f" /{eta_above:g}" if eta_above != 1.0 else "")
    return _case(name, lsqt, ["--double", "--wo-angles=" + ",".join(f"{t:g}" for t in THETA_O)], wi, checks)


def dielectric_case(alpha, eta=1.5):
    """A GGX dielectric between vacuum above and index eta below, with --from-below: slices
    0..2 light from above (relative index eta), 3..5 from below (1/eta; lsqt-cl's frame
    there is the stack upside down: wo and wi with z negated are mitsuba's directions, where
    a negative si.wi.z makes roughdielectric use 1/eta itself)."""
    bsdf = mitsuba_bsdf("dielectric", alpha, int_ior=eta, ext_ior=1.0)
    n_t = len(THETA_O)
    wi, checks = [], []
    for side in (0, 1):
        e = eta if side == 0 else 1.0 / eta
        for t_i, t in enumerate(THETA_O):
            s = side * n_t + t_i
            wo = wo_of(t)
            dirs = lobe_directions(alpha, t, e)
            if side == 1 and t_i == n_t - 1:
                # straight out from 65 deg inside: the generalised half vector faces away
                # from wo, no facet refracts one into the other, f = 0 (no light leaks)
                dirs.append(np.array([0.0, 0.0, -1.0], np.float32))
            for d in _one_mirrored(dirs, t_i == 1):
                wi.append(d)
                flip = np.array([1.0, 1.0, -1.0 if side else 1.0])
                fm = mitsuba_f(bsdf, (wo * flip).astype(np.float32), (d * flip).astype(np.float32))
                tr = d[2] < 0
                conv = g2_corr(alpha, wo[2], float(d[2]), tr) / (g1(alpha, wo[2]) * g1(alpha, float(d[2])))
                checks.append(_check(s, len(wi) - 1, fm * conv,
                                     (fm, f64_bsdf(alpha, e, wo, d, False), f64_bsdf(alpha, e, wo, d, True))))
    lsqt = (f"Medium\nLayer z=0 MicrosurfaceDielectricBsdf alpha={alpha!r} use_multiple_scattering=false\n"
            f"Medium eta={eta!r}\n")
    return _case(f"GGX dielectric a={alpha:g} 1|{eta:g} (+below)", lsqt,
                 ["--double", "--from-below", "--wo-angles=" + ",".join(f"{t:g}" for t in THETA_O)], wi, checks)


def check_against_f64(cs):
    """Every mitsuba value against the float64 closed form with the separable masking
    (mitsuba's own), and every converted reference against the closed form with the
    height-correlated masking; raises if one is off by more than Z_MAX * REF_REL.
    Returns the largest relative differences (raw, converted)."""
    worst_raw = worst_conv = 0.0
    for c in cs:
        for k in c["checks"]:
            fm, f_sep, f_corr = k["_f64"]
            for got, want, which in ((fm, f_sep, "raw"), (k["ref"], f_corr, "converted")):
                if want == 0.0:
                    if got != 0.0:
                        raise AssertionError(f"{c['name']} {k['q']}: mitsuba {got} where the closed form is 0")
                    continue
                r = abs(got / want - 1.0)
                if which == "raw":
                    worst_raw = max(worst_raw, r)
                else:
                    worst_conv = max(worst_conv, r)
                if r > common.Z_MAX * REF_REL:
                    raise AssertionError(f"{c['name']} slice {k['slice']} {k['q']}: mitsuba {got!r} vs float64 "
                                         f"{want!r} ({which}, relative {r:.2e})")
    return worst_raw, worst_conv


def _build(quick):
    alphas = (0.3,) if quick else ALPHAS
    cs = [conductor_case(a, 0.2, 3.0) for a in alphas]
    if not quick:
        cs.append(conductor_case(0.3, 1.1, 2.5, eta_above=1.33))
    cs += [dielectric_case(a) for a in alphas]
    worst = check_against_f64(cs)
    for c in cs:
        for k in c["checks"]:
            k.pop("_f64")
    return cs, worst


def cases(quick=False):
    """The cases, references computed now with mitsuba (and checked against float64)."""
    return _build(quick)[0]


DOC = f"""\
### mitsuba: single-scattering GGX rough conductor and rough dielectric

`tools/validate/refs_mitsuba.py` (group `mitsuba`) compares lsqt-cl's analytic
single-scattering values of `MicrosurfaceConductiveBrdf` and `MicrosurfaceDielectricBsdf`
(`use_multiple_scattering=false`, run with `--double`) with mitsuba 3's `roughconductor`
and `roughdielectric` plugins (`distribution=ggx`, pip wheel, variant `scalar_rgb`,
float32), evaluated when the cases are built.

**What is compared.** BSDF values f (1/sr, not cosine weighted) at exact direction pairs:
lsqt-cl's `info --bsdf` point estimates for the directions of a `--wi-file` (their f_err
is 0: the single-scattering estimate is the analytic value), slice by slice
(`--wo-angles={','.join(f'{t:g}' for t in THETA_O)}`), against the converted mitsuba value.
Incident directions are placed on the lobes through half vectors with slope
tan(theta_h) = s alpha (s from 0 to 3, in and out of the plane of wo), reflection for both
models and refraction for the dielectric, alpha = {', '.join(f'{a:g}' for a in ALPHAS)},
kept only with |cos theta_i| >= cos 80 deg and facets not seen edge-on (|wo.m|, |wi.m| >= 0.1):
no grazing directions, where float32 cancellation (tan^2 theta, wo.m + e wi.m, a small
wo.m) would dominate the reference's error (at wo.m = 0.009 mitsuba's own two adjoint
evaluations differ by 2e-4).
Cases: the conductor with n = 0.2 + 3i under vacuum at the three alphas, and
n = 1.1 + 2.5i under water (eta 1.33: mitsuba gets the relative index n / 1.33, lsqt-cl the
media as written, checking that it divides by the index above); the dielectric between
vacuum and eta = 1.5 with `--from-below`, so each case checks light from above (relative
index 1.5) and from below (1/1.5, with total internal reflection of the facets; in lsqt-cl's
frame for those slices the stack is upside down, so mitsuba gets both directions with z
negated and, seeing si.wi.z < 0, uses 1/eta itself). One direction per case is written
with y < 0; lsqt-cl evaluates it at its mirror image (x, -y, z) and the reference is
mitsuba's value at y < 0, so the mirror symmetry is checked too. From below at 65 deg
one more direction, straight out (0, 0, -1), has no refracting facet orientation
(the generalised half vector faces away from wo): reference 0, and lsqt-cl must give 0.
The directions are float32
vectors that lsqt-cl's reader keeps bit for bit (it normalises in double and stores float),
so both programs see the same directions.

**Conventions.** lsqt-cl's f(wo -> wi) is for paths entering along -wo (the observer side)
and carries |cos theta_i| of the light direction wi (docs/design.md section 1.3); `info` divides it out.
mitsuba's `eval(ctx, si, wo)` returns f(si.wi, wo) |cos theta| of its `wo`; so
si.wi = lsqt-cl's wo, mitsuba's wo = lsqt-cl's wi, and the reference is eval / |wi.z|.
Transmission: lsqt-cl's dielectric is in the flux form (a lossless stack has R + T = 1,
f carries e^2 with e the relative index of wi's side, n_o^2 f(wo -> wi) / |cos i| =
n_i^2 f(wi -> wo) / |cos o|); mitsuba gives exactly this in `TransportMode.Importance`
(Radiance mode multiplies the transmission by 1/eta^2, the radiance BSDF of the reversed
roles), so the references use Importance mode; the script asserts at every pair that
Radiance mode with the roles swapped gives the same value (the adjoint relation), a check
of this reading of mitsuba's conventions on mitsuba itself. Both use the exact
unpolarised Fresnel terms, the conductor's of the complex index (mitsuba's `eta`, `k` floats; lsqt-cl's
metal is the bottom medium with `eta` the real part and `mua` the imaginary part k).

**Masking-shadowing.** mitsuba uses the separable Smith form G = G1(wo) G1(wi); lsqt-cl's
microsurface has uniform heights and so the height-correlated form (Heitz 2014).
With the closed-form GGX Lambda(w) = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2 (either
hemisphere, |cos|), G1 = 1 / (1 + Lambda):

    reflection    G2 = 1 / (1 + Lambda(wo) + Lambda(wi))
    transmission  G2 = B(1 + Lambda(wo), 1 + Lambda(wi))   (B the Beta function)

and the reference is f_mitsuba * G2 / (G1(wo) G1(wi)) (the factor computed in float64),
i.e. mitsuba's D F (and the Jacobian and Fresnel transmission) with the geometry term
replaced. The Beta form is Heitz 2014's height-correlated masking for transmission:
the first hit's height has density (1 + Lo) C1^Lo in C1 (the Smith height CDF), and
light refracted there escapes the other side with (1 - C1)^Li; the 1 + Lo cancels the
G1(wo) of the visible-normal normalisation. At these pairs the factor
G2 / (G1(wo) G1(wi)) runs from 0.92 (reflection) to 1.09 (transmission); it is 1 within
1e-4 at 140 of the 213 non-zero pairs (theta_o = 0, where Lambda(wo) = 0 makes the two
forms equal, and alpha = 0.1, where Lambda is small), which test D, F and the Jacobians;
the other 73 test the masking too. Mitsuba's zeros (facet orientations that the
chi+ terms exclude, total internal reflection) stay zeros.

**Tolerance.** Each reference carries ref_err = {REF_REL:g} x |ref| (one sigma) and the
row passes at |z| <= 4. Justification: mitsuba computes in float32, and the wo of a slice
is rounded to float32 for it (a direction error of ~6e-8 rad changes f by 6e-8 x
|d ln f / d theta|, largest on the flanks of the narrow alpha = 0.1 lobes); when the cases are built every raw mitsuba value is compared
with a float64 closed form written in this script from Walter et al. 2007 (D, the
transmission Jacobian with e^2 and the Fresnel terms from the complex amplitude
coefficients rs, rp, not from mitsuba's or lsqt-cl's formulas) with the separable G, and
every converted reference with the same closed form with the height-correlated G2; the
build fails if any differs by more than 4 x {REF_REL:g}. With mitsuba 3.9.1 the largest
relative difference over all pairs is 1.6e-6 (alpha = 0.1 at theta_o = 65 deg, where
the lobe is narrowest), the median 2.3e-7, the 90th percentile 6.2e-7: so {REF_REL:g} is one sigma with the worst case at 0.8 sigma.
lsqt-cl runs with `--double` (its point estimates then have f_err 0 or ~1e-14), so its
side is exact to about 1e-7 relative or better; the float32 incident directions are exact
inputs to both programs. Zero references (ref_err 0, lsqt-cl's error 0) fall to
common.judge's absolute 1e-5 test.
"""


def main():
    args = sys.argv[1:]
    quick = "--quick" in args
    paths = int(float(args[args.index("--paths") + 1])) if "--paths" in args else PATHS
    cs, (w_raw, w_conv) = _build(quick)
    n = sum(len(c["checks"]) for c in cs)
    print(f"{len(cs)} cases, {n} direction pairs; mitsuba vs float64 closed form: largest relative difference "
          f"{w_raw:.2e} (separable G), {w_conv:.2e} (converted, height-correlated G2); ref_err = {REF_REL:g} x ref")
    # info's bsdf entries are in --wi-file order, y folded to >= 0 (checked here, relied on by "f:i")
    for c in cs:
        _, info = common.run_case(c, paths)
        want = np.array([[x, abs(y), z] for x, y, z in c["wi"]], np.float32)
        for sl in info["slices"]:  # info prints floats with 9 digits: float32 round trip
            if not np.array_equal(np.array([e[:3] for e in sl["bsdf"]], np.float32), want):
                raise AssertionError(f"{c['name']}: info's directions are not the --wi-file's")
    print(common.HEADER)
    fails, worst = 0, 0.0
    for c in cs:
        for r, k in zip(common.rows_of_case(c, paths), c["checks"]):
            d = c["wi"][int(k["q"][2:])]
            side = " below" if "--from-below" in c["args"] and r["slice"] >= len(THETA_O) else ""
            print(common.format_row(r) + f"  s{r['slice']}{side} wi=({d[0]:+.4f},{d[1]:+.4f},{d[2]:+.4f})")
            fails += r["verdict"] == "FAIL"
            if math.isfinite(r["z"]):
                worst = max(worst, abs(r["z"]))
    print(f"largest |z| = {worst:.2f}; {fails} FAIL")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
