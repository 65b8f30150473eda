#!/usr/bin/env python3
"""iadpython (adding-doubling) references for homogeneous Henyey-Greenstein slabs:
directional hemispherical reflectance R and transmittance T for collimated incidence,
at normal and oblique incidence, between index-matched null layers and between smooth
Fresnel boundaries (slab index 1.33 and 1.5 in air).

    /work/venv/bin/python tools/validate/refs_iad.py [--quick] [--convergence]
                                             [--run [--fixture] [--paths-scale X]]

Without --run it prints the references and their quadrature spread (--convergence: the
values at every quadrature order); with --run it runs lsqt-cl (LSQT_CL or build/lsqt-cl)
on every case at case["paths"] (--fixture: case["fixture_paths"]) and prints the table.
Needs iadpython (0.5.3), numpy and scipy; tools/validate/common.py needs nothing.

How the references are made (see DOC below for the why): iadpython 0.5.3's Sample.rt()
answers oblique collimated incidence with zeros, so the angle is put into the quadrature
(Sample.update_quadrature with nu_0 set), the slab's R and T matrices are built from its
building blocks (diamond starting layer, doubling, Fresnel boundaries added with
add_same_slides), and the column of the quadrature angle equal to the incidence angle
(refracted into the slab) is integrated over the exit angles that leave the slab, as
Sample.UX1_and_UXU does for the normal-incidence column."""
import math
import os
import sys

GROUP = "iadpython"

# Quadrature orders whose spread is the reference's error. iadpython's Radau points come
# from Legendre polynomial coefficients and go wrong above about 24 points at normal
# incidence (40 points gives R 20 % off), so nothing above 20 is used. Oblique incidence
# in a Fresnel slab splits the quadrature in three equal parts: multiples of 3 there.
QUADS = (12, 16, 20)
QUADS_FRESNEL_OBLIQUE = (12, 15, 18)
# Floor for ref_err: what the closed-form checks below leave (starting layer, delta-M of
# an isotropic slab, round-off) is at most a few 1e-7; 2e-5 is stated with a wide margin.
REF_ERR_FLOOR = 2e-5
# Extra halvings of iadpython's starting thickness (see _slab_rt): its default start
# leaves relative errors of 1e-4 in the unscattered beam at 60 deg and 1e-3 at 85 deg;
# 16x thinner leaves 3e-7 and 1e-6 (the error goes as the square of the thickness).
START_HALVINGS = 4
# Roughness of the "smooth" Fresnel boundaries in lsqt-cl (single scattering GGX).
ALPHA = 1e-4


def _slab_rt(a, b, g, n, mu0, quad):
    """(R, T) of a slab of albedo a, optical thickness b, HG g, index n in air (no glass
    slides) for collimated incidence at cosine mu0 in air, with `quad` quadrature points."""
    import numpy as np
    import iadpython as iad
    import iadpython.combine as combine
    import iadpython.start as start

    s = iad.Sample(a=a, b=b, g=g, n=n, n_above=1.0, n_below=1.0, quad_pts=quad)
    s.nu_0 = mu0
    s.update_quadrature()  # includes mu0 (refracted: nu_00) as a quadrature angle
    s.nu_0 = 1.0  # rt_matrices-style code refuses nu_0 != 1; the quadrature stays
    nu_in = iad.cos_snell(1.0, mu0, n)
    j = int(np.argmin(abs(s.nu - nu_in)))
    if abs(s.nu[j] - nu_in) > 1e-12 or len(s.nu) != quad:
        raise RuntimeError(f"quadrature lacks the incidence angle: {s.nu} vs {nu_in}")
    d = start.starting_thickness(s)
    for _ in range(START_HALVINGS):
        if d / 2 >= 1e-4:  # below 1e-4 iadpython switches to the O(d) IGI start
            d /= 2
    s.b_thinnest = d
    s.hp, s.hm = iad.hg_legendre(s)
    r, t = start.diamond(s)
    r, t = combine.double_until(s, r, t, s.b_thinnest, s.b_delta_M())
    if n != 1.0:
        R01, R10, T01, T10 = start.boundary_layer(s, top=True)
        r, t = combine.add_same_slides(s, R01, R10, T01, T10, r, t)
    k = int(np.min(np.where(s.nu > s.nu_c())))  # exit angles that leave the slab
    return float(s.twonuw[k:] @ r[k:, j]), float(s.twonuw[k:] @ t[k:, j])


