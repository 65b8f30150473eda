#!/usr/bin/env python3
"""Long validation runs of lsqt-cl against closed forms and adding-doubling references.

    python3 tools/validate/validate.py [PATHS] [-- lsqt-cl options]

Prints, per case and slice, the estimate, its standard error, the reference and the
z-score; exits 1 if any |z| > 4. References: closed forms, and iadpython numbers kept
here (regenerate with tools/validate/iad_slab.py)."""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BIN = os.path.join(ROOT, "build", "lsqt-cl")

CASES = [
    # name, LSQT text, outgoing angles (deg), {quantity: reference or list per slice}
    ("Lambertian fR=0.6", "Medium\nLayer z=0 LambertianBsdf fR=0.6\nMedium\n", [0, 45, 89.9], {"R": 0.6, "T": 0.0}),
    ("adding 0.3/0.5 over 0.6", "Medium\nLayer z=1 LambertianBsdf fR=0.3 fT=0.5\nMedium\n"
     "Layer z=0 LambertianBsdf fR=0.6\nMedium\n", [0, 60, 85], {"R": 0.3 + 0.25 * 0.6 / (1 - 0.18)}),
    ("iad slab mus=1 g=0 d=1", "Medium\nLayer z=1 NullBsdf\nMedium mus=1 HenyeyGreensteinPhase g=0\n"
     "Layer z=0 NullBsdf\nMedium\n", [0], {"R": 0.3413287, "T": 0.6586713}),
    ("iad slab mua=0.5 mus=1 g=0.5", "Medium\nLayer z=1 NullBsdf\nMedium mua=0.5 mus=1 HenyeyGreensteinPhase g=0.5\n"
     "Layer z=0 NullBsdf\nMedium\n", [0], {"R": 0.0771444, "T": 0.4455289}),
    ("lossless tau=1e4 (R+T=1)", "Medium\nLayer z=1 NullBsdf\nMedium mus=1e4 HenyeyGreensteinPhase g=0\n"
     "Layer z=0 NullBsdf\nMedium\n", [0, 89.9], {"R+T": 1.0}),
]


def run(text, angles, paths, extra):
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, "case.lsqt")
        with open(src, "w") as f:
            f.write(text)
        cmd = [BIN, "-q", "-R", "-p", str(paths), "-wi", "16", "--wo-angles=" + ",".join(map(str, angles)),
               "--json", os.path.join(d, "s.json"), *extra, src]
        subprocess.run(cmd, check=True)
        with open(os.path.join(d, "s.json")) as f:
            return json.load(f)


def main():
    args = sys.argv[1:]
    extra = args[args.index("--") + 1:] if "--" in args else []
    args = args[:args.index("--")] if "--" in args else args
    paths = args[0] if args else "1e5"
    worst = 0.0
    for name, text, angles, refs in CASES:
        j = run(text, angles, paths, extra)
        for s in j["slices"]:
            for q, ref in refs.items():
                if q == "R+T":
                    est, err = s["R"] + s["T"], (s["R_err"] ** 2 + s["T_err"] ** 2) ** 0.5
                else:
                    est, err = s[q], s[q + "_err"]
                z = (est - ref) / err if err > 0 else (0.0 if abs(est - ref) < 1e-7 else float("inf"))
                worst = max(worst, abs(z))
                print(f"{name:30s} theta_o={s['theta_o']:.4f} {q:3s} {est:.6f} +- {err:.2g}  ref {ref:.6f}  "
                      f"z={z:+.2f}  ({j['paths_per_second']:.3g} paths/s, {j['seconds']:.2f} s)")
    print(f"largest |z| = {worst:.2f}")
    return 1 if worst > 4 else 0


if __name__ == "__main__":
    sys.exit(main())
