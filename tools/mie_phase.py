#!/usr/bin/env python3
"""mie_phase.py: a phase table for TabulatedPhase (docs/formats.md, "Phase tables") from
Mie theory, with miepython (https://github.com/scottprahl/miepython), installed in a virtual
environment so that it leaves Debian's numpy (which xarray needs) alone:
    python3 -m venv /tmp/mie && /tmp/mie/bin/pip install miepython
    /tmp/mie/bin/python tools/mie_phase.py OUT

    tools/mie_phase.py [--m 1.33] [--radius-um 1.0] [--wavelength-nm 550] [--rows 2001] OUT

Writes OUT: rows of cos(theta) and the unpolarised phase function p(cos theta), theta from
0 to pi in equal steps (cos theta descending from 1 to -1, as Mie codes write it), with a
header of the parameters. lsqt-cl normalises the table itself. The repository's
examples/tables/mie_phase.txt is this tool's output with its defaults (a water droplet of
radius 1 um in air at 550 nm, size parameter 11.4):

    python3 tools/mie_phase.py examples/tables/mie_phase.txt
"""
import argparse
import math
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--m", type=complex, default=complex(1.33, 0), help="the sphere's complex index (1.33)")
    ap.add_argument("--radius-um", type=float, default=1.0, help="the sphere's radius in um (1.0)")
    ap.add_argument("--wavelength-nm", type=float, default=550.0, help="the wavelength in vacuum, nm (550)")
    ap.add_argument("--rows", type=int, default=2001, help="rows, theta from 0 to pi in equal steps (2001)")
    ap.add_argument("out")
    a = ap.parse_args()
    try:
        import miepython
        import numpy as np
    except ImportError:
        sys.exit("mie_phase.py: needs miepython and numpy: python3 -m venv /tmp/mie && /tmp/mie/bin/pip install "
                 "miepython, then run it with /tmp/mie/bin/python (not pip --user: its numpy breaks Debian's xarray)")
    if a.rows < 2:
        sys.exit("mie_phase.py: --rows must be at least 2")
    m = "%g%+gj" % (a.m.real, a.m.imag)
    x = 2 * math.pi * a.radius_um * 1000 / a.wavelength_nm
    theta = np.linspace(0, math.pi, a.rows)
    mu = np.cos(theta)
    mu[0], mu[-1] = 1.0, -1.0
    p = miepython.i_unpolarized(a.m, x, mu, norm="one")
    with open(a.out, "w") as f:
        f.write("# Mie phase function (miepython %s, unpolarised, norm 'one'): m = %s, radius %g um, "
                "wavelength %g nm, size parameter %.6g\n" % (miepython.__version__, m, a.radius_um,
                                                             a.wavelength_nm, x))
        f.write("# made by: python3 tools/mie_phase.py --m %s --radius-um %g --wavelength-nm %g --rows %d OUT\n"
                % (m, a.radius_um, a.wavelength_nm, a.rows))
        f.write("# cos(theta)  p (1/sr)\n")
        for c, v in zip(mu, p):
            f.write("%.10g %.9g\n" % (c, v))


if __name__ == "__main__":
    main()
