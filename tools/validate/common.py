"""Shared by the validation suite (tools/validate/validate.py) and the fixture test
(tests/test_fixtures.py): a case, how lsqt-cl runs it, and how a row is judged.
Standard library only, so that ctest needs nothing from PyPI.

A case is a plain dict (JSON as kept in tests/data/validation_fixtures.json):
    group      which reference ("closed form", "iadpython", "mitsuba", "heitz2016", ...)
    name       what it is, for the table
    lsqt       the LSQT text
    args       lsqt-cl flags besides -p (directions: --wo-angles, -wi/--wi-spread, --double)
    wi         optional list of [x, y, z]: written to a --wi-file (BSDF values at exact pairs)
    paths      paths per slice for the validation run
    fixture_paths  paths per slice for ctest (fewer; the tolerance is in standard errors)
    checks     list of {"slice": k, "q": Q, "ref": value, "ref_err": one sigma of the
               reference (its own noise or convergence spread), "limitation": null or why
               a miss is known and expected}
Q is "R", "T", "R+T", "delta_T", or "f:i" (the BSDF value at the slice's i-th incident
direction, 1/sr, not cosine-weighted, from lsqt-cl info --bsdf)."""
import json
import math
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
Z_MAX = 4.0


def test_args(argv, usage):
    """A ctest script's arguments: [--every N] LSQT_CL [MORE]; returns (N, LSQT_CL, MORE or None)."""
    args, every = list(argv), 1
    if args[:1] == ["--every"]:
        every, args = int(args[1]), args[2:]
    if not args:
        raise SystemExit("usage: " + usage)
    return every, args[0], args[1] if len(args) > 1 else None


def default_bin():
    return os.environ.get("LSQT_CL", os.path.join(ROOT, "build", "lsqt-cl"))


def run_case(case, paths, binary=None, extra=(), bsdf=None):
    """Runs lsqt-cl on a case; returns (summary JSON, info JSON with the BSDF values, or None
    unless bsdf, by default whether a check needs them)."""
    binary = binary or default_bin()
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, "case.lsqt")
        with open(src, "w") as f:
            f.write(case["lsqt"])
        cmd = [binary, "-q", "-R", "-p", str(int(float(paths))), "--lss", os.path.join(d, "s.lss"),
               "-o", os.path.join(d, "s.raw"), "--json", os.path.join(d, "s.json"), *case.get("args", []), *extra]
        if case.get("wi"):
            wi = os.path.join(d, "wi.txt")
            with open(wi, "w") as f:
                for x, y, z in case["wi"]:
                    f.write(f"{x!r} {y!r} {z!r}\n")
            cmd += ["--wi-file", wi]
        subprocess.run(cmd + [src], check=True)
        with open(os.path.join(d, "s.json")) as f:
            summary = json.load(f)
        info = None
        if bsdf if bsdf is not None else any(c["q"].startswith("f:") for c in case["checks"]):
            subprocess.run([binary, "info", os.path.join(d, "s.lss"), "--json", os.path.join(d, "i.json"), "--bsdf"],
                           check=True, stdout=subprocess.DEVNULL)
            with open(os.path.join(d, "i.json")) as f:
                info = json.load(f)
        return summary, info


def estimate(check, summary, info):
    """lsqt-cl's value and one standard error for a check."""
    s = summary["slices"][check["slice"]]
    q = check["q"]
    if q == "R+T":
        return s["R"] + s["T"], math.hypot(s["R_err"], s["T_err"])
    if q.startswith("f:"):
        e = info["slices"][check["slice"]]["bsdf"][int(q[2:])]
        return e[3], e[4]
    return s[q], s[q + "_err"]


def judge(check, est, err):
    """z with the reference's own error included, and the verdict."""
    sig = math.hypot(err, check.get("ref_err", 0.0))
    diff = est - check["ref"]
    if sig > 0:
        z = diff / sig
    else:  # both exact (e.g. single scattering against a closed form): a relative tolerance
        z = 0.0 if abs(diff) <= 1e-5 * max(1.0, abs(check["ref"])) else math.copysign(math.inf, diff)
    ok = math.isfinite(z) and abs(z) <= Z_MAX
    if check.get("limitation"):
        verdict = "known"
    else:
        verdict = "pass" if ok else "FAIL"
    return z, verdict


def rows_of_case(case, paths, binary=None, extra=()):
    summary, info = run_case(case, paths, binary, extra)
    rows = []
    for c in case["checks"]:
        est, err = estimate(c, summary, info)
        z, verdict = judge(c, est, err)
        rows.append({"group": case["group"], "name": case["name"], "slice": c["slice"],
                     "theta_o_deg": math.degrees(summary["slices"][c["slice"]]["theta_o"]), "q": c["q"],
                     "ref": c["ref"], "ref_err": c.get("ref_err", 0.0), "lsqt": est, "lsqt_err": err, "z": z,
                     "verdict": verdict, "limitation": c.get("limitation"), "paths": int(float(paths)),
                     "seconds": summary["seconds"]})
    return rows


def format_row(r):
    return (f"{r['group'][:10]:10s} {r['name'][:44]:44s} {r['theta_o_deg']:5.1f} {r['q']:5s} "
            f"{r['ref']:10.6f} {r['ref_err']:8.1e} {r['lsqt']:10.6f} {r['lsqt_err']:8.1e} {r['z']:+6.2f} {r['verdict']}")


HEADER = (f"{'reference':10s} {'case':44s} {'th_o':>5s} {'q':5s} {'ref':>10s} {'ref_err':>8s} "
          f"{'lsqt-cl':>10s} {'std_err':>8s} {'z':>6s} verdict")
