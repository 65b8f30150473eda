#!/usr/bin/env python3
"""mie_pigment.py: per-band tables of mus, mua and g (docs/guide.md, "Colour and spectra:
bands", `KEY=@FILE`) for a paint film of spheres of lognormally distributed sizes in a
binder, from Mie theory with miepython (https://github.com/scottprahl/miepython), installed
in a virtual environment so that it leaves Debian's numpy (which xarray needs) alone:
    python3 -m venv /tmp/mie && /tmp/mie/bin/pip install miepython
    /tmp/mie/bin/python tools/mie_pigment.py PREFIX

    tools/mie_pigment.py [--m N+Kj | --index-table FILE] [--radius-um 0.12]
        [--sigma-g 1.4] [--nodes 801] [--volume-fraction 0.15] [--binder-index 1.5]
        [--binder-mua 0.01] [--wavelengths 400:2500:1] PREFIX

Writes PREFIX_mus.txt, PREFIX_mua.txt and PREFIX_g.txt: two columns, the wavelength in
vacuum in nm and the value, with a header of the parameters and the command that makes
them again. mus and mua are per mm (so z in the LSQT file is in mm); g has no unit. The
repository's examples/tables/tio2_*.txt are this tool's output with its defaults (rutile
TiO2 spheres of volume-median radius 0.12 um and geometric standard deviation 1.4, 15 % by
volume, in a binder of index 1.5), read by examples/tio2-paint.lsqt:

    python3 tools/mie_pigment.py examples/tables/tio2

Per wavelength lam (vacuum), with the pigment's index m = n + ik, the binder's index nb
(real) and the volume fraction fv, miepython gives the efficiencies qext, qsca and the
asymmetry parameter g of one sphere of radius r, relative index m/nb and size parameter
x = 2 pi r nb / lam (the wavelength in the binder). For spheres of one radius r
(--sigma-g 1):

    mus = fv * 3 qsca / (4 r)
    mua = fv * 3 (qext - qsca) / (4 r) + (1 - fv) * binder_mua

(the cross-section per particle, pi r^2 q, times the number of particles per volume,
fv / (4/3 pi r^3); the binder fills 1 - fv of the volume). Spheres of many sizes, with
<.> the average over the particles (by number) and V = 4/3 pi r^3:

    mus = fv <Csca> / <V>,  mua = fv <Cabs> / <V> + (1 - fv) * binder_mua,
    g = <g Csca> / <Csca>

(Cabs = Cext - Csca). The sizes are lognormal: ln r is normal with standard deviation
ln(sigma_g) (--sigma-g, the geometric standard deviation, >= 1). --radius-um is the
VOLUME-median radius r_v (half the pigment's volume is in spheres smaller than it; the d50
of a volume or mass distribution, as sedimentation and laser diffraction report it,
halved); the number-median radius is r_n = r_v exp(-3 ln^2 sigma_g) (0.0854 um for the
defaults), and the moments by number are <r^k> = r_n^k exp(k^2 ln^2 sigma_g / 2). With
--sigma-g 1 the spheres have the one radius r_v and the tables are the formulas above
exactly. The default 1.4 is an ASSUMED typical width for a pigment grade, not a value
taken from a measurement: pigment TiO2's sizes are roughly lognormal (number-based
electron-microscope size distributions of pigment-grade TiO2: R. Theissmann, M. Kluwig and
T. Koch, Beilstein J. Nanotechnol. 5, 1815-1822 (2014), doi:10.3762/bjnano.5.192), but
this tool cites no published sigma_g; give your pigment's.

Since <Csca>/<V> is the average of Csca/V = 3 qsca / (4 r) over the VOLUME distribution
(lognormal with median r_v and the same sigma_g), the tool averages 3 qsca / (4 r),
3 (qext - qsca) / (4 r) and g qsca / r over it, by the trapezoidal rule on --nodes (801)
points equally spaced in ln r from ln r_v - 6 ln sigma_g to ln r_v + (6 + 3 ln sigma_g)
ln sigma_g (6 standard deviations each side of the volume median, and above it 6 past the
median of the r^6-weighted sizes, those that dominate Rayleigh scattering). The spheres'
high-order resonances (k = 0) are narrow and need that many: with the defaults, 401
points differ from 801 by up to 2.9e-4 (near 400 nm) and 801 from 1601 by up to 1.4e-5
(below 2e-8 from 600 nm up); sigma_g 2 spans more sizes and larger spheres, and there 801
differ from 1601 by up to 7e-4 (near 415 nm): give more nodes for wide distributions.
miepython runs compiled by numba where numba is installed (miepython requires it;
MIEPYTHON_USE_JIT=0 in the environment turns that off): about 11 s for the default 2101
wavelengths, about 4 minutes without numba.

This is the independent-scattering approximation: at fv = 0.15 real pigments crowd
(dependent scattering) and scatter somewhat less than this, and real pigments are not
spheres, so the tables are a plausible model paint, not a particular product.

The pigment's index, one of:
  - built in (the default): rutile TiO2, ordinary ray, from the dispersion formula of
    J. R. DeVore, "Refractive indices of rutile and sphalerite", J. Opt. Soc. Am. 41,
    416-419 (1951), doi:10.1364/JOSA.41.000416:
        n^2 = 5.913 + 0.2441 / (lam^2 - 0.0803),   lam in um,
    fitted to measurements from 0.43 to 1.53 um and extrapolated here to 0.40 and 2.5 um
    (n 2.996 at 400 nm, 2.648 at 550 nm, 2.440 at 2500 nm). The extraordinary ray (n
    about 0.3 higher) is left out, as most pigment models do with the ordinary index.
    k = 0 everywhere: rutile is transparent above its absorption edge (band gap about
    3.0 eV, 410 nm), and this tool has no published rutile k near 400-420 nm to cite, so
    the violet absorption that makes rutile pigments slightly yellowish is NOT modelled;
    give measured n and k with --index-table for it;
  - --m N+Kj: one complex index at every wavelength (Python's complex syntax, e.g.
    2.0+0.01j; the imaginary part is the absorption index k, >= 0; miepython's own
    convention, n - ik, is applied inside);
  - --index-table FILE: three columns, wavelength in nm (increasing), n and k (k >= 0),
    read linearly interpolated (`#` comments, spaces, tabs or a comma between columns).

binder_mua (--binder-mua, per mm, default 0.01 = 0.1 per cm) is the clear binder's own
absorption coefficient, one value at every wavelength: a nominal small value of the order
of a clear acrylic or alkyd resin's in the visible. It ignores the resin's C-H overtone
bands near 1.7 and 2.3 um, which absorb more; set it to what your binder measures.

--wavelengths takes lsqt-cl's forms, START:STOP:STEP (both ends included) or a comma
list, in nm. The default, 400:2500:1, makes every lsqt-cl run between 400 and 2500 nm at
whole nanometres (--wavelengths 400:2500:20, or 1 nm steps) read rows of the table itself,
so linear interpolation adds nothing. Values are written to --digits significant digits
(6).
"""
import argparse
import importlib.util
import math
import os
import re
import sys

