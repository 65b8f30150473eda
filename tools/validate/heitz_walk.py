#!/usr/bin/env python3
"""An independent reference for lsqt-cl's multiple-scattering microsurfaces: the random walk
on a microsurface of Heitz, Hanika, d'Eon and Dachsbacher 2016 ("Multiple-scattering
microfacet BSDFs with the Smith model"), written from the paper in numpy.

    python3 tools/validate/heitz_walk.py             # self-checks (numpy, scipy)
    python3 tools/validate/heitz_walk.py --compare   # then every case against lsqt-cl (LSQT_CL)
      options: --no-self-checks, --fixture (the cases' fixture_paths), --quick (10x fewer walks)

Model: uncorrelated heights with the uniform distribution on [-1, 1] (the walk only needs
C1(h) = (h + 1) / 2, so it keeps u = C1(h) in [0, 1]); Trowbridge-Reitz (GGX) slopes,
isotropic alpha, Smith Lambda(w) = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2 for w upward.

A ray at u travelling upward (d.z > 0) survives to u' > u with probability (u / u')^Lambda(d)
and leaves the surface with probability G1 = u^Lambda(d); travelling downward it survives to
u' < u with probability (u' / u)^(1 + Lambda(-d)) and always hits. At a hit the facet normal
is drawn from the visible normals D_wi(m) ~ <wi, m>+ D(m), wi = -d (either hemisphere: an
upward ray sees facets from below). Facets: conductor (mirror, weight times the exact
Fresnel of the complex index), dielectric (Fresnel reflect or refract; after refraction the
walk goes on on the other side, seen in a mirrored frame z -> -z where the surface is again
the same uncorrelated GGX surface with u -> 1 - u and the relative index inverted; leaving
that side upward is transmission), Lambertian (cosine lobe about m, weight times fR).

The walk is vectorised over walks, with a fixed seed; it returns the directional albedo
R (leaves upward) and T (leaves downward) for light entering along -wo, theta_o from the
normal, with the standard error of the mean.

Visible-normal sampling, derived here for both hemispheres of wi: stretch wi to the alpha = 1
configuration, where GGX is the distribution of the normals of a unit hemisphere (D = 1/pi)
and D_wi is uniform over the projection of the visible part of that hemisphere onto the
plane normal to wi. With the frame T1 = z x wi / |.|, T2 = wi x T1 (T2.z = sin theta >= 0)
a point x T1 + y T2 of the unit disk lifts to a normal with z > 0 iff y > -cos(theta)
sqrt(1 - x^2) (cos theta signed). So: x has density ~ sqrt(1 - x^2) (the x of a uniform
point in the disk) and, given x, y is uniform on (-cos theta s, s), s = sqrt(1 - x^2), for
wi above or below the horizon alike. Unstretch the normal.
"""
import math
import os
import sys

import numpy as np

GROUP = "heitz2016"

METAL = (1.1, 2.6)  # complex index n + i k of the conductor cases (copper-like at 0.5 um)
DIELECTRIC_ETA = 1.5
LAMBERT_FR = 0.7
ALPHAS = (0.3, 1.0, 2.0)
ANGLES = (0.0, 45.0, 75.0)
MAX_BOUNCES = 1000


# ---------------------------------------------------------------------------- small math
def normalize(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def dot(a, b):
    return np.sum(a * b, axis=-1)


def lambda_ggx(z, alpha):
    """Smith Lambda of GGX for a direction with cosine z > 0 to the macro normal."""
    z = np.clip(z, 1e-150, 1.0)
    tan2 = np.maximum(1.0 - z * z, 0.0) / (z * z)
    return 0.5 * (-1.0 + np.sqrt(1.0 + alpha * alpha * tan2))


def fresnel_dielectric(c, eta):
    """Unpolarised Fresnel reflectance, cosine c > 0 on the incident side, eta = n_t / n_i."""
    sin2_t = (1.0 - c * c) / (eta * eta)
    tir = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    rs = (c - eta * cos_t) / (c + eta * cos_t)
    rp = (eta * c - cos_t) / (eta * c + cos_t)
    return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))


