"""Closed forms, computed here with the standard library only
(Gauss-Legendre quadrature written below): a single Lambertian layer, two Lambertian
layers by the adding formula, Oren-Nayar's directional albedo, the attenuation and
single scattering of thin slabs (HG, Rayleigh), and the limits alpha -> 0, mus -> 0 and
rho = 1."""
import math

GROUP = "closed form"

DOC = """Closed forms, evaluated by the standard library in
`tools/validate/refs_closed.py` (Gauss-Legendre quadrature with 64-96 nodes per dimension;
the quadrature error, judged by halving the nodes, is below 1e-9 and enters as a floor of
1e-7 in `ref_err`):

- a single Lambertian layer: R = fR, T = fT, and every point estimate is fR/pi (1/sr);
- two Lambertian layers in vacuum: R = R1 + T1^2 R2 / (1 - R1 R2) (the adding formula for
  the hemispherical albedo, exact for Lambertian layers);
- Oren-Nayar ("simpler expression" of the later public layered-sqt guide): its point estimates are the formula
  itself, and R(theta_o) is its directional albedo by a 2-D quadrature (the formula
  reflects slightly more than it receives at grazing incidence: R > fR there, and that is
  the formula's, not the simulator's);
- a clear absorbing slab over a Lambertian floor: R = fR exp(-tau/mu_o) 2 E3(tau), and the
  unscattered forward coefficient of an absorbing null slab delta_T = exp(-tau/mu_o);
- single scattering in an optically thin slab (tau = 1e-3, where double scattering is
  below 1e-6 of the incident light): R = omega times the integral over the upper hemisphere
  of p(w_o, w) mu/(mu_o + mu) (1 - exp(-tau (1/mu_o + 1/mu))) dw (see `thin_R`),
  for Henyey-Greenstein g = 0.7 and Rayleigh rho = 0 and 0.5;
- limits: a microsurface Lambertian layer at alpha = 1e-4 is a Lambertian layer (to about
  (alpha tan theta)^2 of the value, the masking left at that alpha: the reference's error), a medium
  with mus = 1e-9 is clear, and Rayleigh with rho = 1 is isotropic (against the
  adding-doubling value of the isotropic slab, iadpython, quadrature 16)."""


def gauss_legendre(n):
    """Nodes and weights on [-1, 1] (Newton on the Legendre recurrence)."""
    xs, ws = [], []
    for i in range(n):
        x = math.cos(math.pi * (i + 0.75) / (n + 0.5))
        for _ in range(100):
            p0, p1 = 1.0, x
            for k in range(2, n + 1):
                p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
            dp = n * (x * p1 - p0) / (x * x - 1)
            dx = p1 / dp
            x -= dx
            if abs(dx) < 1e-15:
                break
        xs.append(x)
        ws.append(2 / ((1 - x * x) * dp * dp))
    return xs, ws


def integrate(f, a, b, n=64):
    xs, ws = gauss_legendre(n)
    h = 0.5 * (b - a)
    return h * sum(w * f(a + h * (x + 1)) for x, w in zip(xs, ws))


def e3(tau):
    """Exponential integral E3(tau) = int_0^1 exp(-tau/mu) mu dmu."""
    return integrate(lambda mu: math.exp(-tau / mu) * mu if mu > 0 else 0.0, 0.0, 1.0, 96)


def oren_nayar(fr, sigma, ti, to, dphi):
    s2 = sigma * sigma
    a = 1 - 0.5 * s2 / (s2 + 0.33)
    b = 0.45 * s2 / (s2 + 0.09)
    al, be = max(ti, to), min(ti, to)
    return fr / math.pi * (a + b * max(0.0, math.cos(dphi)) * math.sin(al) * math.tan(be))


def oren_nayar_albedo(fr, sigma, to):
    """R(theta_o) = int f cos(theta_i) dw_i over the upper hemisphere (symmetric in phi)."""
    def over_phi(ti):
        return 2 * integrate(lambda p: oren_nayar(fr, sigma, ti, to, p), 0.0, math.pi, 64)
    # split at theta_i = theta_o, where the formula has a kink
    g = lambda ti: over_phi(ti) * math.cos(ti) * math.sin(ti)
    return integrate(g, 0.0, to, 64) + integrate(g, to, math.pi / 2, 64) if to > 0 else integrate(g, 0, math.pi / 2, 64)