def fresnel_unpolarised(n1, mu1, n2):
    """Reflectance of a smooth interface n1 -> n2 at incidence cosine mu1."""
    s2 = (n1 / n2) ** 2 * (1 - mu1 * mu1)
    if s2 >= 1:
        return 1.0
    mu2 = math.sqrt(1 - s2)
    rs = (n1 * mu1 - n2 * mu2) / (n1 * mu1 + n2 * mu2)
    rp = (n2 * mu1 - n1 * mu2) / (n2 * mu1 + n1 * mu2)
    return 0.5 * (rs * rs + rp * rp)


def clear_slab_rt(n, mu0, b=0.0):
    """Closed form: non-scattering slab of index n, absorption optical thickness b, in air."""
    rho = fresnel_unpolarised(1.0, mu0, n)
    mu1 = math.sqrt(1 - (1 - mu0 * mu0) / (n * n))
    att = math.exp(-b / mu1)
    den = 1 - rho * rho * att * att
    return rho + (1 - rho) ** 2 * rho * att * att / den, (1 - rho) ** 2 * att / den


def reference(a, b, g, n, mu0):
    """Reference (value at the highest order) and spread (max - min over the orders),
    for R and T: ((R, R_spread), (T, T_spread), {quad: (R, T)})."""
    quads = QUADS_FRESNEL_OBLIQUE if (n != 1.0 and mu0 != 1.0) else QUADS
    vals = {q: _slab_rt(a, b, g, n, mu0, q) for q in quads}
    out = []
    for i in range(2):
        v = [vals[q][i] for q in quads]
        out.append((v[-1], max(v) - min(v)))
    return out[0], out[1], vals


# (a, tau, g, n): slab of thickness 1 (z = 1 to z = 0), mus = a*tau, mua = (1-a)*tau,
# each at theta_o = 0 and 60 deg.
SLABS = [
    # index matched, null layers
    (0.5, 0.1, 0.0, 1.0),
    (0.9, 1.0, 0.5, 1.0),
    (0.99, 1.0, -0.5, 1.0),
    (0.99, 3.0, 0.8, 1.0),
    (0.999, 0.3, 0.95, 1.0),
    (0.5, 10.0, 0.95, 1.0),
    (0.999, 10.0, 0.9, 1.0),
    (0.7, 30.0, -0.3, 1.0),
    (0.9, 100.0, 0.0, 1.0),
    (0.999, 100.0, 0.5, 1.0),
    # smooth Fresnel boundaries, slab index 1.33
    (0.5, 0.1, 0.0, 1.33),
    (0.9, 1.0, 0.5, 1.33),
    (0.95, 3.0, -0.5, 1.33),
    (0.999, 10.0, 0.9, 1.33),
    (0.99, 100.0, 0.8, 1.33),
    # slab index 1.5
    (0.9, 0.3, 0.7, 1.5),
    (0.5, 1.0, 0.95, 1.5),
    (0.95, 10.0, 0.0, 1.5),
    (0.8, 30.0, 0.5, 1.5),
    (0.999, 100.0, 0.9, 1.5),
]
ANGLES = (0.0, 60.0)
CLEAR_ANGLES = (0.0, 60.0, 80.0)
QUICK = [(0.9, 1.0, 0.5, 1.0), (0.95, 10.0, 0.0, 1.5), (0.9, 1.0, 0.5, 1.33)]