def fresnel_conductor(c, n, k):
    """Unpolarised Fresnel reflectance from vacuum onto a complex index n + i k."""
    N2 = complex(n, k) ** 2
    c = np.asarray(c, dtype=float)
    root = np.sqrt(N2 - (1.0 - c * c) + 0j)
    rs = (c - root) / (c + root)
    rp = (N2 * c - root) / (N2 * c + root)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def sample_vndf(wi, alpha, u1, u2, u3):
    """Normals m (m.z > 0) with density ~ max(0, wi.m) D(m), wi unit, wi.z of either sign."""
    ws = normalize(np.stack([alpha * wi[:, 0], alpha * wi[:, 1], wi[:, 2]], axis=-1))
    c = ws[:, 2]
    sxy = np.hypot(ws[:, 0], ws[:, 1])
    ok = sxy > 1e-12
    sx = np.where(ok, sxy, 1.0)
    t1 = np.stack([np.where(ok, -ws[:, 1] / sx, 1.0), np.where(ok, ws[:, 0] / sx, 0.0), np.zeros_like(c)], axis=-1)
    t2 = np.cross(ws, t1)
    x = np.sqrt(u1) * np.cos(2.0 * np.pi * u2)
    s = np.sqrt(np.maximum(1.0 - x * x, 0.0))
    y = s * (-c + u3 * (1.0 + c))
    zz = np.sqrt(np.maximum(1.0 - x * x - y * y, 0.0))
    ms = x[:, None] * t1 + y[:, None] * t2 + zz[:, None] * ws
    return normalize(np.stack([alpha * ms[:, 0], alpha * ms[:, 1], np.maximum(ms[:, 2], 1e-12)], axis=-1))


def sample_cosine_about(m, u1, u2):
    """Directions with density cos(angle to m) / pi in the hemisphere of m."""
    r = np.sqrt(u1)
    ph = 2.0 * np.pi * u2
    lx, ly, lz = r * np.cos(ph), r * np.sin(ph), np.sqrt(np.maximum(1.0 - u1, 0.0))
    a = np.where(np.abs(m[:, 2:3]) < 0.9, np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]]))
    b1 = normalize(np.cross(a, m))
    b2 = np.cross(m, b1)
    return lx[:, None] * b1 + ly[:, None] * b2 + lz[:, None] * m


