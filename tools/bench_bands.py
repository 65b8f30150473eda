#!/usr/bin/env python3
"""Bands: the cost of one run with N bands against N one-band runs of the same values, and
each band's standard error against its own one-band run (docs/performance.md, "Bands").

    python3 tools/bench_bands.py [LSQT_CL] [-p PATHS] [--bands 3,32] [--csv PATH]

Cases (each at every band count of --bands):
  dust   a dusty coat: an HG medium (optical thickness 1.2 to 2, albedo 0.6 to 0.98, g 0.6)
         over a coloured Lambertian base (fR 0.1 to 0.7), values varying over the bands
  gold   gold (n, k from examples/tables/, Johnson and Christy 1972) under a rough
         dielectric coat, --wavelengths over 400-710 nm
  slab   an absorbing and scattering slab between null layers whose albedo goes from 0 to
         0.999 over the bands (optical thickness 1, HG g 0.8)
  paint  examples/tio2-paint.lsqt, a white paint from Mie theory (optical thickness 0.4 to
         144, g 0.04 to 0.63), --wavelengths 400:2500 in N bands (106: every 20 nm)
With --baseline apart, the one-band runs are one run of the same bands with
LSQT_BAND_BLOCK=1 (every band on its own paths, one start-up for all); the default runs
each band's own file (a start-up each).
Every run: -wo 4 -wi 64 --wi-spread, seed 0, one untimed run first (the kernel cache).
CPU seconds are user + sys of the lsqt-cl processes (the machine is shared); the error ratio
is, per band, the largest over slices of R_err of the run with bands over that of the
band's one-band run (1 when the bands' walks are the one-band walks)."""
import argparse
import csv
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLAGS = ["-wo", "4", "-wi", "64", "--wi-spread", "-q", "-R"]


def lerp(a, b, n):
    return [a + (b - a) * i / (n - 1) if n > 1 else a for i in range(n)]


def fmt(vals):
    return ",".join("%.6g" % v for v in vals)


def case_text(name, n):
    """(LSQT text with lists, extra flags, one-band texts); tables are read from tables/."""
    if name == "dust":
        tau, alb, fr = lerp(2.0, 1.2, n), lerp(0.98, 0.6, n), lerp(0.7, 0.1, n)
        mus = [t * a for t, a in zip(tau, alb)]
        mua = [t * (1 - a) for t, a in zip(tau, alb)]
        text = lambda s, a, r: ("Medium\nLayer z=1 NullBsdf\nMedium mus=%s mua=%s HenyeyGreensteinPhase g=0.6\n"
                                "Layer z=0 LambertianBsdf fR=%s\nMedium\n" % (s, a, r))
        return (text(fmt(mus), fmt(mua), fmt(fr)), [],
                [text("%.6g" % mus[b], "%.6g" % mua[b], "%.6g" % fr[b]) for b in range(n)])
    if name == "gold":
        wl = [400 + 10 * i for i in range(n)] if n > 3 else [450, 550, 650]
        text = lambda w: ("Medium\nLayer z=0 MicrosurfaceDielectricBsdf alpha=0.2\nMedium eta=1.5\n"
                          "Layer z=-1 MicrosurfaceConductive alpha=0.3\nMedium eta=@tables/gold_n.txt mua=@tables/gold_k.txt\n")
        return (text(None), ["--wavelengths", fmt(wl)], [(text(None), ["--wavelengths", "%g" % w]) for w in wl])
    if name == "slab":
        alb = lerp(0.0, 0.999, n)
        text = lambda s, a: ("Medium\nLayer z=1 NullBsdf\nMedium mus=%s mua=%s HenyeyGreensteinPhase g=0.8\n"
                             "Layer z=0 NullBsdf\nMedium\n" % (s, a))
        return (text(fmt(alb), fmt([1 - a for a in alb])), [],
                [text("%.6g" % a, "%.6g" % (1 - a)) for a in alb])
    if name == "paint":
        text = open(os.path.join(ROOT, "examples", "tio2-paint.lsqt")).read()
        step = 2100 // (n - 1) if n > 1 else 0
        if n < 2 or step * (n - 1) != 2100:
            raise ValueError("paint: N - 1 must divide 2100 (106 bands: every 20 nm)")
        wl = ["--wavelengths", "400:2500:%d" % step]
        return (text, wl, [(text, ["--wavelengths", "%d" % (400 + step * b)]) for b in range(n)])
    raise ValueError(name)


