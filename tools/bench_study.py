#!/usr/bin/python3
"""The speed/accuracy study (issue 13): reference assemblies with known answers, run over a
range of settings, each setting over several seeds; the error against the known answer
beside the CPU time it cost. Writes a CSV, error-against-time plots (log-log) and an
efficiency plot (1 / (error^2 x CPU-s)) with Debian's matplotlib (as tools/lssplot does,
hence /usr/bin/python3), and with --doc the page docs/speed-accuracy.md.

    tools/bench.sh study [--quick] [--doc] [--seeds N] [--out DIR] [-- lsqt-cl flags]

The known answers are the validation suite's (tests/data/validation_fixtures.json, made by
tools/validate/validate.py --write-fixtures from iadpython, Mitsuba 3 and the independent
walk of Heitz et al. 2016), so the study needs no package beyond matplotlib:
  slab    a scattering slab between Fresnel boundaries (iadpython): R and T at 0 and 60 deg
  ggx     a rough GGX conductor, single scattering (Mitsuba 3): BSDF values at 14 pairs
  ms      the multiple-scattering rough conductor, alpha 1 (Heitz 2016 walk): the albedo of
          each slice integrated from the point estimates over an even spread of -wi
          directions against the walk's R, so iter_count, -wi and multiple scattering
          (against the single-scattering quadrature) are measured on what a user stores
  rrss    the tutorial's Substr, which has no known answer: -wi and -rp against the run's
          own error bars (median relative standard error of the stored BSDF values)
Error of a setting: the root mean square over the quantities and seeds of (estimate -
reference) / reference, with the reference's own error subtracted in quadrature (so it is
the Monte Carlo error, not the reference's). CPU-s: user + sys of lsqt-cl, whose kernels
are cached by an untimed first run."""
import csv
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIXTURES = os.path.join(ROOT, "tests", "data", "validation_fixtures.json")
SUBSTR = os.path.join(ROOT, "examples", "tutorial", "Substr.lsqt")


def fixture(name):
    with open(FIXTURES) as f:
        data = json.load(f)
    for c in data["cases"] if isinstance(data, dict) else data:
        if c["name"] == name:
            return c
    raise SystemExit(f"bench_study: no case '{name}' in {FIXTURES}")


def run(binary, text, args, paths, seed, extra, wi=None, bsdf=False):
    """One lsqt-cl run; returns (summary, info or None, cpu_s, wall_s)."""
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, "c.lsqt")
        with open(src, "w") as f:
            f.write(text)
        cmd = [binary, "-q", "-R", "-p", str(int(paths)), "-s", str(seed), "--lss", os.path.join(d, "s.lss"),
               "-o", os.path.join(d, "s.raw"), "--json", os.path.join(d, "s.json"), *args, *extra]
        if wi:
            with open(os.path.join(d, "wi.txt"), "w") as f:
                f.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z in wi)
            cmd += ["--wi-file", os.path.join(d, "wi.txt")]
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.time()
        subprocess.run(cmd + [src], check=True)
        wall = time.time() - t0
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
        with open(os.path.join(d, "s.json")) as f:
            summary = json.load(f)
        info = None
        if bsdf:
            subprocess.run([binary, "info", os.path.join(d, "s.lss"), "--json", os.path.join(d, "i.json"), "--bsdf"],
                           check=True, stdout=subprocess.DEVNULL)
            with open(os.path.join(d, "i.json")) as f:
                info = json.load(f)
    return summary, info, cpu, wall


def sq_errors_checks(case, summary, info):
    """Squared relative errors of a fixture case's checks (reference noise removed)."""
    out = []
    for c in case["checks"]:
        if c["ref"] == 0 or c.get("limitation"):
            continue
        s = summary["slices"][c["slice"]]
        est = info["slices"][c["slice"]]["bsdf"][int(c["q"][2:])][3] if c["q"].startswith("f:") else s[c["q"]]
        out.append(((est - c["ref"]) ** 2 - c.get("ref_err", 0.0) ** 2) / c["ref"] ** 2)
    return out


def sq_errors_albedo(case, summary, info, n):
    """Squared relative errors of each slice's albedo integrated from the point estimates on
    the even spread of n directions (each 2 pi / n sr of the hemisphere) against R."""
    out = []
    w = 2 * math.pi / n
    for c in case["checks"]:
        if c["q"] != "R":
            continue
        ir = sum(e[3] * e[2] for e in info["slices"][c["slice"]]["bsdf"] if e[2] > 0) * w
        out.append(((ir - c["ref"]) ** 2 - c.get("ref_err", 0.0) ** 2) / c["ref"] ** 2)
    return out


def own_error(summary, info):
    """Median relative standard error of the stored BSDF values (no known answer)."""
    rel = [e[4] / e[3] for s in info["slices"] for e in s["bsdf"] if e[3] > 0]
    return statistics.median(rel) ** 2


