#!/usr/bin/env python3
"""Reference values for index-matched slabs from iadpython (adding-doubling), at normal
incidence (iadpython 0.5.3 answers oblique collimated incidence with zeros).

    pip install iadpython scipy && python3 tools/validate/iad_slab.py

Prints UR1/UT1 (total reflectance/transmittance for collimated normal incidence) for the
slabs whose values tests/test_simulate.c keeps as fixtures, at two quadrature orders so
a reader can see that they have converged."""
import iadpython as iad

SLABS = [  # (description, mua, mus, g, thickness)
    ("mus=1 mua=0 g=0 d=1", 0.0, 1.0, 0.0, 1.0),
    ("mus=1 mua=0.5 g=0.5 d=1", 0.5, 1.0, 0.5, 1.0),
]

for name, mua, mus, g, d in SLABS:
    mut = mua + mus
    for quad in (8, 16):
        s = iad.Sample(a=mus / mut, b=mut * d, g=g, n=1.0, n_above=1.0, n_below=1.0, quad_pts=quad)
        ur1, ut1, _, _ = s.rt()
        print(f"{name:28s} quad_pts={quad:2d}  UR1={ur1:.7f}  UT1={ut1:.7f}")