# paths per slice: validation run (standard errors <= 1e-3) and ctest fixture (about
# 0.1-1.5 s each, about 15 s for all), from timings of lsqt-cl on PoCL with 2 shared cores
PATHS_DEFAULT, FIXTURE_DEFAULT = 4e5, 1e5
PATHS = {(0.999, 100.0, 0.5, 1.0): 3e5, (0.999, 100.0, 0.9, 1.5): 2.5e5}
FIXTURE_PATHS = {(0.999, 10.0, 0.9, 1.33): 5e4, (0.99, 100.0, 0.8, 1.33): 2e4,
                 (0.999, 100.0, 0.5, 1.0): 1e4, (0.999, 100.0, 0.9, 1.5): 2e4}


def _fmt(x):
    return f"{x:.10g}"


def slab_lsqt(a, tau, g, n, alpha=ALPHA):
    mus, mua = a * tau, (1 - a) * tau
    med = f"Medium eta={_fmt(n)} mus={_fmt(mus)} mua={_fmt(mua)} HenyeyGreensteinPhase g={_fmt(g)}\n" \
        if n != 1.0 else f"Medium mus={_fmt(mus)} mua={_fmt(mua)} HenyeyGreensteinPhase g={_fmt(g)}\n"
    if n == 1.0:
        lay = "NullBsdf"
    else:
        lay = f"MicrosurfaceDielectricBsdf alpha={_fmt(alpha)} use_multiple_scattering=false"
    return f"Medium\nLayer z=1 {lay}\n{med}Layer z=0 {lay}\nMedium\n"


def slab_name(a, tau, g, n):
    edge = "null" if n == 1.0 else f"Fresnel n={n:g}"
    return f"{edge} a={a:g} tau={tau:g} g={g:g}"


def _paths(key, default):
    return PATHS.get(key, default[0]), FIXTURE_PATHS.get(key, default[1])


def cases(quick=False):
    out = []
    for a, tau, g, n in (QUICK if quick else SLABS):
        checks = []
        for k, th in enumerate(ANGLES):
            mu0 = 1.0 if th == 0 else math.cos(math.radians(th))
            (r, dr), (t, dt), _ = reference(a, tau, g, n, mu0)
            checks.append({"slice": k, "q": "R", "ref": r, "ref_err": max(dr, REF_ERR_FLOOR), "limitation": None})
            checks.append({"slice": k, "q": "T", "ref": t, "ref_err": max(dt, REF_ERR_FLOOR), "limitation": None})
        p, fp = _paths((a, tau, g, n), (PATHS_DEFAULT, FIXTURE_DEFAULT))
        out.append({"group": GROUP, "name": slab_name(a, tau, g, n), "lsqt": slab_lsqt(a, tau, g, n),
                    "args": ["--wo-angles=" + ",".join(f"{x:g}" for x in ANGLES), "--wi-spread", "-wi", "16"],
                    "paths": p, "fixture_paths": fp, "checks": checks})
    if not quick:
        # the Fresnel boundaries alone: a clear slab of index 1.5, closed form (iadpython
        # with a = 0 agrees to 1e-8), shows how close alpha = 1e-4 is to smooth
        checks = []
        for k, th in enumerate(CLEAR_ANGLES):
            mu0 = 1.0 if th == 0 else math.cos(math.radians(th))
            r, t = clear_slab_rt(1.5, mu0)
            ri, ti = _slab_rt(0.0, 1e-9, 0.0, 1.5, mu0, 12 if th == 0 else 18)
            assert abs(ri - r) < 1e-7 and abs(ti - t) < 1e-7, (th, r, ri, t, ti)
            checks.append({"slice": k, "q": "R", "ref": r, "ref_err": 0.0, "limitation": None})
            checks.append({"slice": k, "q": "T", "ref": t, "ref_err": 0.0, "limitation": None})
        lay = f"MicrosurfaceDielectricBsdf alpha={_fmt(ALPHA)} use_multiple_scattering=false"
        out.append({"group": GROUP, "name": "Fresnel n=1.5 clear slab (closed form)",
                    "lsqt": f"Medium\nLayer z=1 {lay}\nMedium eta=1.5\nLayer z=0 {lay}\nMedium\n",
                    "args": ["--wo-angles=" + ",".join(f"{x:g}" for x in CLEAR_ANGLES), "--wi-spread", "-wi", "16"],
                    "paths": 4e5, "fixture_paths": 1e5, "checks": checks})
    return out