def settings(quick):
    """(study, label, series, x, case, text, args, paths, error function, wants info, wi)."""
    slab = fixture("Fresnel n=1.33 a=0.9 tau=1 g=0.5")
    ggx = fixture("GGX conductor a=0.3 n=0.2+3i")
    ms = fixture("MS conductor a=1.0 (metal 1.1+2.6i)")
    ss = fixture("SS conductor a=1.0 (quadrature)")
    ms_args = ["--wo-angles=0,45,75", "--wi-spread"]
    ps_slab = [1000, 4000, 16000] if quick else [1000, 4000, 16000, 64000]
    ps_ggx = [100, 400, 1600] if quick else [100, 400, 1600, 6400]
    ps_ms = [250, 1000] if quick else [250, 1000, 4000]
    out = []
    for prec in ("float", "double"):
        pa = ["--double"] if prec == "double" else []
        for p in ps_slab:
            out.append(("precision", f"slab {prec}", f"slab {prec}", p, slab, slab["lsqt"], slab["args"] + pa, p,
                        lambda c, s, i: sq_errors_checks(c, s, i), False, None))
        for p in ps_ggx:
            out.append(("precision", f"ggx {prec}", f"ggx {prec}", p, ggx, ggx["lsqt"],
                        [a for a in ggx["args"] if a != "--double"] + pa, p,
                        lambda c, s, i: sq_errors_checks(c, s, i), True, ggx["wi"]))
    for it in (1, 2, 6, 16):
        text = ms["lsqt"].replace("use_multiple_scattering=true", f"use_multiple_scattering=true iter_count={it}")
        for p in ps_ms:
            out.append(("iter_count", f"iter_count {it}", f"iter_count={it}", p, ms, text, ms_args + ["-wi", "256"], p,
                        lambda c, s, i: sq_errors_albedo(c, s, i, 256), True, None))
    for label, case in (("multiple scattering on", ms), ("multiple scattering off", ss)):
        for p in ps_ms:
            out.append(("scattering", label, label, p, case, case["lsqt"], ms_args + ["-wi", "256"], p,
                        lambda c, s, i: sq_errors_albedo(c, s, i, 256), True, None))
    for n in ((64, 256) if quick else (64, 256, 1024)):
        out.append(("wi", f"-wi {n} (spread)", "albedo from the spread", n, ms, ms["lsqt"], ms_args + ["-wi", str(n)],
                    1000, (lambda n: lambda c, s, i: sq_errors_albedo(c, s, i, n))(n), True, None))
    with open(SUBSTR) as f:
        substr = f.read()
    for n in ((80, 300) if quick else (80, 160, 300)):
        out.append(("rrss", f"Substr -wi {n}", "Substr -wi (-rp 0.3)", n, None, substr, ["-wi", str(n), "-rp", "0.3"],
                    4000, lambda c, s, i: [own_error(s, i)], True, None))
    for rp in ((0.1, 0.8) if quick else (0.1, 0.3, 0.8)):
        out.append(("rrss", f"Substr -rp {rp}", "Substr -rp (-wi 80)", rp, None, substr, ["-rp", str(rp)], 4000,
                    lambda c, s, i: [own_error(s, i)], True, None))
    return out


