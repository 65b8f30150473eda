#!/usr/bin/python3
"""The speed/accuracy study: reference assemblies with known answers, run over a
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

import bench_doc  # tools/, beside this script

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
        out.append(((est - c["ref"]) / c["ref"]) ** 2)
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
        out.append(((ir - c["ref"]) / c["ref"]) ** 2)
    return out


def ref_floor(case, albedo=False):
    """The RMS relative error of the known answers themselves (the floor of the error)."""
    rel = [(c.get("ref_err", 0.0) / c["ref"]) ** 2 for c in case["checks"]
           if c["ref"] != 0 and not c.get("limitation") and (not albedo or c["q"] == "R")]
    return math.sqrt(statistics.fmean(rel)) if rel else 0.0


def own_error(case, summary, info):
    """The run's own error bars: for R and T (the slab) their relative standard error, RMS
    over the checks; else the median relative standard error of the stored BSDF values."""
    if case is not None and all(c["q"] in ("R", "T") for c in case["checks"]) and case["name"].startswith("Fresnel"):
        rel = [summary["slices"][c["slice"]][c["q"] + "_err"] / summary["slices"][c["slice"]][c["q"]]
               for c in case["checks"]]
        return math.sqrt(statistics.fmean(r * r for r in rel))
    rel = [e[4] / e[3] for s in info["slices"] for e in s["bsdf"] if e[3] and e[4] is not None and e[3] > 0]
    return statistics.median(rel) if rel else float("nan")


def settings(quick):
    """(study, label, series, x, case, text, args, paths, known-answer error function or None, wi)."""
    slab = fixture("Fresnel n=1.33 a=0.9 tau=1 g=0.5")
    ms = fixture("MS conductor a=1.0 (metal 1.1+2.6i)")
    ss = fixture("SS conductor a=1.0 (quadrature)")
    ms_args = ["--wo-angles=0,45,75", "--wi-spread"]
    checks = lambda c, s, i: sq_errors_checks(c, s, i)
    albedo = lambda n: lambda c, s, i: sq_errors_albedo(c, s, i, n)
    # multiples of 8192 = 32 batches of a 256-path chunk: below that some batches are
    # empty and a run has no error bars of its own
    ps_slab = [8192, 32768] if quick else [8192, 32768, 131072]
    ps_ms = [8192] if quick else [8192, 32768]
    out = []
    for prec in ("float", "double"):
        pa = ["--double"] if prec == "double" else []
        for p in ps_slab:
            out.append(("precision", f"slab {prec}", f"slab {prec}", p, slab, slab["lsqt"], slab["args"] + pa, p, checks,
                        None))
        for p in ps_ms:
            out.append(("precision", f"ms conductor {prec}", f"ms conductor {prec}", p, ms, ms["lsqt"],
                        ms_args + ["-wi", "256"] + pa, p, albedo(256), None))
    for it in (1, 2, 6, 16):
        text = ms["lsqt"].replace("use_multiple_scattering=true", f"use_multiple_scattering=true iter_count={it}")
        for p in ps_ms:
            out.append(("iter_count", f"iter_count {it}", f"iter_count={it}", p, ms, text, ms_args + ["-wi", "256"], p,
                        albedo(256), None))
    for label, case in (("multiple scattering on", ms), ("multiple scattering off", ss)):
        for p in ps_ms:
            out.append(("scattering", label, label, p, case, case["lsqt"], ms_args + ["-wi", "256"], p, albedo(256),
                        None))
    for n in ((64, 256) if quick else (64, 256, 1024)):
        out.append(("wi", f"-wi {n} (spread)", "ms conductor, even spread", n, ms, ms["lsqt"],
                    ms_args + ["-wi", str(n)], 8192, albedo(n), None))
    with open(SUBSTR) as f:
        substr = f.read()
    for n in ((80, 300) if quick else (80, 160, 300)):
        out.append(("rrss", f"Substr -wi {n} -rp 0.3", "Substr -wi (-rp 0.3)", n, None, substr,
                    ["-wi", str(n), "-rp", "0.3"], 8192, None, None))
    for rp in (0.1, 0.8):  # (-rp 0.3 is the -wi series' first row)
        out.append(("rrss", f"Substr -wi 80 -rp {rp}", "Substr -rp (-wi 80)", rp, None, substr, ["-rp", str(rp)], 8192,
                    None, None))
    return out


def plots(rows, out_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    files = []
    for study, title in (("precision", "-p from low to high, float and double"),
                         ("iter_count", "multiple-scattering conductor (alpha 1): iter_count"),
                         ("scattering", "multiple scattering on and off (each against its own answer)")):
        fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
        series = {}
        for r in rows:
            if r["study"] == study:
                series.setdefault(r["series"], []).append(r)
        for ax, key, ylabel in ((axes[0], "error", "relative RMS error against the known answer"),
                                (axes[1], "own_error", "median relative standard error (own error bars)")):
            for name, rs in series.items():
                rs.sort(key=lambda r: r["cpu_s"])
                pts = [(r["cpu_s"], r[key]) for r in rs if r[key]]
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=name)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("CPU seconds (user + sys) per run")
            ax.set_ylabel(ylabel, fontsize=8)
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
        fig.suptitle(title, fontsize=9)
        fig.tight_layout()
        path = os.path.join(out_dir, f"error-time-{study}.png")
        fig.savefig(path, dpi=80)
        plt.close(fig)
        files.append(path)
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    best = {}
    for r in rows:  # per label: at its largest -p (start-up matters least there)
        if r["label"] not in best or r["paths"] > best[r["label"]]["paths"]:
            best[r["label"]] = r
    labels = list(best)
    ax.barh([i - 0.2 for i in range(len(labels))], [best[k]["efficiency"] or 0 for k in labels], height=0.4,
            label="known answer")
    ax.barh([i + 0.2 for i in range(len(labels))], [best[k]["own_efficiency"] or 0 for k in labels], height=0.4,
            label="own error bars")
    ax.set_yticks(range(len(labels)))
    ax.set_yticklabels(labels, fontsize=7)
    ax.set_xscale("log")
    ax.set_xlabel("efficiency 1 / (error^2 x CPU-s), higher is better")
    ax.set_title("efficiency per setting, at its largest -p (compare within a group)", fontsize=9)
    ax.legend(fontsize=7)
    ax.invert_yaxis()
    fig.tight_layout()
    path = os.path.join(out_dir, "efficiency.png")
    fig.savefig(path, dpi=80)
    plt.close(fig)
    files.append(path)
    return files


def main():
    args, extra = bench_doc.split_args(sys.argv[1:])
    quick, doc = "--quick" in args, "--doc" in args
    seeds = int(args[args.index("--seeds") + 1]) if "--seeds" in args else (2 if quick else 8)
    out_dir = args[args.index("--out") + 1] if "--out" in args else os.path.join(ROOT, "build", "study")
    binary = os.environ.get("LSQT_CL", os.path.join(ROOT, "build", "lsqt-cl"))
    os.makedirs(out_dir, exist_ok=True)
    rows = []
    warmed = set()
    print(f"{'study':10s} {'setting':28s} {'x':>7s} {'paths':>7s} {'cpu_s':>7s} {'wall_s':>7s} {'error':>9s} "
          f"{'floor':>8s} {'own_err':>9s} {'eff':>9s} {'own_eff':>9s}", flush=True)
    t_start = time.time()
    for study, label, series, x, case, text, a, paths, err_fn, wi in settings(quick):
        key = (text, tuple(a))
        if key not in warmed:  # fills the kernel cache: compile time is not the setting's
            run(binary, text, a, 100, 1, extra, wi)
            warmed.add(key)
        sq, own, cpu, wall = [], [], 0.0, 0.0
        for k in range(seeds):
            summary, info, c, w = run(binary, text, a, paths, 1 + k, extra, wi, True)
            if err_fn:
                sq += err_fn(case, summary, info)
            own.append(own_error(case, summary, info))
            cpu += c
            wall += w
        cpu, wall = cpu / seeds, wall / seeds
        err = math.sqrt(statistics.fmean(sq)) if sq else None
        own_err = math.sqrt(statistics.fmean(e * e for e in own))  # 0: an exact estimator (no noise)
        floor = ref_floor(case, albedo=not label.startswith("slab")) if case else None  # R and T, or R only
        row = {"study": study, "label": label, "series": series, "x": x, "paths": paths, "seeds": seeds,
               "cpu_s": cpu, "wall_s": wall, "error": err, "ref_floor": floor, "own_error": own_err,
               "efficiency": 1.0 / (err * err * cpu) if err else None,
               "own_efficiency": 1.0 / (own_err ** 2 * cpu) if own_err > 0 else None}
        rows.append(row)
        f = lambda v, spec: format(v, spec) if v is not None else "-"
        print(f"{study:10s} {label:28s} {x:7g} {paths:7d} {cpu:7.3f} {wall:7.3f} {f(err, '9.3e')} {f(floor, '8.1e')} "
              f"{own_err:9.3e} {f(row['efficiency'], '9.3g')} {f(row['own_efficiency'], '9.3g')}", flush=True)
    csv_path = os.path.join(out_dir, "study.csv")
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {csv_path} ({time.time() - t_start:.0f} s)")
    if doc:
        img_dir = os.path.join(ROOT, "docs", "speed-accuracy")
        os.makedirs(img_dir, exist_ok=True)
        files = plots(rows, img_dir)
        write_doc(rows, seeds, extra)
    else:
        files = plots(rows, out_dir)
    for p in files:
        print(f"wrote {p}")
    return 0


def write_doc(rows, seeds, extra):
    """docs/speed-accuracy.md: the measured tables and what they tell a user (every number
    in the text comes from the rows)."""
    binary = os.environ.get("LSQT_CL", os.path.join(ROOT, "build", "lsqt-cl"))
    dev = subprocess.run([binary, "--list-devices"], capture_output=True, text=True).stdout.strip().splitlines()
    by = {}
    for r in rows:
        by.setdefault(r["study"], []).append(r)
    g = lambda v, spec: format(v, spec) if v is not None else "—"

    def table(rs):
        t = ["| setting | paths | CPU-s | wall s | error (known answer) | its floor | own error | efficiency | own efficiency |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for r in rs:
            t.append(f"| {r['label']} | {r['paths']} | {r['cpu_s']:.3f} | {r['wall_s']:.3f} | {g(r['error'], '.2e')} | "
                     f"{g(r['ref_floor'], '.1e')} | {g(r['own_error'], '.2e')} | {g(r['efficiency'], '.3g')} | "
                     f"{g(r['own_efficiency'], '.3g')} |")
        return "\n".join(t)

    def at(label, paths=None):
        rs = [r for r in rows if r["label"] == label and (paths is None or r["paths"] == paths)]
        return max(rs, key=lambda r: r["paths"]) if rs else None

    ratio = lambda a, b, k: a[k] / b[k] if a and b and a[k] and b[k] else float("nan")
    sf, sd = at("slab float"), at("slab double")
    mf, md = at("ms conductor float"), at("ms conductor double")
    its = {k: at(f"iter_count {k}") for k in (1, 2, 6, 16)}
    best_it = max(its, key=lambda k: its[k]["own_efficiency"])
    on, off = at("multiple scattering on"), at("multiple scattering off")
    wis = sorted(by["wi"], key=lambda r: r["x"])
    rr = {r["label"]: r for r in by["rrss"]}
    slab_ps = sorted((r for r in by["precision"] if r["label"] == "slab float"), key=lambda r: r["paths"])
    fall = (slab_ps[0]["own_error"] / slab_ps[-1]["own_error"], math.sqrt(slab_ps[-1]["paths"] / slab_ps[0]["paths"]))
    text = f"""# Speed and accuracy: which settings buy how much accuracy per second

