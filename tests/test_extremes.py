#!/usr/bin/env python3
"""Extremes (every estimate finite and stable at the extremes): every model at each end of its parameters, in
float and in double, through the program itself (RAW, LSS, --json and the printed
summary). Standard library only.

    test_extremes.py [--every N] LSQT_CL [FILTER]

(--every N: every N-th assembly only, no limit pairs; the sanitizer build, where each
process costs seconds.)

Per assembly and precision, at theta_o 0, 60 and 89.9 degrees, on an even spread of 16
incident directions (the whole sphere where the stack transmits), 1024 paths:
- the run succeeds; nothing NaN, Inf or negative in the RAW, the LSS (lsqt-cl info --json
  --bsdf), the JSON summary or the printed summary;
- no path cut by the safety cap, no overflowed tally, no dropped non-finite contribution
  (the LSS flags);
- energy: R + T <= 1 + 3 sigma (+1e-6 for rounding), and for Oren-Nayar at most its own
  formula's directional albedo (which exceeds fR at grazing incidence);
- limits, as pairs that must agree within 4 sigma of their difference (16384 paths): a layer of
  thickness 1e-6 at z = 1e6 and the same optical thickness at z = 0; a medium 1e6 thick
  with mus = 1e-6 and one 1 thick with mus = 1; Rayleigh rho = 1 and isotropic HG; HG
  g = 0 and SGGX spheres (Apara = Aperp); a microsurface Lambertian at alpha 1e-4 and a
  Lambertian layer; a medium with mus = 1e-9 and a clear one.
The RNG seed is fixed (the default), so the run is reproducible."""
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools", "validate"))
from refs_closed import oren_nayar_albedo  # noqa: E402  (the formula's albedo, quadrature)
from common import test_args  # noqa: E402

ANGLES = [0, 60, 89.9]
PATHS = 1024
PATHS_LIMIT = 16384  # the limit pairs: about 0.5 % on R and T


def stack(*lines):
    return "\n".join(lines) + "\n"


def slab(medium, top="NullBsdf", bottom="NullBsdf", z0=0.0, d=1.0):
    return stack("Medium", f"Layer z={z0 + d!r} {top}", f"Medium {medium}", f"Layer z={z0!r} {bottom}", "Medium")