def run(binary, path, flags, paths, json_path, env=None):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    subprocess.run([binary, path, "-p", str(paths), "--json", json_path] + FLAGS + flags, check=True,
                   stdout=subprocess.DEVNULL, env=dict(os.environ, **(env or {})))
    wall = time.time() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, json.load(open(json_path))


def max_r_err(js, band, n):
    return max((s["R_err"][band] if n > 1 else s["R_err"]) for s in js["slices"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("lsqt_cl", nargs="?", default=os.path.join(ROOT, "build", "lsqt-cl"))
    ap.add_argument("-p", "--paths", type=int, default=20000)
    ap.add_argument("--bands", default="3,32")
    ap.add_argument("--cases", default="dust,gold,slab")
    ap.add_argument("--baseline", choices=("runs", "apart"), default="runs")
    ap.add_argument("--csv")
    a = ap.parse_args()
    binary = os.path.abspath(a.lsqt_cl)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        os.symlink(os.path.join(ROOT, "examples", "tables"), os.path.join(d, "tables"))
        for name in a.cases.split(","):
            for n in [int(x) for x in a.bands.split(",")]:
                text, flags, ones = case_text(name, n)
                many = os.path.join(d, "%s-%d.lsqt" % (name, n))
                open(many, "w").write(text)
                run(binary, many, flags, 1, os.path.join(d, "warm.json"))  # the kernel cache
                wall, cpu, js = run(binary, many, flags, a.paths, os.path.join(d, "many.json"))
                one_wall = one_cpu = 0.0
                ratios = []
                if a.baseline == "apart":
                    one_wall, one_cpu, j1 = run(binary, many, flags, a.paths, os.path.join(d, "one.json"),
                                                {"LSQT_BAND_BLOCK": "1"})
                    for b in range(n):
                        e1 = max_r_err(j1, b, n)
                        ratios.append(max_r_err(js, b, n) / e1 if e1 > 0 else float("nan"))
                for b, one in enumerate(ones if a.baseline == "runs" else []):
                    t, f = one if isinstance(one, tuple) else (one, [])
                    p = os.path.join(d, "%s-%d-one%d.lsqt" % (name, n, b))
                    open(p, "w").write(t)
                    if b == 0:
                        run(binary, p, f, 1, os.path.join(d, "warm.json"))
                    w1, c1, j1 = run(binary, p, f, a.paths, os.path.join(d, "one.json"))
                    one_wall, one_cpu = one_wall + w1, one_cpu + c1
                    e1 = max_r_err(j1, 0, 1)
                    ratios.append(max_r_err(js, b, n) / e1 if e1 > 0 else float("nan"))
                row = {"case": name, "bands": n, "paths": a.paths, "wall_s": wall, "cpu_s": cpu,
                       "one_band_runs_wall_s": one_wall, "one_band_runs_cpu_s": one_cpu,
                       "cpu_ratio": cpu / one_cpu if one_cpu > 0 else float("nan"),
                       "max_err_ratio": max(r for r in ratios if r == r) if any(r == r for r in ratios) else float("nan")}
                # a band's efficiency (1 / (error^2 CPU)) over its own run's, and the gain
                effs = sorted(1.0 / (row["cpu_ratio"] * r * r) for r in ratios if r == r and r > 0)
                row["gain"] = effs[0] if effs else float("nan")
                row["median_band_efficiency"] = effs[len(effs) // 2] if effs else float("nan")
                rows.append(row)
                print("%-5s %3d bands: one run %.2f CPU-s (%.2f s wall), %d one-band runs %.2f CPU-s (%.2f s wall): "
                      "ratio %.3f; largest error ratio %.3f; gain %.2f (the least efficient band's; median %.2f)"
                      % (name, n, cpu, wall, n, one_cpu, one_wall, row["cpu_ratio"], row["max_err_ratio"],
                         row["gain"], row["median_band_efficiency"]), flush=True)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
