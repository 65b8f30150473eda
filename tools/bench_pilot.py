#!/usr/bin/env python3
"""RRSS pilot sizes compared on error per CPU-second.

For each case (the six tutorial files and a slab) and each placement (a set of lsqt-cl
flags), runs lsqt-cl with a few seeds and reads every kept direction's BSDF value and
standard error (`lsqt-cl info --bsdf`). Per run: CPU-s (user + sys: the machine is shared),
the median and the largest relative standard error over the kept directions of all
slices, and both at equal CPU time (error * sqrt(CPU-s): what one CPU-second buys, as
Monte Carlo error falls as 1 / sqrt(time)). The table gives, per case and placement, the
means over the seeds and the efficiency against the first placement,
(err_first^2 * cpu_first) / (err^2 * cpu): above 1 is better. A case whose point
estimates have no noise (the Lambertian's are exact) compares on CPU-s alone.

usage: tools/bench_pilot.py LSQT_CL [--seeds N] [--placements "A;B;..."] [--cases a,b]
       default placements "-rp 0.8;-rp 0.3;-rp 0.1"; the runs' other flags are each
       case's -p below (the kept directions' error bars need every batch's paths).
"""
import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TUT = os.path.join(ROOT, "examples", "tutorial")
SLAB = "Medium\nLayer z=1 NullBsdf\nMedium mus=0.9 mua=0.1 HenyeyGreensteinPhase g=0.8\nLayer z=0 NullBsdf\nMedium\n"
# -p per case: about 1-2 CPU-s at -rp 0.8 on 2 cores, so start-up (about 0.15 CPU-s) is small
CASES = [("Lambertian", 2000000), ("Dust", 200000), ("Dusty", 100000), ("Silver", 400000),
         ("Substr", 60000), ("Rough", 30000), ("slab", 400000)]


def run(binary, case, paths, flags, seed, d):
    src = os.path.join(d, "slab.lsqt") if case == "slab" else os.path.join(TUT, case + ".lsqt")
    if case == "slab":
        with open(src, "w") as f:
            f.write(SLAB)
    lss = os.path.join(d, "s.lss")
    cmd = [binary, "-q", "-R", "-p", str(paths), "-s", str(seed), "--lss", lss, "-o", os.path.join(d, "s.raw"),
           *flags, src]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    ij = os.path.join(d, "i.json")
    subprocess.run([binary, "info", lss, "--json", ij, "--bsdf"], check=True, stdout=subprocess.DEVNULL)
    with open(ij) as f:
        info = json.load(f)
    rel = [e[4] / e[3] for s in info["slices"] for e in s["bsdf"] if e[3] and e[3] > 0 and e[4] is not None]
    return cpu, statistics.median(rel), max(rel)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--placements", default="-rp 0.8;-rp 0.3;-rp 0.1")
    ap.add_argument("--cases", default=",".join(c for c, _ in CASES))
    ap.add_argument("--scale", type=float, default=1.0, help="multiply every case's -p")
    a = ap.parse_args()
    placements = [p.split() for p in a.placements.split(";")]
    want = a.cases.split(",")
    print("| case | -p | placement | CPU-s | median rel err | largest | median at 1 CPU-s | largest at 1 CPU-s "
          "| efficiency (median) | efficiency (largest) |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as d:
        for case, paths in CASES:
            if case not in want:
                continue
            paths = int(paths * a.scale)
            run(a.binary, case, 1000, placements[0], 0, d)  # fills the kernel cache
            first = None
            for pl in placements:
                rs = [run(a.binary, case, paths, pl, s, d) for s in range(a.seeds)]
                cpu = statistics.fmean(r[0] for r in rs)
                med = math.sqrt(statistics.fmean(r[1] ** 2 for r in rs))
                big = math.sqrt(statistics.fmean(r[2] ** 2 for r in rs))
                if first is None:
                    first = (cpu, med, big)
                eff = [(first[0] * first[k] ** 2) / (cpu * e ** 2) if e > 0 else first[0] / cpu
                       for k, e in ((1, med), (2, big))]
                print(f"| {case} | {paths:.0e} | {' '.join(pl)} | {cpu:.2f} | {med:.2e} | {big:.2e} | "
                      f"{med * math.sqrt(cpu):.2e} | {big * math.sqrt(cpu):.2e} | {eff[0]:.2f} | {eff[1]:.2f} |",
                      flush=True)


if __name__ == "__main__":
    sys.exit(main())