def assemblies():
    """(name, LSQT text). Each model at each end of each parameter."""
    a = []
    for fr, ft in ((0, 0), (1, 0), (0, 1), (0.5, 0.5)):
        a.append((f"Lambertian fR={fr} fT={ft}", stack("Medium", f"Layer z=0 LambertianBsdf fR={fr} fT={ft}", "Medium")))
    for al in (1e-4, 10):
        for fr, ft in ((0, 0), (1, 0), (0, 1)):
            a.append((f"microsurface Lambertian alpha={al} fR={fr} fT={ft}",
                      stack("Medium", f"Layer z=0 MicrosurfaceLambertianBrdf alpha={al} fR={fr} fT={ft}", "Medium")))
        a.append((f"microsurface Lambertian alpha={al} single",
                  stack("Medium", f"Layer z=0 MicrosurfaceLambertianBrdf alpha={al} use_multiple_scattering=false",
                        "Medium")))
    for al in (1e-4, 1e-2, 1, 10):
        for up, down in ((1, 4), (4, 1), (1, 1.0001)):  # eta ratios 4, 1/4 (total internal reflection), ~1
            for ms in ("true", "false"):
                a.append((f"microsurface dielectric alpha={al} eta {up}|{down} ms={ms}",
                          stack(f"Medium eta={up}", f"Layer z=0 MicrosurfaceDielectricBsdf alpha={al} "
                                f"use_multiple_scattering={ms}", f"Medium eta={down}")))
        if al not in (1e-4, 10):
            continue
        a.append((f"microsurface dielectric alpha={al} kR=0 kT=1", stack(
            "Medium", f"Layer z=0 MicrosurfaceDielectricBsdf alpha={al} kR=0 kT=1", "Medium eta=1.5")))
        a.append((f"microsurface dielectric alpha={al} kR=1 kT=0", stack(
            "Medium", f"Layer z=0 MicrosurfaceDielectricBsdf alpha={al} kR=1 kT=0", "Medium eta=1.5")))
    for al in (1e-4, 1e-2, 1, 10):
        for eta, k in ((0.01, 10), (4, 0), (0.2, 3.9)):
            for ms in ("true", "false"):
                a.append((f"conductor alpha={al} n={eta}+{k}i ms={ms}", stack(
                    "Medium", f"Layer z=0 MicrosurfaceConductiveBrdf alpha={al} use_multiple_scattering={ms}",
                    f"Medium eta={eta} mua={k}")))
    for sig in (0, 0.4, 0.8):
        for fr in (0, 1):
            a.append((f"Oren-Nayar sigma={sig} fR={fr}", stack("Medium", f"Layer z=0 OrenNayarDiffuseBrdf fR={fr} sigma={sig}",
                                                               "Medium")))
    # media: phase functions at their ends, optical thickness from 1e-4 to 1e4
    for g in (-0.999, 0.999):
        a.append((f"HG g={g} tau=10 albedo 0.99", slab(f"mus=9.9 mua=0.1 HenyeyGreensteinPhase g={g}")))
    a.append(("HG2 g0=0.999 g1=-0.999 b=0.5 tau=5", slab("mus=4.5 mua=0.5 HenyeyGreenstein2Phase g0=0.999 g1=-0.999 b=0.5")))
    for rho in (-1, 1):
        a.append((f"Rayleigh rho={rho} tau=2", slab(f"mus=2 RayleighPhase rho={rho}")))
    for ap, ae in ((1, 1e-3), (1e-3, 1), (1, 1e3), (1e3, 1)):
        for ty in ("Specular", "Diffuse"):
            a.append((f"SGGX {ty} Apara={ap} Aperp={ae} tau=3", slab(f"mus=3 mua=0.3 SggxPhase Apara={ap} Aperp={ae} type={ty}")))
    for tau, alb in ((1e-4, 0.5), (1e-4, 1.0), (1e4, 0.99), (1e4, 0.5), (1e4, 0.0)):
        a.append((f"HG g=0.8 tau={tau} albedo {alb}", slab(f"mus={tau * alb!r} mua={tau * (1 - alb)!r} HenyeyGreensteinPhase g=0.8")))
    a.append(("tau=1e4 albedo 0.99 between rough dielectrics eta 1.5",
              slab("eta=1.5 mus=9900 mua=100 HenyeyGreensteinPhase g=0.9", top="MicrosurfaceDielectricBsdf alpha=0.1",
                   bottom="MicrosurfaceDielectricBsdf alpha=0.1")))
    # thickness from 1e-6 to 1e6, far from z = 0
    a.append(("thin slab d=1e-6 at z=1e6 (tau 0.5)", slab("mus=4e5 mua=1e5 HenyeyGreensteinPhase g=0.3", z0=1e6, d=1e-6)))
    a.append(("thin slab d=1e-6 at z=0 (tau 0.5)", slab("mus=4e5 mua=1e5 HenyeyGreensteinPhase g=0.3", d=1e-6)))
    a.append(("thick slab d=1e6 mus=1e-6 (tau 1)", slab("mus=1e-6 HenyeyGreensteinPhase g=0.5", z0=-5e5, d=1e6)))
    a.append(("slab d=1 mus=1 (tau 1)", slab("mus=1 HenyeyGreensteinPhase g=0.5")))
    a.append(("thin dielectric film d=1e-6 at z=-1e6", slab("eta=1.33 mua=1e4", top="MicrosurfaceDielectricBsdf alpha=0.2",
                                                          bottom="MicrosurfaceDielectricBsdf alpha=0.2", z0=-1e6, d=1e-6)))
    a.append(("Rayleigh rho=1 tau=1", slab("mus=1 RayleighPhase rho=1")))
    a.append(("HG g=0 tau=1", slab("mus=1 HenyeyGreensteinPhase g=0")))
    a.append(("SGGX Specular Apara=Aperp=0.5 tau=1", slab("mus=1 SggxPhase Apara=0.5 Aperp=0.5 type=Specular")))
    a.append(("microsurface Lambertian alpha=1e-4 fR=0.7", stack("Medium", "Layer z=0 MicrosurfaceLambertianBrdf alpha=1e-4 fR=0.7",
                                                                  "Medium")))
    a.append(("Lambertian fR=0.7", stack("Medium", "Layer z=0 LambertianBsdf fR=0.7", "Medium")))
    a.append(("mus=1e-9 over Lambertian 0.7", slab("mus=1e-9 HenyeyGreensteinPhase g=0.9", bottom="LambertianBsdf fR=0.7")))
    a.append(("clear over Lambertian 0.7", slab("", bottom="LambertianBsdf fR=0.7")))
    return a


