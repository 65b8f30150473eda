#!/usr/bin/env python3
"""Writes tests/data/conductor_eta_heitz.txt: directional albedos R(theta_o) of GGX
conductors with eta > k, multiple scattering on, from the independent numpy random walk of
tools/validate/heitz_walk.py (Heitz et al. 2016, exact complex-index Fresnel via numpy's
complex sqrt), for test_conductor_eta. Needs numpy (not at test time):

    python3 tests/data/gen_conductor_eta_heitz.py > tests/data/conductor_eta_heitz.txt

The walk sees only the relative index (metal over the medium above); the file keeps the
assembly's absolute indices (above, eta, mua) so the test runs the LSQT text itself."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "validate"))
import heitz_walk as hw  # noqa: E402

N = 2000000
CASES = [  # above, metal eta, metal mua, alpha
    (1.0, 4.0, 2.0, 1.0),
    (1.0, 3.0, 0.1, 1.0),
    (2.0, 1.5, 0.1, 0.5),
    (1.5, 4.0, 2.0, 0.3),
]
ANGLES = (0.0, 60.0, 80.0)

print("# above eta mua alpha theta_o_deg R R_err walks (heitz_walk.py, seed 9000 + 10 case + slice)")
for c, (above, eta, mua, alpha) in enumerate(CASES):
    for s, th in enumerate(ANGLES):
        a = hw.albedo("conductor", alpha, th, N, seed=9000 + 10 * c + s, metal=(eta / above, mua / above))
        assert a["cut"] == 0
        print(f"{above:g} {eta:g} {mua:g} {alpha:g} {th:g} {a['R']:.9f} {a['R_err']:.3e} {N}", flush=True)