def hg(g, c):
    return (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * c) ** 1.5)


def rayleigh(rho, c):
    gam = rho / (2 - rho)
    return 3 / (16 * math.pi) * (1 + 3 * gam + (1 - gam) * c * c) / (1 + 2 * gam)


def thin_R(phase, albedo, tau, mu_o):
    """Single-scattering reflectance of a slab of optical thickness tau for light entering
    at mu_o = cos(theta_o): scattering at depth t, then leaving up at mu,
    R = omega int_0^1 int_0^2pi p(cos Theta) mu / (mu_o + mu) (1 - exp(-tau (1/mu_o + 1/mu))) dphi dmu
    (depth t: reached with exp(-t/mu_o), scatters with dt/mu_o, escapes with exp(-t/mu)).
    The light travels down along -w_o, leaves up along w: cos Theta = -(mu_o mu - s_o s cos phi)
    with the sign of a downward direction against an upward one."""
    so = math.sqrt(1 - mu_o * mu_o)

    def inner(mu):
        s = math.sqrt(max(0.0, 1 - mu * mu))
        k = mu / (mu_o + mu) * -math.expm1(-tau * (1 / mu_o + 1 / mu))
        return k * 2 * integrate(lambda p: phase(-(mu_o * mu) + so * s * math.cos(p)), 0.0, math.pi, 48)
    return albedo * integrate(inner, 1e-12, 1.0, 96)


def lam(fr, ft=0.0):
    return f"LambertianBsdf fR={fr} fT={ft}"


def case(name, lsqt, angles, checks, paths=1e5, fixture_paths=2e4, args=()):
    return {"group": GROUP, "name": name, "lsqt": lsqt,
            "args": ["--wo-angles=" + ",".join(str(a) for a in angles), *args],
            "paths": paths, "fixture_paths": fixture_paths, "checks": checks}


def chk(k, q, ref, ref_err=1e-7):
    return {"slice": k, "q": q, "ref": ref, "ref_err": ref_err, "limitation": None}