# ---------------------------------------------------------------------------- the walk
def walk(kind, alpha, theta_o, n, seed=1, eta=DIELECTRIC_ETA, metal=METAL, fR=LAMBERT_FR, kR=1.0, kT=1.0,
         fresnel_one=False, wo=None, max_bounces=MAX_BOUNCES):
    """n walks entering along -wo (wo at theta_o in the xz-plane, or the given (n,3) array).
    kind: 'conductor', 'dielectric' (eta = n_below / n_above) or 'lambertian'.
    Returns per-walk arrays: weight leaving up, weight leaving down, bounces, first-order flag."""
    rng = np.random.default_rng(seed)
    if wo is None:
        wo = np.tile([math.sin(theta_o), 0.0, math.cos(theta_o)], (n, 1))
    d = -np.asarray(wo, dtype=float)  # direction of travel, in the frame of the current side
    u = np.ones(n)  # C1 of the height; the walk starts above the whole surface
    side = np.zeros(n, dtype=np.int8)  # 0: the side of incidence, 1: the other (dielectric)
    w = np.ones(n)
    up, down = np.zeros(n), np.zeros(n)
    bounces = np.zeros(n, dtype=np.int64)
    first_order = np.zeros(n, dtype=bool)  # left after exactly one facet interaction
    idx = np.arange(n)
    for _ in range(max_bounces + 1):
        if idx.size == 0:
            break
        dd, uu = d[idx], u[idx]
        x = rng.random(idx.size)
        x = np.where(x > 0.0, x, 1e-300)
        going_up = dd[:, 2] > 0.0
        lam_up = lambda_ggx(dd[:, 2], alpha)
        lam_dn = 1.0 + lambda_ggx(-dd[:, 2], alpha)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            log_u = np.log(np.maximum(uu, 1e-300))
            log_new = np.where(going_up, log_u - np.log(x) / lam_up, log_u + np.log(x) / lam_dn)
        escaped = going_up & ~(log_new < 0.0)
        e = idx[escaped]
        s = side[e]
        up[e[s == 0]] = w[e[s == 0]]
        down[e[s == 1]] = w[e[s == 1]]
        first_order[e] = bounces[e] == 1
        keep = ~escaped
        idx, dd, log_new = idx[keep], dd[keep], log_new[keep]
        if idx.size == 0:
            break
        u[idx] = np.exp(log_new)
        wi = -dd
        r = rng.random((idx.size, 3))
        m = sample_vndf(wi, alpha, r[:, 0], r[:, 1], r[:, 2])
        c = np.clip(dot(wi, m), 0.0, 1.0)
        bounces[idx] += 1
        if kind == "conductor":
            F = np.ones_like(c) if fresnel_one else fresnel_conductor(c, *metal)
            w[idx] *= F
            d[idx] = -wi + 2.0 * c[:, None] * m
        elif kind == "lambertian":
            w[idx] *= fR
            r2 = rng.random((idx.size, 2))
            d[idx] = sample_cosine_about(m, r2[:, 0], r2[:, 1])
        elif kind == "dielectric":
            e_rel = np.where(side[idx] == 0, eta, 1.0 / eta)
            F = fresnel_dielectric(c, e_rel)
            refl = rng.random(idx.size) < F
            w[idx] *= np.where(refl, kR, kT)
            nd = -wi + 2.0 * c[:, None] * m
            sin2_t = (1.0 - c * c) / (e_rel * e_rel)
            cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
            wt = -wi / e_rel[:, None] + (c / e_rel - cos_t)[:, None] * m
            wt = normalize(wt * np.array([1.0, 1.0, -1.0]))  # into the mirrored frame of the other side
            nd = np.where(refl[:, None], nd, wt)
            d[idx] = normalize(nd)
            t = idx[~refl]
            u[t] = 1.0 - u[t]
            side[t] ^= 1
        else:
            raise ValueError(kind)
    cut = idx.size  # walks still on the surface after max_bounces facets (counted as lost)
    return {"up": up, "down": down, "bounces": bounces, "first": first_order, "cut": cut, "n": n}


def albedo(kind, alpha, theta_deg, n, seed=1, **kw):
    """Directional albedo R, T with standard errors, and diagnostics."""
    o = walk(kind, alpha, math.radians(theta_deg), n, seed=seed, **kw)
    sq = math.sqrt(n)
    return {"R": float(o["up"].mean()), "R_err": float(o["up"].std(ddof=1) / sq),
            "T": float(o["down"].mean()), "T_err": float(o["down"].std(ddof=1) / sq),
            "R1": float((o["up"] * o["first"]).mean()), "T1": float((o["down"] * o["first"]).mean()),
            "mean_bounces": float(o["bounces"].mean()), "max_bounces": int(o["bounces"].max()), "cut": o["cut"]}


# ---------------------------------------------------------------------------- quadratures
def _m_grid(alpha, nt=800, nphi=400):
    """Normals m on a grid (Gauss-Legendre in t = atan(tan theta_m / alpha) and phi), with
    weights of dm, so that sum D(m) dm = 1 to quadrature accuracy even for small alpha."""
    xt, wt = np.polynomial.legendre.leggauss(nt)
    t = 0.25 * np.pi * (xt + 1.0)  # in (0, pi/2)
    th = np.arctan(alpha * np.tan(t))
    dth = alpha / np.cos(t) ** 2 / (1.0 + (alpha * np.tan(t)) ** 2) * 0.25 * np.pi * wt
    xp, wp = np.polynomial.legendre.leggauss(nphi)
    ph = np.pi * (xp + 1.0)
    dph = np.pi * wp
    TH, PH = np.meshgrid(th, ph, indexing="ij")
    W = np.outer(np.sin(th) * dth, dph)
    m = np.stack([np.sin(TH) * np.cos(PH), np.sin(TH) * np.sin(PH), np.cos(TH)], axis=-1)
    cm = np.cos(TH)
    tan2 = np.tan(TH) ** 2
    D = 1.0 / (np.pi * alpha ** 2 * cm ** 4 * (1.0 + tan2 / alpha ** 2) ** 2)
    return m.reshape(-1, 3), (D * W).ravel()


