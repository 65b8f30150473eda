#!/usr/bin/env python3
"""The four speed targets (docs/performance.md), measured: each workload once (after one untimed run
that fills the kernel cache), with wall and CPU seconds (user + sys of the whole process:
the machine is shared), paths/s, scattering events per second and per CPU-second, and
next-event evaluations per second, against the target.

    python3 tools/bench_targets.py [LSQT_CL] [--csv PATH] [--doc] [-- more lsqt-cl flags, e.g. -d gpu]

--doc: after measuring, rewrite docs/performance.md (tools/bench_doc.py: the machine, the
device, the commit and one table), only when every workload ran.

Workloads (the original layered-sqt's CPU-seconds on this kind of machine in brackets):
  Rough   MicrosurfaceLambertianBrdf fR=0.6 alpha=2.4, defaults (-p 1e4, 12 x 80, RRSS)  [405]
  Substr  the tutorial's Substr at -wi 300 -rp 0.3 -p 1e4                                  [160]
  Slab    a slab mus=0.9 mua=0.1 HG g=0.8 between null layers, -p 1e5                     [13.7]
  MCX     20 thick, mus=10 mua=0.01 g=0.9, eta 1.37 between smooth boundaries, -p 1e4
          (target in scattering events per CPU-second; MCX-CL does about 5.1e6; 1e4 paths of
          560 events each per slice make start-up and the RRSS candidate walks a few percent)
Start-up: the wall and CPU seconds of a 1-path run of the workload (context, kernel build,
tables, the launches), cold (an empty kernel cache: POCL_CACHE_DIR for PoCL and
CUDA_CACHE_PATH for NVIDIA's driver, each a fresh folder) and cached."""
import csv
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import bench_doc  # tools/, beside this script

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SUBSTR = os.path.join("examples", "tutorial", "Substr.lsqt")
WORKLOADS = [  # kind: the measure of the target ("cpu_s": at most, "events_per_cpu_s": at least)
    {"name": "Rough", "label": "Rough (alpha 2.4, defaults)", "file": None, "lsqt": "rough.lsqt",
     "about": "a rough Lambertian microsurface alone, lsqt-cl's defaults (-p 1e4, 12 slices x 80 directions, RRSS)",
     "text": "Medium\nLayer z=0 MicrosurfaceLambertianBrdf fR=0.6 alpha=2.4\nMedium\n", "flags": [],
     "kind": "cpu_s", "target": 4.0, "reference": "original layered-sqt 405 CPU-s"},
    {"name": "Substr", "label": "Substr -wi 300 -rp 0.3", "file": SUBSTR, "lsqt": SUBSTR,
     "about": "the tutorial's rough dielectric over a diffuse substrate", "text": open(os.path.join(ROOT, SUBSTR)).read(),
     "flags": ["-wi", "300", "-rp", "0.3"], "kind": "cpu_s", "target": 1.6,
     "reference": "original layered-sqt 160 CPU-s"},
    {"name": "Slab", "label": "Slab -p 1e5", "file": None, "lsqt": "slab.lsqt",
     "about": "a slab of optical thickness 1 (mus 0.9, mua 0.1, Henyey-Greenstein g 0.8) between null layers",
     "text": "Medium\nLayer z=1 NullBsdf\nMedium mus=0.9 mua=0.1 HenyeyGreensteinPhase g=0.8\nLayer z=0 NullBsdf\n"
             "Medium\n", "flags": ["-p", "100000"], "kind": "cpu_s", "target": 0.3,
     "reference": "original layered-sqt 13.7 CPU-s"},
    {"name": "MCX", "label": "MCX-like slab", "file": None, "lsqt": "mcx.lsqt",
     "about": "a slab 20 thick (mus 10, mua 0.01, g 0.9, optical thickness 200) of index 1.37 between smooth "
              "boundaries, about 560 events a path",
     "text": "Medium\nLayer z=20 MicrosurfaceDielectricBsdf alpha=1e-4 use_multiple_scattering=false\n"
             "Medium eta=1.37 mus=10 mua=0.01 HenyeyGreensteinPhase g=0.9\n"
             "Layer z=0 MicrosurfaceDielectricBsdf alpha=1e-4 use_multiple_scattering=false\nMedium\n",
     "flags": ["-p", "10000"], "kind": "events_per_cpu_s", "target": 2e7, "reference": "MCX-CL about 5.1e6"},
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
    args, extra = bench_doc.split_args(sys.argv[1:])
    out_csv = None
    if "--csv" in args:
        i = args.index("--csv")
        if i + 1 >= len(args):
            sys.exit("bench_targets.py: --csv needs a PATH")
        out_csv = args[i + 1]
        del args[i:i + 2]
    doc = "--doc" in args
    args = [a for a in args if a != "--doc"]
    if len(args) > 1 or (args and args[0].startswith("-")):
        sys.exit(f"bench_targets.py: unexpected arguments {' '.join(args)} (lsqt-cl flags go after --)")
    binary = args[0] if args else os.path.join(ROOT, "build", "lsqt-cl")
    if not (os.path.isfile(binary) and os.access(binary, os.X_OK)):
        sys.exit(f"bench_targets.py: {binary} is missing or not executable: build lsqt-cl first (bash tools/build.sh)")
    started = time.localtime()
    rows, failed = [], []
    print(f"{'workload':8s} {'wall_s':>7s} {'cpu_s':>7s} {'paths/s':>9s} {'events/s':>9s} {'ev/cpu_s':>9s} "
          f"{'nee/s':>9s} {'start_cold':>10s} {'start':>6s} {'err':>7s} {'effic':>8s}  target")
    with tempfile.TemporaryDirectory() as d:
        for w in WORKLOADS:
            name, text, flags, kind, target = w["name"], w["text"], w["flags"], w["kind"], w["target"]
            one = without_p(flags)
            try:
                with tempfile.TemporaryDirectory() as cache:
                    cold_w, cold_c, _ = run(binary, text, one + ["-p", "1"], extra, d,
                                            dict(os.environ, POCL_CACHE_DIR=cache, CUDA_CACHE_PATH=cache))
                run(binary, text, flags, extra, d)  # fills the kernel cache
                warm_w, warm_c, _ = run(binary, text, one + ["-p", "1"], extra, d)
                wall, cpu, j = run(binary, text, flags, extra, d)
                events = j["events_per_path"] * j["paths_added"] * len(j["slices"])
                errs = [s["max_rel_err"] for s in j["slices"] if s.get("max_rel_err") is not None]
                err = max(errs) if errs and max(errs) > 0 else None  # none below a full set of batches
                row = {"workload": name, "device": j["device"], "command": " ".join(["lsqt-cl", "-R", *flags, *extra,
                                                                                     w["lsqt"]]),
                       "wall_s": wall, "cpu_s": cpu, "sim_s": j["seconds"], "paths_per_s": j["paths_per_second"],
                       "events_per_s": j["events_per_second"], "events_per_cpu_s": events / cpu,
                       "nee_per_s": j["nee_evaluations_per_second"], "startup_cold_wall_s": cold_w,
                       "startup_cold_cpu_s": cold_c, "startup_wall_s": warm_w, "startup_cpu_s": warm_c,
                       "max_rel_err": err, "efficiency": 1.0 / (err * err * cpu) if err and cpu > 0 else None,
                       "target": f"{kind} {'<=' if kind == 'cpu_s' else '>='} {target:g}"}
            except (OSError, ValueError, KeyError, TypeError, ZeroDivisionError, subprocess.CalledProcessError) as e:
                print(f"{name:8s} FAILED: {e}", file=sys.stderr, flush=True)
                failed.append(name)
                continue
            met = row[kind] <= target if kind == "cpu_s" else row[kind] >= target
            row["met"] = met
            rows.append(row)
            fmt = lambda v, spec: format(v, spec) if v is not None else "-"
            print(f"{name:8s} {wall:7.2f} {cpu:7.2f} {row['paths_per_s']:9.3g} {row['events_per_s']:9.3g} "
                  f"{row['events_per_cpu_s']:9.3g} {row['nee_per_s']:9.3g} {cold_w:10.2f} {warm_w:6.2f} "
                  f"{fmt(err, '7.3g')} {fmt(row['efficiency'], '8.3g')}  {row['target']}: "
                  f"{'met' if met else 'NOT met'}", flush=True)
    if rows:
        print(f"device: {rows[0]['device']}; start_cold / start: wall seconds of a 1-path run with an empty / a "
              f"filled kernel cache (context, build, tables, launches); err: largest relative standard error of "
              f"the BSDF values over the slices; effic: 1 / (err^2 * cpu_s)")
    if out_csv and rows:
        with open(out_csv, "w", newline="") as f:
            wr = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            wr.writeheader()
            wr.writerows(rows)
    if failed:
        print(f"bench_targets.py: {len(failed)} of {len(WORKLOADS)} workloads failed ({', '.join(failed)})"
              + ("; docs/performance.md not written" if doc else ""), file=sys.stderr)
        return 1
    if doc:
        print(f"wrote {bench_doc.write_atomic(bench_doc.render(rows, WORKLOADS, extra, started, binary))}")
    return 0

if __name__ == "__main__":
    sys.exit(main())