def cases(quick=False):
    out = []
    angles = [0, 45, 89.9]
    # a single Lambertian layer: exact values (zero variance: every path weighs fR)
    c = case("Lambertian fR=0.6 fT=0.3", f"Medium\nLayer z=0 {lam(0.6, 0.3)}\nMedium\n", angles, [],
             args=["--wi-spread", "-wi", "16"], paths=2e4, fixture_paths=4e3)
    for k in range(3):
        c["checks"] += [chk(k, "R", 0.6), chk(k, "T", 0.3), chk(k, "f:0", 0.6 / math.pi), chk(k, "f:15", 0.3 / math.pi)]
    out.append(c)
    # adding formula
    r1, t1, r2 = 0.3, 0.5, 0.6
    radd = r1 + t1 * t1 * r2 / (1 - r1 * r2)
    out.append(case("adding: Lambertian 0.3/0.5 over 0.6", f"Medium\nLayer z=1 {lam(r1, t1)}\nMedium\n"
                    f"Layer z=0 {lam(r2)}\nMedium\n", [0, 60, 85], [chk(k, "R", radd) for k in range(3)],
                    args=["--wi-spread", "-wi", "16"]))
    # Oren-Nayar: point estimates are the formula; R is its directional albedo
    for sigma in ([0.1, 0.5] if not quick else [0.5]):
        ang = [0, 60, 80]
        wi = [[math.sin(math.radians(t)) * math.cos(math.radians(p)), math.sin(math.radians(t)) * math.sin(math.radians(p)),
               math.cos(math.radians(t))] for t, p in ((10, 0), (50, 30), (70, 120), (85, 179))]
        c = case(f"Oren-Nayar fR=0.8 sigma={sigma}", f"Medium\nLayer z=0 OrenNayarDiffuseBrdf fR=0.8 sigma={sigma}\nMedium\n",
                 ang, [], paths=1e5, fixture_paths=2e4)
        c["wi"] = wi
        for k, to in enumerate(ang):
            tor = math.radians(to)
            c["checks"].append(chk(k, "R", oren_nayar_albedo(0.8, sigma, tor)))
            for i, (x, y, z) in enumerate(wi):
                ti = math.acos(z)
                c["checks"].append(chk(k, f"f:{i}", oren_nayar(0.8, sigma, ti, tor, math.atan2(y, x)), 1e-6))
        out.append(c)
    # clear absorbing slab over a Lambertian floor; delta_T of an absorbing null slab
    tau = 0.5
    ang = [0, 60]
    out.append(case("clear slab mua=0.5 d=1 over Lambertian 0.7",
                    f"Medium\nLayer z=1 NullBsdf\nMedium mua={tau}\nLayer z=0 {lam(0.7)}\nMedium\n", ang,
                    [chk(k, "R", 0.7 * math.exp(-tau / math.cos(math.radians(t))) * 2 * e3(tau)) for k, t in enumerate(ang)],
                    args=["--wi-spread", "-wi", "16"]))
    out.append(case("absorbing null slab mua=0.5: delta_T",
                    "Medium\nLayer z=1 NullBsdf\nMedium mua=0.5\nLayer z=0 NullBsdf\nMedium\n", [0, 60, 85],
                    [chk(k, "delta_T", math.exp(-0.5 / math.cos(math.radians(t)))) for k, t in enumerate([0, 60, 85])],
                    args=["--wi-spread", "-wi", "16"], paths=4e3, fixture_paths=1e3))
    # single scattering in a thin slab
    thin = [("HenyeyGreensteinPhase g=0.7", lambda c_: hg(0.7, c_)), ("RayleighPhase rho=0", lambda c_: rayleigh(0, c_)),
            ("RayleighPhase rho=0.5", lambda c_: rayleigh(0.5, c_))]
    for text, ph in (thin if not quick else thin[:1]):
        ang = [0, 60]
        out.append(case(f"thin slab tau=1e-3 albedo 0.8 {text}",
                        f"Medium\nLayer z=1 NullBsdf\nMedium mus=8e-4 mua=2e-4 {text}\nLayer z=0 NullBsdf\nMedium\n", ang,
                        [chk(k, "R", thin_R(ph, 0.8, 1e-3, math.cos(math.radians(t))), 2e-7) for k, t in enumerate(ang)],
                        args=["--wi-spread", "-wi", "16"], paths=4e6, fixture_paths=1e6))
    # limits
    # the microsurface differs from the limit by about Lambda ~ (alpha tan theta)^2 / 4 of the value (the
    # masking of the observer's and the light's directions): that is the reference's own error here
    lim = []
    for k, t in enumerate([0, 60, 89]):
        wi9 = 1 - 9.5 / 16  # z of the spread's 10th direction (uniform in z)
        tan_max = max(math.tan(math.radians(t)), math.sqrt(1 - wi9 * wi9) / wi9)
        lim += [chk(k, "R", 0.6, 1e-7 + 0.6 * (1e-4 * tan_max) ** 2)]
        lim += [chk(k, q, 0.6 / math.pi, 1e-7 + 0.6 / math.pi * (1e-4 * tan_max) ** 2) for q in ("f:0", "f:9")]
    out.append(case("limit alpha=1e-4: microsurface Lambertian = Lambertian 0.6",
                    "Medium\nLayer z=0 MicrosurfaceLambertianBrdf alpha=1e-4 fR=0.6\nMedium\n", [0, 60, 89], lim,
                    args=["--wi-spread", "-wi", "16"], paths=1e5, fixture_paths=1e4))
    out.append(case("limit mus=1e-9: clear medium over Lambertian 0.5",
                    "Medium\nLayer z=1 NullBsdf\nMedium mus=1e-9 HenyeyGreensteinPhase g=0.5\nLayer z=0 "
                    f"{lam(0.5)}\nMedium\n", [0, 70], [chk(k, "R", 0.5) for k in range(2)] + [chk(k, "f:3", 0.5 / math.pi) for k in range(2)],
                    args=["--wi-spread", "-wi", "16"], paths=2e4, fixture_paths=4e3))
    out.append(case("limit rho=1: Rayleigh = isotropic (iad slab mus=1 d=1)",
                    "Medium\nLayer z=1 NullBsdf\nMedium mus=1 RayleighPhase rho=1\nLayer z=0 NullBsdf\nMedium\n", [0],
                    [chk(0, "R", 0.3413287, 2e-7), chk(0, "T", 0.6586713, 2e-7)],
                    args=["--wi-spread", "-wi", "16"], paths=2e5, fixture_paths=4e4))
    return out