def plots(rows, out_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    files = []
    for study, title, xname in (("precision", "error against CPU time: -p from low to high, float and double", None),
                                ("iter_count", "multiple-scattering conductor: iter_count, -p from low to high", None),
                                ("scattering", "multiple scattering on and off (each against its own reference)", None)):
        fig, ax = plt.subplots(figsize=(6.4, 4.4))
        series = {}
        for r in rows:
            if r["study"] == study:
                series.setdefault(r["series"], []).append(r)
        for name, rs in series.items():
            rs.sort(key=lambda r: r["cpu_s"])
            ax.plot([r["cpu_s"] for r in rs], [r["error"] for r in rs], "o-", label=name)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU seconds (user + sys) per run")
        ax.set_ylabel("relative RMS error against the known answer")
        ax.set_title(title, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = os.path.join(out_dir, f"error-time-{study}.png")
        fig.savefig(path, dpi=90)
        plt.close(fig)
        files.append(path)
    fig, ax = plt.subplots(figsize=(7.2, 5.0))
    labels = []
    best = {}
    for r in rows:  # per label: the efficiency at its largest -p (the steadiest figure)
        key = r["label"]
        if key not in best or r["x"] > best[key]["x"] or r["study"] in ("wi", "rrss"):
            best[key] = r
    for i, (label, r) in enumerate(best.items()):
        ax.barh(i, r["efficiency"])
        labels.append(label)
    ax.set_yticks(range(len(labels)))
    ax.set_yticklabels(labels, fontsize=7)
    ax.set_xscale("log")
    ax.set_xlabel("efficiency 1 / (error^2 x CPU-s), higher is better")
    ax.set_title("efficiency per setting (compare within a group only)", fontsize=9)
    ax.invert_yaxis()
    fig.tight_layout()
    path = os.path.join(out_dir, "efficiency.png")
    fig.savefig(path, dpi=90)
    plt.close(fig)
    files.append(path)
    return files


def main():
    args = sys.argv[1:]
    extra = args[args.index("--") + 1:] if "--" in args else []
    args = args[:args.index("--")] if "--" in args else args
    quick, doc = "--quick" in args, "--doc" in args
    seeds = int(args[args.index("--seeds") + 1]) if "--seeds" in args else (2 if quick else 3)
    out_dir = args[args.index("--out") + 1] if "--out" in args else os.path.join(ROOT, "build", "study")
    binary = os.environ.get("LSQT_CL", os.path.join(ROOT, "build", "lsqt-cl"))
    os.makedirs(out_dir, exist_ok=True)
    rows = []
    warmed = set()
    print(f"{'study':10s} {'setting':28s} {'x':>7s} {'paths':>7s} {'cpu_s':>7s} {'wall_s':>7s} {'error':>9s} "
          f"{'efficiency':>10s}", flush=True)
    for study, label, series, x, case, text, a, paths, err_fn, want_info, wi in settings(quick):
        key = (text, tuple(a))
        if key not in warmed:  # fills the kernel cache: compile time is not the setting's
            run(binary, text, a, 100, 1, extra, wi)
            warmed.add(key)
        sq, cpu, wall = [], 0.0, 0.0
        for k in range(seeds):
            summary, info, c, w = run(binary, text, a, paths, 1 + k, extra, wi, want_info)
            sq += err_fn(case, summary, info)
            cpu += c
            wall += w
        cpu, wall = cpu / seeds, wall / seeds
        err = math.sqrt(max(statistics.fmean(sq), 1e-30))
        row = {"study": study, "label": label, "series": series, "x": x, "paths": paths, "seeds": seeds,
               "cpu_s": cpu, "wall_s": wall, "error": err, "efficiency": 1.0 / (err * err * cpu)}
        rows.append(row)
        print(f"{study:10s} {label:28s} {x:7g} {paths:7d} {cpu:7.3f} {wall:7.3f} {err:9.3e} {row['efficiency']:10.3g}",
              flush=True)
    csv_path = os.path.join(out_dir, "study.csv")
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {csv_path}")
    if doc:
        img_dir = os.path.join(ROOT, "docs", "speed-accuracy")
        os.makedirs(img_dir, exist_ok=True)
        files = plots(rows, img_dir)
        write_doc(rows, files, seeds, extra)
    else:
        files = plots(rows, out_dir)
    for p in files:
        print(f"wrote {p}")
    return 0


def write_doc(rows, files, seeds, extra):
    """docs/speed-accuracy.md: the measured table and what it tells a user."""
    import platform
    dev = subprocess.run([os.environ.get("LSQT_CL", os.path.join(ROOT, "build", "lsqt-cl")), "--list-devices"],
                         capture_output=True, text=True).stdout.strip().splitlines()
    by = {}
    for r in rows:
        by.setdefault(r["study"], []).append(r)

    def table(rs):
        t = ["| setting | x | paths | CPU-s | wall s | rel. error | efficiency |", "|---|---:|---:|---:|---:|---:|---:|"]
        for r in rs:
            t.append(f"| {r['label']} | {r['x']:g} | {r['paths']} | {r['cpu_s']:.3f} | {r['wall_s']:.3f} | "
                     f"{r['error']:.2e} | {r['efficiency']:.3g} |")
        return "\n".join(t)

    def eff(label, x):
        for r in rows:
            if r["label"] == label and r["x"] == x:
                return r
        return None

    ps_ms = sorted({r["x"] for r in by["iter_count"]})
    top = ps_ms[-1]
    it = {k: eff(f"iter_count {k}", top) for k in (1, 2, 6, 16)}
    best_it = max(it, key=lambda k: it[k]["efficiency"])
    slab_f = max((r for r in by["precision"] if r["label"] == "slab float"), key=lambda r: r["x"])
    slab_d = max((r for r in by["precision"] if r["label"] == "slab double"), key=lambda r: r["x"])
    ggx_f = max((r for r in by["precision"] if r["label"] == "ggx float"), key=lambda r: r["x"])
    ggx_d = max((r for r in by["precision"] if r["label"] == "ggx double"), key=lambda r: r["x"])
    ms_on = eff("multiple scattering on", top)
    ms_off = eff("multiple scattering off", top)
    rel = lambda a, b: a["efficiency"] / b["efficiency"]
    text = f"""# Speed and accuracy: which settings buy how much accuracy per second

Generated by `tools/bench.sh study --doc` (`tools/bench_study.py`); do not edit by hand.
Machine: {platform.node() and 'this project machine'} with {os.cpu_count()} cores, device
`{dev[-1].strip() if dev else 'default'}`{(', flags ' + ' '.join(extra)) if extra else ''}. Each row is the mean of {seeds} seeds.

**How to read it.** The error is the root mean square, over the quantities and the seeds, of
(lsqt-cl − known answer) / known answer, with the known answer's own uncertainty taken out
in quadrature, so it is lsqt-cl's Monte Carlo error. The known answers are the validation
suite's (`docs/validation.md`): iadpython for the slab, Mitsuba 3 for the single-scattering
GGX conductor, the independent walk of Heitz et al. (2016) for the multiple-scattering
conductor. Efficiency is 1 / (error² × CPU-s): a setting with twice the efficiency reaches
the same error in half the time. Monte Carlo error falls as 1 / sqrt(paths), so efficiency
is flat in −p once start-up (about 0.2 CPU-s: OpenCL context, cached kernels) is small
against the run; compare settings at the largest −p. CPU-s is user + sys (the machine is
shared); each run's kernels are cached by an untimed first run. At the smallest −p the
error has few samples and is itself uncertain by tens of percent.

![error against time, precision](speed-accuracy/error-time-precision.png)
![error against time, iter_count](speed-accuracy/error-time-iter_count.png)
![error against time, multiple scattering](speed-accuracy/error-time-scattering.png)
![efficiency per setting](speed-accuracy/efficiency.png)

## What it tells a user

- **−p**: error falls as 1/sqrt(−p) in every row below (4× the paths, half the error),
  down to the known answers' own accuracy. Below about 1000 paths per slice start-up
  dominates the time, so small runs are cheap in error per second only up to that point.
- **float or double**: on the slab, double costs {slab_d['cpu_s'] / slab_f['cpu_s']:.2f}× the CPU time of float for an
  error of {slab_d['error']:.2e} against {slab_f['error']:.2e} (efficiency ratio float/double
  {rel(slab_f, slab_d):.2f}); on the GGX conductor {ggx_d['cpu_s'] / ggx_f['cpu_s']:.2f}× for {ggx_d['error']:.2e} against {ggx_f['error']:.2e}
  (ratio {rel(ggx_f, ggx_d):.2f}). Float's rounding (1e-7) is far below Monte Carlo error at
  any −p a user runs, so float is the default; `--double` is for checking extreme
  parameters (docs/validation.md's extremes), not for accuracy per second.
- **iter_count** (walks per next-event estimate on a multiple-scattering microsurface): at
  −p {top}, efficiency {', '.join(f'{k}: {it[k]["efficiency"]:.3g}' for k in (1, 2, 6, 16))}; the best here is
  iter_count = {best_it}. Raising iter_count beats raising −p when the point estimates' own
  noise (the random walk on the facets) dominates, as on this rough (alpha 1) conductor; it
  costs the same per walk as a path only where the layer's next-event work dominates the
  path (a single layer), so in a deep stack its price is relatively lower still.
- **Multiple scattering**: on (against the walk's answer) costs {ms_on['cpu_s'] / ms_off['cpu_s']:.2f}× the CPU time of off
  (against the single-scattering quadrature) at −p {top}, efficiency ratio on/off
  {rel(ms_on, ms_off):.2f}. Turning it off is not a speed setting: it changes the answer by the
  missing multiple scattering ({100 * (1 - 0.2281886 / 0.4106477):.0f} % of R at 45° for alpha 1), far more than any Monte
  Carlo error.
- **−wi**: the albedo integrated from the point estimates needs enough directions to
  resolve the BSDF; the rows below show its error and cost as −wi grows at −p 1000.
- **−rp and −wi with RRSS** (the tutorial's Substr, no known answer: its own error bars):
  a longer pilot (−rp) costs more (it estimates 4 × −wi candidates) and buys a better
  choice of directions; the error bars of the stored values are those of the paths.

## Tables

### −p, float and double
{table(by['precision'])}

### iter_count (multiple-scattering conductor, alpha 1, albedo from 256 directions)
{table(by['iter_count'])}

### Multiple scattering on and off
{table(by['scattering'])}

### −wi (even spread; albedo error, includes the quadrature's)
{table(by['wi'])}

### RRSS: −wi and −rp on Substr (error: median relative standard error of the stored values)
{table(by['rrss'])}
"""
    with open(os.path.join(ROOT, "docs", "speed-accuracy.md"), "w") as f:
        f.write(text)
    print("wrote docs/speed-accuracy.md")


if __name__ == "__main__":
    sys.exit(main())
