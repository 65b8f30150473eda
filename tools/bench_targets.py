#!/usr/bin/env python3
"""The four speed targets of issue 13, measured: each workload once (after one untimed run
that fills the kernel cache), with wall and CPU seconds (user + sys of the whole process:
the machine is shared), paths/s, scattering events per second and per CPU-second, and
next-event evaluations per second, against the target.

    python3 tools/bench_targets.py [LSQT_CL] [--csv PATH] [-- more lsqt-cl flags, e.g. -d gpu]

Workloads (the original layered-sqt's CPU-seconds on this kind of machine in brackets):
  Rough   MicrosurfaceLambertianBrdf fR=0.6 alpha=2.4, defaults (-p 1e4, 12 x 80, RRSS)  [405]
  Substr  the tutorial's Substr at -wi 300 -rp 0.3 -p 1e4                                  [160]
  Slab    a slab mus=0.9 mua=0.1 HG g=0.8 between null layers, -p 1e5                     [13.7]
  MCX     20 thick, mus=10 mua=0.01 g=0.9, eta 1.37 between smooth boundaries, -p 1e4
          (target in scattering events per CPU-second; MCX-CL does about 5.1e6; 1e4 paths of
          560 events each per slice make start-up and the RRSS candidate walks a few percent)
Start-up: the wall and CPU seconds of a 1-path run of the workload (context, kernel build,
tables, the launches), cold (an empty PoCL kernel cache: POCL_CACHE_DIR in a fresh
folder) and cached."""
import csv
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

WORKLOADS = [  # name, LSQT text, flags, target kind, target value
    ("Rough", "Medium\nLayer z=0 MicrosurfaceLambertianBrdf fR=0.6 alpha=2.4\nMedium\n", [], "cpu_s", 4.0),
    ("Substr", open(os.path.join(ROOT, "examples", "tutorial", "Substr.lsqt")).read(), ["-wi", "300", "-rp", "0.3"],
     "cpu_s", 1.6),
    ("Slab", "Medium\nLayer z=1 NullBsdf\nMedium mus=0.9 mua=0.1 HenyeyGreensteinPhase g=0.8\nLayer z=0 NullBsdf\n"
     "Medium\n", ["-p", "100000"], "cpu_s", 0.3),
    ("MCX", "Medium\nLayer z=20 MicrosurfaceDielectricBsdf alpha=1e-4 use_multiple_scattering=false\n"
     "Medium eta=1.37 mus=10 mua=0.01 HenyeyGreensteinPhase g=0.9\n"
     "Layer z=0 MicrosurfaceDielectricBsdf alpha=1e-4 use_multiple_scattering=false\nMedium\n", ["-p", "10000"],
     "events_per_cpu_s", 2e7),
]


def run(binary, text, flags, extra, d, env=None):
    src = os.path.join(d, "w.lsqt")
    with open(src, "w") as f:
        f.write(text)
    cmd = [binary, "-q", "-R", "--json", os.path.join(d, "s.json"), "--lss", os.path.join(d, "s.lss"), "-o",
           os.path.join(d, "s.raw"), *flags, *extra, src]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    subprocess.run(cmd, check=True, env=env)
    wall = time.time() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return wall, cpu, json.load(open(os.path.join(d, "s.json")))


def without_p(flags):
    """FLAGS less any -p N."""
    out, skip = [], False
    for f in flags:
        if skip:
            skip = False
        elif f == "-p":
            skip = True
        else:
            out.append(f)
    return out


def main():
    args = sys.argv[1:]
    extra = args[args.index("--") + 1:] if "--" in args else []
    args = args[:args.index("--")] if "--" in args else args
    out_csv = None
    if "--csv" in args:
        i = args.index("--csv")
        out_csv = args[i + 1]
        del args[i:i + 2]
    binary = args[0] if args else os.path.join(ROOT, "build", "lsqt-cl")
    rows = []
    print(f"{'workload':8s} {'wall_s':>7s} {'cpu_s':>7s} {'paths/s':>9s} {'events/s':>9s} {'ev/cpu_s':>9s} "
          f"{'nee/s':>9s} {'start_cold':>10s} {'start':>6s}  target")
    with tempfile.TemporaryDirectory() as d:
        for name, text, flags, kind, target in WORKLOADS:
            one = without_p(flags)
            with tempfile.TemporaryDirectory() as cache:
                cold_w, cold_c, _ = run(binary, text, one + ["-p", "1"], extra, d, dict(os.environ, POCL_CACHE_DIR=cache))
            run(binary, text, flags, extra, d)  # fills the kernel cache
            warm_w, warm_c, _ = run(binary, text, one + ["-p", "1"], extra, d)
            wall, cpu, j = run(binary, text, flags, extra, d)
            events = j["events_per_path"] * j["paths_added"] * len(j["slices"])
            row = {"workload": name, "device": j["device"], "wall_s": wall, "cpu_s": cpu,
                   "sim_s": j["seconds"], "paths_per_s": j["paths_per_second"], "events_per_s": j["events_per_second"],
                   "events_per_cpu_s": events / cpu, "nee_per_s": j["nee_evaluations_per_second"],
                   "startup_cold_wall_s": cold_w, "startup_cold_cpu_s": cold_c, "startup_wall_s": warm_w,
                   "startup_cpu_s": warm_c, "target": f"{kind} {'<=' if kind == 'cpu_s' else '>='} {target:g}"}
            met = row[kind] <= target if kind == "cpu_s" else row[kind] >= target
            row["met"] = met
            rows.append(row)
            print(f"{name:8s} {wall:7.2f} {cpu:7.2f} {row['paths_per_s']:9.3g} {row['events_per_s']:9.3g} "
                  f"{row['events_per_cpu_s']:9.3g} {row['nee_per_s']:9.3g} {cold_w:10.2f} {warm_w:6.2f}  {row['target']}: "
                  f"{'met' if met else 'NOT met'}", flush=True)
    print(f"device: {rows[0]['device']}; start_cold / start: wall seconds of a 1-path run with an empty / a filled "
          f"kernel cache (context, build, tables, launches)")
    if out_csv:
        with open(out_csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