DEVORE = (5.913, 0.2441, 0.0803)  # n^2 = A + B / (lam_um^2 - C), rutile, ordinary ray
DEFAULTS = dict(radius_um=0.12, sigma_g=1.4, nodes=801, volume_fraction=0.15, binder_index=1.5,
                binder_mua=0.01, wavelengths="400:2500:1", digits=6)
SPAN = 6.0  # the quadrature's span in ln r, in standard deviations (see the docstring)


def size_nodes(radius_um, sigma_g, nodes):
    """Radii (um) and weights (summing to 1) of the quadrature over the VOLUME distribution:
    lognormal with median radius_um and geometric standard deviation sigma_g; one node of
    weight 1 at radius_um where sigma_g is 1."""
    import numpy as np
    if sigma_g == 1:
        return np.array([radius_um]), np.array([1.0])
    s = math.log(sigma_g)
    t = np.linspace(-SPAN, SPAN + 3 * s, nodes)  # (ln r - ln r_v) / s
    w = np.exp(-0.5 * t * t)
    return radius_um * np.exp(s * t), w / w.sum()


def rutile_n(nm):
    """Rutile's ordinary index at nm (vacuum), DeVore (1951); nm a float or numpy array."""
    a, b, c = DEVORE
    um2 = (nm / 1000.0) ** 2
    return (a + b / (um2 - c)) ** 0.5