DOC = """\
### iadpython: Henyey-Greenstein slabs (adding-doubling)

**What is compared.** lsqt-cl's per-slice R and T (the fractions of paths entering along
-wo that leave up and down: directional hemispherical reflectance and transmittance for
collimated incidence at theta_o, T including the unscattered delta_T) against the
adding-doubling values of iadpython 0.5.3, at theta_o = 0 and 60 deg (angle in air).
Each slab is one unit thick (`Layer z=1` to `Layer z=0`) with `mus = a*tau`,
`mua = (1-a)*tau` and `HenyeyGreensteinPhase g`; iadpython gets albedo a, optical
thickness tau, g. Twenty slabs span a = 0.5 ... 0.999, tau = 0.1 ... 100, g = -0.5 ...
0.95: ten between index-matched `NullBsdf` layers (iadpython n = n_above = n_below = 1),
five of index 1.33 and five of index 1.5 between smooth Fresnel boundaries in air
(`Medium eta=n` between two `MicrosurfaceDielectricBsdf alpha=1e-4
use_multiple_scattering=false` layers, air above and below; iadpython n = slab index,
n_above = n_below = 1, i.e. no glass slides). A twenty-first case, a clear slab of index
1.5 at 0, 60 and 80 deg, is checked against the closed form R = rho + (1-rho)^2 rho/(1-rho^2)
(rho the unpolarised Fresnel reflectance; iadpython with a = 0 gives it to 1e-8).

**How the references are made.** `Sample.rt()` answers oblique collimated incidence with
zeros (its `rt_matrices` returns zero matrices when `nu_0 != 1`), so the answer is built
from iadpython's own blocks: `update_quadrature()` with `nu_0 = cos theta_o` puts the
incidence angle (refracted into the slab, `nu_00`) into the quadrature; the slab's R and T
matrices come from `start.diamond`, `combine.double_until` and, for Fresnel boundaries,
`start.boundary_layer` + `combine.add_same_slides`, exactly as `rt_matrices` does; R and T
are the column of that quadrature angle integrated over the exit angles that leave the
slab (`sum_i 2 nu_i w_i M[i, j]` over nu_i above the critical cosine), as
`UX1_and_UXU` does for the normal-incidence column. Checks: at normal incidence and with
iadpython's own starting thickness this equals `Sample.rt()` to 1e-16 (with the thinner
start of trap 3, to 1.3e-6); non-scattering slabs (a = 0, tau 0.1 ... 10, n 1, 1.33,
1.5, 0/60/85 deg) match the two-interface closed form within 1.7e-7; lossless slabs give
R + T = 1 within 1e-8 at the orders used for the value (7e-5 at 12 points for a Fresnel
slab at 60 deg, inside the spread below).

**Convergence and ref_err.** Each reference is computed at three quadrature orders:
12, 16, 20 points (index-matched slabs, and Fresnel slabs at normal incidence), and
12, 15, 18 for a Fresnel slab at oblique incidence (iadpython splits that quadrature in
three equal parts). The reference is the highest order; ref_err is the spread max - min
over the three orders, floored at 2e-5. Spreads are below 1e-6 for most moderate-g
index-matched slabs, 1e-5 ... 4e-4 for Fresnel slabs (the normal-incidence Fresnel values
drift monotonically, roughly as 1/N^2: a Richardson estimate of the remaining error beyond
20 points is about half the spread; 24, 32, 40 points confirm it for n = 1.33, a = 0.9,
tau = 1, g = 0.5), and largest for g = 0.95, where the delta-M truncation of the phase
function to N Legendre terms converges slowly and not monotonically: 5.1e-4 (tau = 0.3,
a = 0.999, 60 deg), 2.3e-4 (tau = 10, a = 0.5), 2.8e-3 and 1.9e-3 for T of the n = 1.5,
a = 0.5, tau = 1 slab at 0 and 60 deg (those two checks are weaker than the others).
lsqt-cl runs 4e5 paths per slice (2.5e5-3e5 for the two tau = 100, a = 0.999 slabs):
standard errors 1e-5 ... 9.5e-4. The ctest fixtures run 1e4-1e5 (about 15 s for all).

**Traps and how they were avoided.**
(1) Oblique incidence gives zeros through `Sample.rt()`: built from the blocks as above.
(2) iadpython's Radau points come from Legendre polynomial coefficients and lose accuracy
above about 20-24 points (at normal incidence, 32 points moves R by 1e-5 and 40 points
gives R = 0.1024 instead of 0.1298 for a = 0.9, tau = 1, g = 0.5): no order above 20.
(3) The default starting layer (thickness halved until below the smallest quadrature
cosine) leaves relative errors of 1e-4 at 60 deg and up to 7e-3 at 85 deg in the
unscattered beam; the start here is 16 times thinner (but not below 1e-4, where iadpython
switches to the first-order IGI start), which brings the non-scattering errors to 1.7e-7.
(4) The Fresnel boundaries are GGX microsurfaces, not exactly smooth. Same-seed runs of
the clear n = 1.5 slab at alpha = 1e-2, 1e-3, 1e-4 (2e6 paths) differ in R by 1.7e-3,
2.5e-5 between 1e-3 and 1e-4 at 60 deg and 1.9e-4 at 80 deg, falling faster than linearly
in alpha, so alpha = 1e-4 is smooth to about 1e-5 or better at the angles used; R + T of
that slab is 0.999999, and scattering slabs (n = 1.33 and 1.5) moved by at most 1.6e-4
(below their 6e-4 noise) between alpha 1e-3 and 1e-4. The clear slab agrees with the
closed form within 0.7 sigma. (5) Conventions: theta_o is the angle in air (iadpython
refracts it itself: `cos_snell(1, nu_0, n)`); n_above/n_below are glass slides in
iadpython, set to 1 here (no slides); mus and mua are per unit length and the slab is one
unit thick, so they are optical thicknesses. (6) Slabs related by the similarity
relation (same mua and (1-g) mus) give nearly the same R and T; the case list avoids such
near duplicates.
"""