Generated by `tools/bench.sh study --doc` (`tools/bench_study.py`, {seeds} seeds per row); do
not edit by hand. Machine: {os.cpu_count()} cores, device `{dev[-1].strip() if dev else 'default'}`{(', flags ' + ' '.join(extra)) if extra else ''}.

**How to read it.** Two errors per setting, each the root mean square over the seeds:
- *error (known answer)*: (lsqt-cl − answer) / answer over the case's quantities. The answers
  are the validation suite's (`docs/validation.md`): iadpython for the slab's R and T
  (a slab of albedo 0.9, optical thickness 1, g 0.5 between Fresnel boundaries of index
  1.33, at 0° and 60°), the independent random walk of Heitz et al. (2016) for the rough
  conductor (alpha 1, index 1.1 + 2.6i) with multiple scattering, its quadrature for
  single scattering. For the conductor the quantity is each slice's albedo integrated from
  the stored point estimates over an even spread of `-wi` directions, so it measures what
  a user keeps. *its floor* is the answers' own uncertainty: an error near it says
  nothing more about lsqt-cl.
- *own error*: the run's own error bars, the relative standard error of R and T (slab)
  or the median one of the stored BSDF values (the others). lsqt-cl's estimates are
  unbiased (the validation suite's z-scores), so this is the error a user gets per
  direction.
Efficiency is 1 / (error² × CPU-s): twice the efficiency reaches the same error in half the
time. Monte Carlo error falls as 1 / sqrt(paths), so efficiency is flat in −p once start-up
(the OpenCL context and cached kernels, about 0.06 CPU-s) is small against the run, and
the settings compare at their largest −p. CPU-s is user + sys (the machine is shared);
each setting's kernels are cached by an untimed first run. Runs use multiples of 8192
paths: 32 batches of 256-path chunks, the fewest that give every batch, and so the error
bars, its paths.

![error against time: -p, float and double](speed-accuracy/error-time-precision.png)
![error against time: iter_count](speed-accuracy/error-time-iter_count.png)
![error against time: multiple scattering](speed-accuracy/error-time-scattering.png)
![efficiency per setting](speed-accuracy/efficiency.png)

## What it tells a user

- **−p** buys accuracy at the Monte Carlo rate: from {slab_ps[0]['paths']} to {slab_ps[-1]['paths']} paths the slab's
  own error falls {fall[0]:.2f}× (1/sqrt(paths) predicts {fall[1]:.2f}×) and the known-answer error
  {slab_ps[0]['error'] / slab_ps[-1]['error']:.2f}× (it is noisier: {seeds} seeds of 4 quantities). Below 8192 paths per slice a
  run has no error bars of its own, and start-up is a large share of a short run.
- **float, not double**: double costs {ratio(sd, sf, 'cpu_s'):.2f}× the CPU time on the slab and
  {ratio(md, mf, 'cpu_s'):.2f}× on the conductor for the same Monte Carlo error (own efficiency float/double
  {ratio(sf, sd, 'own_efficiency'):.2f} and {ratio(mf, md, 'own_efficiency'):.2f}). Float's rounding (1e-7 relative) is far below
  the error of any run a user makes; `--double` is for checking extreme parameters, not
  for accuracy per second.
- **iter_count** (walks per point estimate on a multiple-scattering microsurface): own
  efficiency at {its[1]['paths']} paths {', '.join(f'{k}: {its[k]["own_efficiency"]:.3g}' for k in its)}. On this rough
  conductor raising iter_count to {best_it} beats raising −p: more walks per vertex cut the point
  estimates' noise for less than the same number of extra paths costs (a path pays for its
  walk, its sampling and its other vertices). The known-answer error (iter_count 1 to 16:
  {', '.join(g(its[k]['error'], '.2e') for k in its)}, floor {g(its[1]['ref_floor'], '.1e')}) {'is within 1.5× of its floor from iter_count 6 on, so it does not separate the larger settings' if its[6]['error'] < 1.5 * its[6]['ref_floor'] else 'falls with iter_count too'}. The default (auto:
  6 for alpha > 0.5) is {'the best here' if best_it == 6 else 'not the best here: iter_count ' + str(best_it) + ' is more efficient'}.