def parse_wavelengths(text):
    """lsqt-cl's --wavelengths forms: START:STOP:STEP (both ends) or a comma list; nm."""
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if step <= 0 or stop < start:
                raise ValueError
            n = (stop - start) / step
            if abs(n - round(n)) > 1e-9 * max(1.0, n):
                raise ValueError("STEP must divide STOP - START")
            out = [start + i * step for i in range(int(round(n)) + 1)]
        else:
            out = [float(v) for v in text.split(",")]
    except ValueError as e:
        sys.exit("mie_pigment.py: --wavelengths %r: expected START:STOP:STEP or a comma list of nm%s"
                 % (text, " (%s)" % e if str(e) and "could not" not in str(e) else ""))
    if not out or any(not math.isfinite(v) or v <= 0 for v in out) or any(b <= a for a, b in zip(out, out[1:])):
        sys.exit("mie_pigment.py: --wavelengths %r: wavelengths must be positive and increasing" % text)
    return out


def read_index_table(path):
    """Rows (nm, n, k) of an index table."""
    rows = []
    try:
        lines = open(path).read().splitlines()
    except OSError as e:
        sys.exit("mie_pigment.py: cannot read %s: %s" % (path, e.strerror))
    for i, line in enumerate(lines, 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        f = re.split(r"[\s,]+", line)
        try:
            if len(f) != 3:
                raise ValueError
            nm, n, k = (float(v) for v in f)
            if not (math.isfinite(nm) and math.isfinite(n) and math.isfinite(k)) or nm <= 0 or n <= 0 or k < 0:
                raise ValueError
        except ValueError:
            sys.exit("mie_pigment.py: %s:%d: expected three numbers, wavelength in nm, n > 0 and k >= 0: %r"
                     % (path, i, line))
        if rows and nm <= rows[-1][0]:
            sys.exit("mie_pigment.py: %s:%d: wavelengths must increase" % (path, i))
        rows.append((nm, n, k))
    if len(rows) < 2:
        sys.exit("mie_pigment.py: %s: needs at least two rows (wavelength nm, n, k)" % path)
    return rows


def pigment_index(a, nms):
    """(description, list of complex n + ik at nms)."""
    if a.index_table:
        rows = read_index_table(a.index_table)
        lo, hi = rows[0][0], rows[-1][0]
        if nms[0] < lo or nms[-1] > hi:
            sys.exit("mie_pigment.py: %s covers %g to %g nm, not the wavelengths %g to %g nm"
                     % (a.index_table, lo, hi, nms[0], nms[-1]))
        out, j = [], 0
        for nm in nms:
            while rows[j + 1][0] < nm:
                j += 1
            (x0, n0, k0), (x1, n1, k1) = rows[j], rows[j + 1]
            t = (nm - x0) / (x1 - x0)
            out.append(complex(n0 + t * (n1 - n0), k0 + t * (k1 - k0)))
        return "n and k from %s (linear interpolation)" % os.path.basename(a.index_table), out
    if a.m is not None:
        m = complex(a.m.real, abs(a.m.imag))
        if m.real <= 0:
            sys.exit("mie_pigment.py: --m: the real part must be positive")
        return "constant m = %s" % fmt_complex(m), [m] * len(nms)
    return ("rutile TiO2, ordinary ray, DeVore (1951) n^2 = %g + %g/(lam_um^2 - %g), k = 0" % DEVORE,
            [complex(rutile_n(nm), 0.0) for nm in nms])


def fmt_complex(m):
    return "%g%+gj" % (m.real, m.imag)


def command_line(a):
    """The command that makes these tables again (every parameter spelled out)."""
    words = ["python3", "tools/mie_pigment.py"]
    if a.index_table:
        words += ["--index-table", a.index_table]
    elif a.m is not None:
        words += ["--m", fmt_complex(complex(a.m.real, abs(a.m.imag)))]
    words += ["--radius-um", "%g" % a.radius_um, "--sigma-g", "%g" % a.sigma_g]
    if a.sigma_g != 1:
        words += ["--nodes", str(a.nodes)]
    words += ["--volume-fraction", "%g" % a.volume_fraction,
              "--binder-index", "%g" % a.binder_index, "--binder-mua", "%g" % a.binder_mua,
              "--wavelengths", a.wavelengths]
    if a.digits != DEFAULTS["digits"]:
        words += ["--digits", str(a.digits)]
    return " ".join(words + [a.prefix])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n\n".join(__doc__.split("\n\n")[3:]))
    src = ap.add_mutually_exclusive_group()
    src.add_argument("--m", type=complex, help="a constant complex index n+kj of the pigment (default: rutile TiO2)")
    src.add_argument("--index-table", metavar="FILE", help="the pigment's n and k: rows of wavelength nm, n, k")
    ap.add_argument("--radius-um", type=float, default=DEFAULTS["radius_um"],
                    help="the spheres' volume-median radius in um (0.12)")
    ap.add_argument("--sigma-g", type=float, default=DEFAULTS["sigma_g"],
                    help="the sizes' geometric standard deviation, 1 to 3; 1: one radius (1.4)")
    ap.add_argument("--nodes", type=int, default=DEFAULTS["nodes"],
                    help="quadrature points over the sizes, 2 to 100000 (801)")
    ap.add_argument("--volume-fraction", type=float, default=DEFAULTS["volume_fraction"],
                    help="the pigment's volume fraction, in (0, 1) (0.15)")
    ap.add_argument("--binder-index", type=float, default=DEFAULTS["binder_index"],
                    help="the binder's (real) refractive index (1.5)")
    ap.add_argument("--binder-mua", type=float, default=DEFAULTS["binder_mua"],
                    help="the binder's own absorption coefficient, per mm (0.01)")
    ap.add_argument("--wavelengths", default=DEFAULTS["wavelengths"],
                    help="nm: START:STOP:STEP or a comma list (400:2500:1)")
    ap.add_argument("--digits", type=int, default=DEFAULTS["digits"], help="significant digits written (6)")
    ap.add_argument("prefix", help="writes PREFIX_mus.txt, PREFIX_mua.txt, PREFIX_g.txt")
    a = ap.parse_args()
    for name, ok in (("--radius-um", a.radius_um > 0), ("--sigma-g", 1 <= a.sigma_g <= 3),
                     ("--nodes", 2 <= a.nodes <= 100000), ("--volume-fraction", 0 < a.volume_fraction < 1),
                     ("--binder-index", a.binder_index >= 1), ("--binder-mua", a.binder_mua >= 0),
                     ("--digits", 3 <= a.digits <= 17)):
        if not ok:
            sys.exit("mie_pigment.py: %s out of range (radius > 0, 1 <= sigma-g <= 3, 2 <= nodes <= 100000, "
                     "0 < volume fraction < 1, binder index >= 1, binder mua >= 0, 3 <= digits <= 17)" % name)
    # miepython's compiled code (numba, which miepython requires) where it is there, unless
    # the environment says otherwise: some 70 times faster than its pure Python.
    if "MIEPYTHON_USE_JIT" not in os.environ and importlib.util.find_spec("numba") is not None:
        os.environ["MIEPYTHON_USE_JIT"] = "1"
    try:
        import miepython
        import numpy as np
    except ImportError:
        sys.exit("mie_pigment.py: needs miepython and numpy: python3 -m venv /tmp/mie && /tmp/mie/bin/pip install "
                 "miepython, then run it with /tmp/mie/bin/python (not pip --user: its numpy breaks Debian's xarray)")

    nms = parse_wavelengths(a.wavelengths)
    what, ms = pigment_index(a, nms)
    lam = np.array(nms)
    # miepython's convention is m = n - ik; the relative index and the size parameter are
    # those in the binder.
    # Rows: the quadrature's radii r (weights w, over the volume distribution); columns:
    # the wavelengths. Each node's terms are the one-radius formulas, so that one node of
    # weight 1 (--sigma-g 1) gives them exactly.
    r, w = size_nodes(a.radius_um, a.sigma_g, a.nodes)
    m_rel = np.array([complex(m.real, -m.imag) for m in ms]) / a.binder_index
    x = 2 * math.pi * r[:, None] * 1000.0 * a.binder_index / lam[None, :]
    qext, qsca, _, g = miepython.efficiencies_mx(np.broadcast_to(m_rel, x.shape).ravel(), x.ravel())
    qext, qsca, g = (np.asarray(v, dtype=float).reshape(x.shape) for v in (qext, qsca, g))
    r_mm = r[:, None] * 1e-3
    fv = a.volume_fraction
    w = w[:, None]
    mus = (w * (fv * 3 * qsca / (4 * r_mm))).sum(axis=0)
    mua = (w * (fv * 3 * np.maximum(qext - qsca, 0.0) / (4 * r_mm))).sum(axis=0) + (1 - fv) * a.binder_mua
    if len(r) == 1:
        g = g[0]
    else:  # <g Csca> / <Csca>, by number: g qsca / r and qsca / r over the volume distribution
        csca = (w * (qsca / r_mm)).sum(axis=0)
        g = np.where(csca > 0, (w * (g * qsca / r_mm)).sum(axis=0) / np.where(csca > 0, csca, 1.0), 0.0)

    if a.sigma_g == 1:
        sizes = "spheres of radius %g um" % a.radius_um
        cols = ("mus (1/mm) = fv * 3 qsca / (4 r)",
                "mua (1/mm) = fv * 3 (qext - qsca) / (4 r) + (1 - fv) * binder_mua",
                "g (asymmetry parameter, for HenyeyGreensteinPhase)")
    else:
        sizes = ("spheres of lognormal radii, volume-median %g um (number-median %.4g um), geometric standard "
                 "deviation %g (%d nodes in ln r)" % (a.radius_um, a.radius_um * math.exp(-3 * math.log(a.sigma_g) ** 2),
                                                      a.sigma_g, a.nodes))
        cols = ("mus (1/mm) = fv <Csca> / <V>, averages by number",
                "mua (1/mm) = fv <Cext - Csca> / <V> + (1 - fv) * binder_mua, averages by number",
                "g = <g Csca> / <Csca> (asymmetry parameter, for HenyeyGreensteinPhase)")
    head = ["Mie pigment film (miepython %s, tools/mie_pigment.py): %s" % (miepython.__version__, what),
            "%s, volume fraction %g, in a binder of index %g absorbing %g per mm;"
            % (sizes, fv, a.binder_index, a.binder_mua),
            "size parameter x = 2 pi r n_binder / lam, relative index m / n_binder; independent scattering",
            "made by: %s" % command_line(a)]
    tables = (("mus", mus, cols[0]), ("mua", mua, cols[1]), ("g", g, cols[2]))
    for name, v, col in tables:
        path = "%s_%s.txt" % (a.prefix, name)
        with open(path, "w") as f:
            for line in head:
                f.write("# %s\n" % line)
            f.write("# columns: wavelength (nm, vacuum)  %s\n" % col)
            for nm, val in zip(nms, v):
                f.write("%.10g %.*g\n" % (nm, a.digits, val))
    print("mie_pigment.py: wrote %s_{mus,mua,g}.txt, %d wavelengths %g to %g nm" % (a.prefix, len(nms), nms[0], nms[-1]))


if __name__ == "__main__":
    main()