def single_scattering(kind, alpha, theta_deg, eta=DIELECTRIC_ETA, metal=METAL, fresnel_one=False, grid=(800, 400)):
    """Single-scattering albedo of the uniform-height GGX microsurface by quadrature over m:
    R1 = int D <wi,m>+ / cos_i F / (1 + L(wi) + L(wo)) dm (reflection up),
    T1 = int D <wi,m>+ / cos_i (1 - F) B(1 + L(wi), 1 + L(-wt)) dm (refraction down), the
    height-correlated Smith terms that uniform uncorrelated heights imply (Heitz 2014, 2016)."""
    from scipy.special import beta as B
    m, dm = _m_grid(alpha, *grid)
    th = math.radians(theta_deg)
    wi = np.array([math.sin(th), 0.0, math.cos(th)])
    c = m @ wi
    vis = c > 0
    m, dm, c = m[vis], dm[vis], c[vis]
    li = float(lambda_ggx(np.array([wi[2]]), alpha)[0])
    wo = 2.0 * c[:, None] * m - wi
    if kind == "conductor":
        F = np.ones_like(c) if fresnel_one else fresnel_conductor(c, *metal)
    else:
        F = fresnel_dielectric(c, eta)
    okr = wo[:, 2] > 0
    lo = lambda_ggx(wo[:, 2], alpha)
    R1 = np.sum(np.where(okr, dm * c / wi[2] * F / (1.0 + li + lo), 0.0))
    T1 = 0.0
    if kind == "dielectric":
        sin2_t = (1.0 - c * c) / eta ** 2
        cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
        wt = -wi / eta + (c / eta - cos_t)[:, None] * m
        okt = (wt[:, 2] < 0) & (sin2_t < 1.0)
        lt = lambda_ggx(-wt[:, 2], alpha)
        T1 = np.sum(np.where(okt, dm * c / wi[2] * (1.0 - F) * B(1.0 + li, 1.0 + lt), 0.0))
    norm = np.sum(dm * c / wi[2])  # = 1 + Lambda(wi): projected area of the visible facets
    return float(R1), float(T1), float(norm), 1.0 + li


# ---------------------------------------------------------------------------- self-checks
def vndf_check(alpha, wi, n=400000, seed=7):
    """Moments of sampled visible normals against quadrature of <wi,m>+ D(m)."""
    rng = np.random.default_rng(seed)
    r = rng.random((n, 3))
    ms = sample_vndf(np.tile(wi, (n, 1)), alpha, r[:, 0], r[:, 1], r[:, 2])
    m, dm = _m_grid(alpha)
    wq = np.maximum(m @ wi, 0.0) * dm
    out = []
    for f in (lambda v: v[:, 0], lambda v: v[:, 2], lambda v: v[:, 2] ** 2, lambda v: v[:, 0] * v[:, 2]):
        q = np.sum(f(m) * wq) / np.sum(wq)
        s = f(ms)
        out.append((float(s.mean()), float(s.std() / math.sqrt(n)), float(q)))
    return out