def main(argv):
    quick = "--quick" in argv
    cs = cases(quick)
    if "--convergence" in argv:
        for a, tau, g, n in (QUICK if quick else SLABS):
            for th in ANGLES:
                mu0 = 1.0 if th == 0 else math.cos(math.radians(th))
                (r, dr), (t, dt), vals = reference(a, tau, g, n, mu0)
                per = "  ".join(f"{q}: {v[0]:.6f} {v[1]:.6f}" for q, v in vals.items())
                print(f"{slab_name(a, tau, g, n):34s} {th:4.0f}  {per}  spread R {dr:.1e} T {dt:.1e}")
        return 0
    if "--run" not in argv:
        for c in cs:
            for ch in c["checks"]:
                print(f"{c['name']:40s} slice {ch['slice']} {ch['q']} {ch['ref']:.6f} +- {ch['ref_err']:.1e}")
        return 0
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import common
    scale = float(argv[argv.index("--paths-scale") + 1]) if "--paths-scale" in argv else 1.0
    key = "fixture_paths" if "--fixture" in argv else "paths"
    print(common.HEADER)
    bad = 0
    for c in cs:
        for r in common.rows_of_case(c, c[key] * scale):
            print(common.format_row(r), f"{r['seconds']:.1f}s", flush=True)
            bad += r["verdict"] == "FAIL"
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