- **Multiple scattering off** costs {ratio(off, on, 'cpu_s'):.2f}× the CPU time of on, and its point estimates are
  exact (analytic single scattering: no noise of their own); its error against its own
  answer is {g(off['error'], '.1e')} against {g(on['error'], '.1e')} with multiple scattering on. But off is not a speed
  setting: it drops the multiple scattering, {100 * (1 - 0.2281886 / 0.4106477):.0f} % of R at 45° for alpha 1, far more than
  any Monte Carlo error.
- **−wi** (even spread, −p 8192): {', '.join(f"-wi {r['x']:g}: {r['cpu_s']:.3f} CPU-s, albedo error {r['error']:.2e}" for r in wis)}. The
  point estimates' cost grows with the directions while the albedo of this smooth BSDF is
  resolved already by the fewest; store as many directions as the BSDF's detail needs
  (narrow lobes: RRSS, below), not more.
- **RRSS −wi and −rp** (the tutorial's Substr: no known answer, own errors): a longer pilot
  costs more, since it evaluates rx = 4 × −wi candidates for its share of the paths (−rp 0.1:
  {rr['Substr -wi 80 -rp 0.1']['cpu_s']:.2f} CPU-s, 0.3: {rr['Substr -wi 80 -rp 0.3']['cpu_s'] if 'Substr -wi 80 -rp 0.3' in rr else float('nan'):.2f}, 0.8: {rr['Substr -wi 80 -rp 0.8']['cpu_s']:.2f}), and leaves the stored
  values' error bars as they were (the pilot's tallies are kept): what it buys is where
  the directions go (docs/guide.md, "RRSS or the even spread"). −wi 300 costs
  {ratio(rr.get('Substr -wi 300 -rp 0.3'), rr.get('Substr -wi 80 -rp 0.3'), 'cpu_s'):.2f}× −wi 80 at the same per-direction error.

## Tables

### −p, float and double
{table(by['precision'])}

### iter_count (the multiple-scattering conductor)
{table(by['iter_count'])}

### Multiple scattering on and off (the conductor; off against the single-scattering answer)
{table(by['scattering'])}

### −wi (even spread, the conductor's albedo)
{table(sorted(by['wi'], key=lambda r: r['x']))}

### RRSS: −wi and −rp on Substr (own errors only)
{table(by['rrss'])}
"""
    path = os.path.join(ROOT, "docs", "speed-accuracy.md")
    old = open(path).read() if os.path.exists(path) else ""
    b, e = old.find("<!-- original:begin -->"), old.find("<!-- original:end -->")
    if 0 <= b < e:  # tools/bench_original.py's section (the original layered-sqt): kept as it is
        text = text.rstrip("\n") + "\n\n" + old[b:e + len("<!-- original:end -->")] + "\n"
    with open(path, "w") as f:
        f.write(text)
    print("wrote docs/speed-accuracy.md")


if __name__ == "__main__":
    sys.exit(main())