def self_checks(n=200000):
    lines = []
    p = lines.append
    # visible normals, wi above and below the horizon
    for alpha, wi in ((0.3, (0.6, 0.0, 0.8)), (1.0, (0.6, 0.0, 0.8)), (2.0, (0.8, 0.0, -0.6)), (1.0, (0.96, 0.0, -0.28))):
        wi = np.array(wi)
        worst = max(abs(s - q) / e for s, e, q in vndf_check(alpha, wi))
        p(f"VNDF alpha={alpha} wi.z={wi[2]:+.2f}: moments E[m.x], E[m.z], E[m.z^2], E[m.x m.z] vs quadrature, "
          f"largest |z| = {worst:.2f}")
    # quadrature sanity: sum <wi,m>+ D dm / cos = 1 + Lambda(wi)
    for alpha, th in ((0.3, 75.0), (2.0, 45.0)):
        _, _, norm, want = single_scattering("conductor", alpha, th)
        p(f"quadrature alpha={alpha} theta={th}: int <wi,m>+ D dm / cos_i = {norm:.6f}, 1 + Lambda = {want:.6f}")
    # energy: conductor with Fresnel = 1, dielectric with kR = kT = 1, Lambertian fR = 1
    for alpha in (1.0, 2.0):
        for th in (0.0, 75.0):
            a = albedo("conductor", alpha, th, n, fresnel_one=True)
            b = albedo("dielectric", alpha, th, n)
            c = albedo("lambertian", alpha, th, n, fR=1.0)
            p(f"energy alpha={alpha} theta={th}: conductor F=1 R = {a['R']:.6f} (mean bounces {a['mean_bounces']:.3f},"
              f" cut {a['cut']}); dielectric R+T = {b['R'] + b['T']:.6f} (cut {b['cut']}); Lambertian fR=1 R = "
              f"{c['R']:.6f} (mean bounces {c['mean_bounces']:.3f}, cut {c['cut']})")
    # first-order (single-scattering) part of the walk against quadrature
    for kind, alpha, th, kw in (("conductor", 1.0, 45.0, {"fresnel_one": True}), ("conductor", 2.0, 75.0, {}),
                                ("dielectric", 0.3, 0.0, {}), ("dielectric", 1.0, 45.0, {}),
                                ("dielectric", 2.0, 75.0, {})):
        a = albedo(kind, alpha, th, n, **kw)
        R1, T1, _, _ = single_scattering(kind, alpha, th, **kw)
        eR = math.sqrt(max(a["R1"] * (1 - a["R1"]), 1e-30) / n)
        eT = math.sqrt(max(a["T1"] * (1 - a["T1"]), 1e-30) / n)
        p(f"single scattering {kind}{' F=1' if kw else ''} alpha={alpha} theta={th}: walk R1 = {a['R1']:.5f} vs "
          f"quadrature {R1:.5f} (z {(a['R1'] - R1) / eR:+.2f})" +
          (f"; walk T1 = {a['T1']:.5f} vs {T1:.5f} (z {(a['T1'] - T1) / eT:+.2f})" if kind == "dielectric" else ""))
    # smooth limit: alpha -> 0 gives the Fresnel values and the facet albedo
    for th in (0.0, 45.0, 75.0):
        c = math.cos(math.radians(th))
        a = albedo("conductor", 1e-3, th, n)
        b = albedo("dielectric", 1e-3, th, n)
        l = albedo("lambertian", 1e-3, th, n)
        Fc = float(fresnel_conductor(np.array([c]), *METAL)[0])
        Fd = float(fresnel_dielectric(np.array([c]), DIELECTRIC_ETA)[0])
        p(f"alpha=1e-3 theta={th}: conductor R = {a['R']:.5f} +- {a['R_err']:.1e} (Fresnel {Fc:.5f}); dielectric "
          f"R = {b['R']:.5f} +- {b['R_err']:.1e} (Fresnel {Fd:.5f}), T = {b['T']:.5f}; Lambertian R = {l['R']:.5f} "
          f"+- {l['R_err']:.1e} (fR {LAMBERT_FR})")
    # reciprocity of the multiple-scattering dielectric: with diffuse (cosine-weighted)
    # incidence, eta_a^2 T_hh(a -> b) = eta_b^2 T_hh(b -> a); from below is eta -> 1/eta
    n5 = 5 * n
    rng = np.random.default_rng(11)
    r = rng.random((2, n5))
    cz = np.sqrt(r[0])
    wo = np.stack([np.sqrt(1 - cz ** 2) * np.cos(2 * np.pi * r[1]), np.sqrt(1 - cz ** 2) * np.sin(2 * np.pi * r[1]), cz], -1)
    for alpha in (0.3, 1.0):
        t_ab = walk("dielectric", alpha, 0.0, n5, seed=12, wo=wo)["down"]
        t_ba = walk("dielectric", alpha, 0.0, n5, seed=13, wo=wo, eta=1.0 / DIELECTRIC_ETA)["down"]
        a, b = t_ab.mean(), DIELECTRIC_ETA ** 2 * t_ba.mean()
        e = math.hypot(t_ab.std() / math.sqrt(n5), DIELECTRIC_ETA ** 2 * t_ba.std() / math.sqrt(n5))
        p(f"reciprocity alpha={alpha} eta={DIELECTRIC_ETA}: T_hh(above) = {a:.5f}, eta^2 T_hh(below) = {b:.5f} "
          f"(z {(a - b) / e:+.2f})")
    return lines