LIMITS = [  # pairs of assembly names that must agree (R and T per slice)
    ("thin slab d=1e-6 at z=1e6 (tau 0.5)", "thin slab d=1e-6 at z=0 (tau 0.5)"),
    ("thick slab d=1e6 mus=1e-6 (tau 1)", "slab d=1 mus=1 (tau 1)"),
    ("Rayleigh rho=1 tau=1", "HG g=0 tau=1"),
    ("SGGX Specular Apara=Aperp=0.5 tau=1", "HG g=0 tau=1"),
    ("microsurface Lambertian alpha=1e-4 fR=0.7", "Lambertian fR=0.7"),
    ("mus=1e-9 over Lambertian 0.7", "clear over Lambertian 0.7"),
]

failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL: " + msg, flush=True)


def numbers(x):
    if isinstance(x, bool):
        return
    if isinstance(x, (int, float)):
        yield x
    elif isinstance(x, dict):
        for v in x.values():
            yield from numbers(v)
    elif isinstance(x, list):
        for v in x:
            yield from numbers(v)


def run(binary, name, text, double, d, paths):
    src = os.path.join(d, "a.lsqt")
    with open(src, "w") as f:
        f.write(text)
    tag = f"{name} [{'double' if double else 'float'}]"
    cmd = [binary, "-R", "-p", str(paths), "--wo-angles=" + ",".join(map(str, ANGLES)), "--wi-spread", "-wi", "16",
           "--json", os.path.join(d, "s.json"), "--lss", os.path.join(d, "s.lss"), "-o", os.path.join(d, "s.raw"), src]
    if double:
        cmd.insert(1, "--double")
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"{tag}: exit {p.returncode}: {p.stderr.strip()[-300:]}")
        return None
    if re.search(r"\b(nan|inf)\b", p.stdout + p.stderr, re.I):
        fail(f"{tag}: the printed summary shows nan/inf:\n{p.stdout}")
    s = json.load(open(os.path.join(d, "s.json")))
    q = subprocess.run([binary, "info", os.path.join(d, "s.lss"), "--json", os.path.join(d, "i.json"), "--bsdf"],
                       capture_output=True, text=True)
    if q.returncode != 0:
        fail(f"{tag}: lsqt-cl info: exit {q.returncode}: {q.stderr.strip()[-300:]}")
        return None
    info = json.load(open(os.path.join(d, "i.json")))
    for what, obj in (("JSON summary", s), ("LSS (info --json --bsdf)", info)):
        bad = [v for v in numbers(obj) if not math.isfinite(v)]
        if bad:
            fail(f"{tag}: {what} holds {len(bad)} non-finite numbers")
    for sl in info["slices"]:
        neg = [e for e in sl["bsdf"] if e[3] < 0 or e[4] < 0]
        if neg:
            fail(f"{tag}: LSS: {len(neg)} negative BSDF values or errors at theta_o {sl['theta_o']:.4f}: {neg[:2]}")
        if sl["n_nonfinite"] or sl["cut_paths"]:
            fail(f"{tag}: LSS: {sl['n_nonfinite']} non-finite estimates, {sl['cut_paths']} paths cut")
    if info["flags"]:
        fail(f"{tag}: LSS flags {info['flag_names']}")
    raw_bad = 0
    with open(os.path.join(d, "s.raw")) as f:
        lines = f.read().split("\n")[3:]
    for l in lines:
        if l.strip():
            v = [float(t) for t in l.split()[1:]]
            raw_bad += any(not math.isfinite(t) for t in v) or v[3] < 0
    if raw_bad:
        fail(f"{tag}: RAW: {raw_bad} lines non-finite or negative")
    if not lines or not any(l.strip() for l in lines):
        fail(f"{tag}: RAW has no estimates")
    for sl in s["slices"]:
        for k in ("R", "T", "delta_T"):
            if sl[k] < 0:
                fail(f"{tag}: {k} = {sl[k]} < 0 at theta_o {sl['theta_o']:.4f}")
        if sl["cut_paths"]:
            fail(f"{tag}: {sl['cut_paths']} paths cut by the safety cap")
        tot, err = sl["R"] + sl["T"], math.hypot(sl["R_err"], sl["T_err"])
        cap = 1.0
        m = re.match(r"Oren-Nayar sigma=([0-9.]+) fR=([0-9.]+)", name)
        if m:  # the formula's own albedo (> fR at grazing incidence): the stated exception
            cap = max(1.0, oren_nayar_albedo(float(m.group(2)), float(m.group(1)), sl["theta_o"]))
        if tot > cap + 3 * err + 1e-6:
            fail(f"{tag}: R + T = {tot:.6f} +- {err:.2g} above {cap:.6f} at theta_o {sl['theta_o']:.4f}")
    return s