# ---------------------------------------------------------------------------- cases
def _lsqt(kind, alpha):
    if kind == "conductor":
        return (f"Medium\nLayer z=0 MicrosurfaceConductiveBrdf alpha={alpha} use_multiple_scattering=true\n"
                f"Medium eta={METAL[0]} mua={METAL[1]}\n")
    if kind == "dielectric":
        return f"Medium\nLayer z=0 MicrosurfaceDielectricBsdf alpha={alpha}\nMedium eta={DIELECTRIC_ETA}\n"
    return f"Medium\nLayer z=0 MicrosurfaceLambertianBrdf alpha={alpha} fR={LAMBERT_FR}\nMedium\n"


# walks per reference value: ref_err ~ 1e-3 or below (dielectric R, T are 0 or 1 per walk)
N_REF = {"conductor": 100000, "dielectric": 500000, "lambertian": 200000}
ARGS = ["--wo-angles=" + ",".join(f"{t:g}" for t in ANGLES), "--wi-spread", "-wi", "16"]


def _ms_checks(kind, alpha, n, seed, first_slice=0, **kw):
    checks = []
    for k, th in enumerate(ANGLES):
        a = albedo(kind, alpha, th, n, seed=seed + k, **kw)
        if a["cut"]:
            raise RuntimeError(f"{a['cut']} walks reached {MAX_BOUNCES} facets ({kind}, alpha {alpha}, {th} deg)")
        checks.append({"slice": first_slice + k, "q": "R", "ref": a["R"], "ref_err": a["R_err"], "limitation": None})
        if kind == "dielectric":
            checks.append({"slice": first_slice + k, "q": "T", "ref": a["T"], "ref_err": a["T_err"],
                           "limitation": None})
        else:  # nothing leaves downward: T = 0 exactly
            checks.append({"slice": first_slice + k, "q": "T", "ref": 0.0, "ref_err": 0.0, "limitation": None})
    return checks


def cases(quick=False):
    """Single-layer cases. Multiple scattering: the walk's albedo, ref_err its standard error.
    The dielectric also from below (--from-below: slices 3-5, light entering from eta=1.5;
    the walk from below is the walk from above with eta -> 1/eta, the surface being
    symmetric), and once with kR, kT < 1. Single scattering (use_multiple_scattering=false):
    the quadrature of single_scattering(), ref_err its change from a 400x200 to an 800x400 grid."""
    div = 10 if quick else 1
    out = []
    for kind in ("conductor", "dielectric", "lambertian"):
        extra = {"conductor": f" (metal {METAL[0]}+{METAL[1]}i)", "dielectric": f" eta={DIELECTRIC_ETA}",
                 "lambertian": f" fR={LAMBERT_FR}"}[kind]
        for ia, alpha in enumerate(ALPHAS):
            seed = 1000 * (1 + ("conductor", "dielectric", "lambertian").index(kind)) + 100 * ia
            checks = _ms_checks(kind, alpha, N_REF[kind] // div, seed)
            args = list(ARGS)
            if kind == "dielectric":
                checks += _ms_checks(kind, alpha, N_REF[kind] // div, seed + 50, first_slice=len(ANGLES),
                                     eta=1.0 / DIELECTRIC_ETA)
                args.append("--from-below")
            out.append({"group": GROUP, "name": f"MS {kind} a={alpha}{extra}" + (" +below" if kind == "dielectric" else ""),
                        "lsqt": _lsqt(kind, alpha), "args": args, "paths": 200000,
                        "fixture_paths": 100000, "checks": checks})
    out.append({"group": GROUP, "name": f"MS dielectric a=1.0 eta={DIELECTRIC_ETA} kR=0.8 kT=0.9",
                "lsqt": _lsqt("dielectric", 1.0).replace("alpha=1.0", "alpha=1.0 kR=0.8 kT=0.9"), "args": list(ARGS),
                "paths": 200000, "fixture_paths": 100000,
                "checks": _ms_checks("dielectric", 1.0, N_REF["dielectric"] // div, 7000, kR=0.8, kT=0.9)})
    for kind in ("conductor", "dielectric"):
        for alpha in ALPHAS:
            checks = []
            for k, th in enumerate(ANGLES):
                fine = single_scattering(kind, alpha, th)
                coarse = single_scattering(kind, alpha, th, grid=(400, 200))
                for q, i in (("R", 0), ("T", 1)):
                    err = 0.0 if fine[i] == 0.0 else max(abs(fine[i] - coarse[i]), 1e-7)
                    checks.append({"slice": k, "q": q, "ref": fine[i], "ref_err": err, "limitation": None})
            text = _lsqt(kind, alpha).replace(" use_multiple_scattering=true", "").replace(
                f"alpha={alpha}", f"alpha={alpha} use_multiple_scattering=false")
            out.append({"group": GROUP, "name": f"SS {kind} a={alpha} (quadrature)", "lsqt": text,
                        "args": list(ARGS), "paths": 200000, "fixture_paths": 100000, "checks": checks})
    return out


DOC = """\
## Multiple-scattering microsurfaces: the Heitz et al. 2016 random walk (`heitz2016`)

`tools/validate/heitz_walk.py` is an independent numpy implementation of the random walk on
a microsurface of Heitz, Hanika, d'Eon and Dachsbacher 2016 ("Multiple-scattering
microfacet BSDFs with the Smith model"), written from the paper and first principles, not
from lsqt-cl's kernels. The surface: uncorrelated heights with the uniform distribution,
GGX (Trowbridge-Reitz) slopes, isotropic alpha. Between facets the walk samples the free
path from the Smith masking: a ray at height h going up leaves the surface with
probability C1(h)^Lambda(w), otherwise hits at C1(h') = C1(h) X^(-1/Lambda); going down it
always hits, at C1(h') = C1(h) X^(1/(1 + Lambda(-w))). At a hit the facet normal is drawn
from the visible normals of the direction of arrival, above or below the horizon (a ray
going up can hit a facet from below; the sampler for both cases is derived in the file's
docstring). Facets: conductor mirrors (weight times the exact Fresnel reflectance of the
complex index), dielectric interfaces (reflect with the Fresnel probability, else refract,
weights kR and kT; after a refraction the walk continues on the other side, in the
mirrored frame where the surface is again the same random surface, C1 -> 1 - C1, relative
index inverted), or Lambertian reflectors of albedo fR (cosine lobe about the facet
normal). It estimates the directional albedo R (energy leaving upward) and T (downward)
for light entering at theta_o, with the standard error of the mean over 1e5 (conductor),
5e5 (dielectric) or 2e5 (Lambertian) walks with fixed seeds; no walk reached the cap of
1000 facets. A second reference, for `use_multiple_scattering=false`, is the
single-scattering albedo by quadrature over facet normals (Gauss-Legendre, 800 x 400),
with the height-correlated Smith terms that uniform uncorrelated heights imply:
reflection `<wi,m> D F / (cos_i (1 + Lambda_i + Lambda_o))`, transmission
`<wi,m> D (1 - F) B(1 + Lambda_i, 1 + Lambda_t) / cos_i` (B the beta function); its
ref_err is its change from a 400 x 200 grid (at most 3e-6).

Self-checks of the reference (`python3 tools/validate/heitz_walk.py`, 2e5 walks each):

| check | result |
| --- | --- |
| visible normals, wi.z = +0.8 (alpha 0.3, 1), -0.6 (alpha 2), -0.28 (alpha 1): four moments of m against quadrature of <wi,m>+ D(m) | largest \\|z\\| 1.94, 1.94, 1.83, 2.23 (4e5 samples) |
| quadrature: integral of <wi,m>+ D dm / cos_i = 1 + Lambda(wi) | 1.250589 vs 1.250589 (alpha 0.3, 75 deg); 1.618034 vs 1.618034 (alpha 2, 45 deg) |
| energy: conductor with Fresnel = 1, dielectric kR = kT = 1 (R + T), Lambertian fR = 1; alpha 1 and 2, theta 0 and 75 | all 1.000000, no walk cut (mean facets per walk 1.6-4.4) |
| first-order part of the walk against the single-scattering quadrature | conductor F=1 alpha 1, 45 deg: 0.37575 vs 0.37677 (z -0.95); conductor alpha 2, 75 deg: 0.21041 vs 0.21162 (z -1.32); dielectric R1/T1 alpha 0.3, 0 deg: 0.03519/0.95297 vs 0.03560/0.95279; alpha 1, 45 deg: 0.01690/0.74440 vs 0.01734/0.74449; alpha 2, 75 deg: 0.01819/0.03488 vs 0.01819/0.03524 (all \\|z\\| < 1.6) |
| smooth limit alpha = 1e-3, theta 0/45/75 | conductor R 0.60609/0.60468/0.65627 = Fresnel 0.60609/0.60469/0.65627; dielectric R 0.0397/0.0501/0.2524 (+-5e-4, 5e-4, 1e-3) vs Fresnel 0.0400/0.0502/0.2531; Lambertian R = 0.70000 = fR |
| reciprocity of the multiple-scattering dielectric, diffuse incidence: T_hh(above) = eta^2 T_hh(below) (1e6 walks) | alpha 0.3: 0.94250 vs 0.94383 (z -1.17); alpha 1: 0.97542 vs 0.97584 (z -0.37) |

Compared (single layer, `--wo-angles=0,45,75 --wi-spread -wi 16`; R and T from lsqt-cl's
exit tallies): `MicrosurfaceConductiveBrdf use_multiple_scattering=true` over a metal of
index 1.1 + 2.6i; `MicrosurfaceDielectricBsdf` over a medium of eta 1.5 with
`--from-below` (slices 3-5: light entering from the eta = 1.5 side, R back into it, T out
into the top medium; the walk uses eta = 1/1.5), and once with kR = 0.8, kT = 0.9 (alpha
1); `MicrosurfaceLambertianBrdf fR=0.7` (T = 0 exactly for the BRDFs); each at alpha 0.3,
1 and 2. Single scattering: the conductor and the dielectric with
`use_multiple_scattering=false` at the same alphas against the quadrature. At 2e5 paths
per slice all 120 rows agree, largest |z| 2.30.
"""


def main():
    if "--no-self-checks" not in sys.argv:
        for line in self_checks():
            print(line, flush=True)
    if "--compare" in sys.argv:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import common
        key = "fixture_paths" if "--fixture" in sys.argv else "paths"
        print(common.HEADER)
        worst = 0.0
        for case in cases("--quick" in sys.argv):
            for row in common.rows_of_case(case, case[key]):
                worst = max(worst, abs(row["z"]))
                print(common.format_row(row), flush=True)
        print(f"largest |z| = {worst:.2f}")
        return 1 if worst > common.Z_MAX else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