def main():
    every, binary, flt = test_args(sys.argv[1:], "test_extremes.py [--every N] LSQT_CL [FILTER]")
    pat = re.compile(flt) if flt else None
    limit_names = {n for pair in LIMITS for n in pair}
    todo = [(n, t) for i, (n, t) in enumerate(assemblies())
            if (not pat or pat.search(n)) and (i % every == 0 or (every == 1 and n in limit_names))]
    print(f"{len(todo)} assemblies x float, double = {2 * len(todo)} runs, {PATHS} paths, theta_o {ANGLES}")
    t0 = time.time()
    results = {}
    in_limits = {n for pair in LIMITS for n in pair}
    with tempfile.TemporaryDirectory() as d:
        for name, text in todo:
            for double in (False, True):
                t = time.time()
                s = run(binary, name, text, double, d, PATHS_LIMIT if name in in_limits else PATHS)
                if s:
                    results[(name, double)] = s
                    print(f"{name:58s} {'double' if double else 'float '} " +
                          " ".join(f"{x['R']:.4f}+{x['T']:.4f}" for x in s["slices"]) + f"  {time.time() - t:.1f} s",
                          flush=True)
    for a, b in LIMITS:
        for double in (False, True):
            if (a, double) not in results or (b, double) not in results:
                continue
            for sa, sb in zip(results[(a, double)]["slices"], results[(b, double)]["slices"]):
                for k in ("R", "T"):
                    err = math.hypot(sa[k + "_err"], sb[k + "_err"])
                    z = (sa[k] - sb[k]) / err if err > 0 else (0 if abs(sa[k] - sb[k]) < 1e-6 else math.inf)
                    ok = abs(z) <= 4
                    print(f"limit {a} = {b} [{'double' if double else 'float'}] theta_o "
                          f"{math.degrees(sa['theta_o']):.1f} {k}: {sa[k]:.5f} vs {sb[k]:.5f} z={z:+.2f}")
                    if not ok:
                        fail(f"limit {a} = {b}: {k} {sa[k]:.6f} vs {sb[k]:.6f} (z = {z:+.2f})")
    n = 2 * len(todo)
    print(f"{time.time() - t0:.0f} s; {len(failures)} failures")
    print(f"{n - len({f.split(':')[0] for f in failures})} passed, {len({f.split(':')[0] for f in failures})} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
