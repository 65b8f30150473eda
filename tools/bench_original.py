#!/usr/bin/env python3
"""The original layered-sqt (M. Grady Saunders, 2020) beside lsqt-cl: CPU time per path
and error per CPU-second, on the tutorial's six assemblies and a scattering slab.

    python3 tools/bench_original.py ORIGINAL LSQT_CL [--doc] [--k K] [--ref R] [--cases A,B]
    (ORIGINAL from tools/original/build.sh DEST; or tools/bench.sh original ORIGINAL [--doc])

Per case, in a temporary folder:
1. the original at its defaults (src/main.cpp: -p 10000 -wo 12 -wi 80 -rx 4 -rp 0.8 -s 0),
   given explicitly, with -t 2, once;
2. lsqt-cl at its defaults, the same but for the RRSS pilot's share (-rp 0.3, not 0.8), with
   K times the paths (default 100; after an untimed run that fills the kernel cache), its
   own error bars from `lsqt-cl info --json --bsdf`;
3. the reference: lsqt-cl per slice at the original's own directions (`--wo-angles`,
   `--wi-file`), R times the original's paths (default 100), so its noise is small
   against the original's error.
CPU-s are user + sys of the child (getrusage), beside wall time: the machine may be shared.

The original reads a stricter dialect of the same language: the short model names
(Lambertian, not LambertianBsdf; HenyeyGreenstein, not HenyeyGreensteinPhase), no comments
or blank lines. Both programs get that text (lsqt-cl reads the short names as aliases),
with use_multiple_scattering written out at the original's defaults, since its
MicrosurfaceDielectric defaults to false where lsqt-cl's defaults to true.

Errors (relative, the median over all stored directions of all slices, f_ref > 0):
- the original: |f_orig - f_ref| / f_ref, measured;
- lsqt-cl: its relative standard error, times 0.674 (the median of |N(0, 1)|) to give the
  median |error| it implies, so both columns are the same statistic.
At 1 CPU-s: error * sqrt(cpu_s), assuming error ~ 1/sqrt(time). Efficiency 1/(err^2 cpu_s);
the ratio is lsqt-cl's over the original's. Lambertian.lsqt checks first that both RAWs mean
the same (f, not f cos, 1/sr): its BSDF is fR/pi at every direction in both programs.
"""
import json
import math
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TUTORIAL = ["Lambertian", "Dust", "Dusty", "Silver", "Substr", "Rough"]
SLAB = "Medium\nLayer z=1 NullBsdf\nMedium mus=0.9 mua=0.1 HenyeyGreensteinPhase g=0.8\nLayer z=0 NullBsdf\nMedium\n"
ORIG_P, ORIG_WO = 10000, 12
SETTINGS = ["-wo", "12", "-wi", "80", "-rx", "4", "-rp", "0.8", "-s", "0", "-t", "2"]  # the original's defaults
LSQT_SETTINGS = ["-wo", "12", "-wi", "80", "-s", "0", "-t", "2"]  # lsqt-cl's defaults (-rx 4, -rp 0.3)
NAMES = {"NullBsdf": "Null", "LambertianBsdf": "Lambertian", "OrenNayarDiffuseBrdf": "OrenNayarDiffuse",
         "MicrosurfaceLambertianBrdf": "MicrosurfaceLambertian", "MicrosurfaceDielectricBsdf": "MicrosurfaceDielectric",
         "MicrosurfaceConductiveBrdf": "MicrosurfaceConductive", "HenyeyGreensteinPhase": "HenyeyGreenstein",
         "HenyeyGreenstein2Phase": "HenyeyGreenstein2", "RayleighPhase": "Rayleigh", "SggxPhase": "Sggx"}
ORIG_MS = {"MicrosurfaceLambertian": "true", "MicrosurfaceDielectric": "false", "MicrosurfaceConductive": "false"}
MEDIAN_ABS_NORMAL = 0.6745


def original_text(text):
    """The LSQT text in the original's dialect, multiple scattering explicit."""
    out = []
    for line in text.splitlines():
        toks = [NAMES.get(t, t) for t in line.split("#")[0].split()]
        model = next((t for t in toks if t in ORIG_MS), None)
        if model and not any(t.startswith("use_multiple_scattering=") for t in toks):
            toks.append("use_multiple_scattering=" + ORIG_MS[model])
        if toks:
            out.append(" ".join(toks))
    return "\n".join(out) + "\n"


def timed(cmd, cwd, log):
    """Runs cmd; returns (cpu_s, wall_s) of it."""
    print("  $ " + " ".join(cmd), flush=True)
    r0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.time()
    with open(log, "w") as f:
        p = subprocess.run(cmd, cwd=cwd, stdin=subprocess.DEVNULL, stdout=f, stderr=subprocess.STDOUT)
    wall, r1 = time.time() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode:
        sys.exit(f"bench_original: exit {p.returncode}: {' '.join(cmd)}\n{open(log).read()[-2000:]}")
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), wall


def run_original(binary, text, d):
    """The original in d (it writes c.raw and c.lsqt.lss beside its input; its -o is
    unusable: with -o it never opens the input). Returns (cpu, wall, slices, thetas)."""
    with open(os.path.join(d, "c.lsqt"), "w") as f:
        f.write(text)
    cpu, wall = timed([binary, "-p", str(ORIG_P), *SETTINGS, "c.lsqt"], d, os.path.join(d, "orig.log"))
    lines = open(os.path.join(d, "c.raw")).read().split("\n")
    thetas = [float(x) for x in lines[2].split()[1:]]
    rows = [l.split() for l in lines[3:] if l.strip()]
    slices = [[] for _ in thetas]
    for a, b in zip(rows[::2], rows[1::2]):  # each estimate twice: (x, y, z), then (x, -y, z)
        assert a[0] == b[0] and float(a[2]) == -float(b[2]), (a, b)
        slices[int(a[0])].append((float(a[1]), abs(float(a[2])), float(a[3]), float(a[4])))
    return cpu, wall, slices, thetas


def run_lsqt(binary, text, args, d, tag):
    """lsqt-cl in d; returns (cpu, wall, info of `lsqt-cl info --json --bsdf`)."""
    src, out = os.path.join(d, "c.lsqt"), os.path.join(d, tag)
    with open(src, "w") as f:
        f.write(text)
    cpu, wall = timed([binary, "-q", "-R", *args, "--lss", out + ".lss", "-o", out + ".raw", src], d, out + ".log")
    subprocess.run([binary, "info", out + ".lss", "--json", out + ".json", "--bsdf"], check=True,
                   stdout=subprocess.DEVNULL)
    with open(out + ".json") as f:
        return cpu, wall, json.load(f)


def bench(orig, lsqt, name, text, k, ref):
    print(f"{name}:", flush=True)
    with tempfile.TemporaryDirectory() as d:
        o_cpu, o_wall, o_slices, thetas = run_original(orig, text, d)
        run_lsqt(lsqt, text, ["-p", "1000", *LSQT_SETTINGS], d, "warm")  # fills the kernel cache
        l_cpu, l_wall, info = run_lsqt(lsqt, text, ["-p", str(k * ORIG_P), *LSQT_SETTINGS], d, "lsqt")
        pairs = []  # (f_orig, f_ref, stderr_ref)
        for s, dirs in enumerate(o_slices):
            deg = s / ORIG_WO * 0.99 * 90  # the original's theta_o (src/file_data.cpp)
            assert abs(math.radians(deg) - thetas[s]) < 1e-5
            wi = os.path.join(d, f"wi{s}.txt")
            with open(wi, "w") as f:
                f.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z, _ in dirs)
            _, _, ri = run_lsqt(lsqt, text, ["-p", str(ref * ORIG_P), "-s", "1", "-t", "2", f"--wo-angles={deg!r}",
                                             "--wi-file", wi], d, f"ref{s}")
            est = ri["slices"][0]["bsdf"]
            assert len(est) == len(dirs) and all(abs(e[0] - x) < 1e-5 and abs(e[2] - z) < 1e-5
                                                 for e, (x, _, z, _) in zip(est, dirs))
            pairs += [(fo, e[3], e[4] or 0.0) for (_, _, _, fo), e in zip(dirs, est)]
    pairs = [p for p in pairs if p[1] > 0]
    own = [e[4] / e[3] for s in info["slices"] for e in s["bsdf"] if e[3] > 0 and e[4] is not None]
    r = {"case": name, "o_cpu": o_cpu, "o_wall": o_wall, "o_paths": ORIG_P * ORIG_WO,
         "l_cpu": l_cpu, "l_wall": l_wall, "l_paths": k * ORIG_P * ORIG_WO, "n": len(pairs),
         "o_err": statistics.median(abs(fo - fr) / fr for fo, fr, _ in pairs),
         "o_bias": statistics.median((fo - fr) / fr for fo, fr, _ in pairs),
         "ref_err": statistics.median(sr / fr for _, fr, sr in pairs),
         "l_stderr": statistics.median(own) if own else 0.0}
    if name == "Lambertian":  # both RAWs hold f (1/sr), not f cos: fR / pi everywhere
        worst = max(max(abs(fo * math.pi / 0.6 - 1), abs(fr * math.pi / 0.6 - 1)) for fo, fr, _ in pairs)
        print(f"  convention check: max |f / (0.6/pi) - 1| = {worst:.1e} (original and reference)")
        if worst > 1e-4:
            sys.exit("bench_original: the two RAWs disagree on Lambertian.lsqt (f vs f cos?)")
    if name == "Silver":  # no noise in either, a narrow lobe: the same directions and mirror convention
        print(f"  convention check: median |f_orig / f_ref - 1| = {r['o_err']:.1e}")
    r["l_err"] = MEDIAN_ABS_NORMAL * r["l_stderr"]
    r["o_pp"], r["l_pp"] = o_cpu / r["o_paths"], l_cpu / r["l_paths"]
    r["speed"] = r["o_pp"] / r["l_pp"]
    r["o_1s"], r["l_1s"] = r["o_err"] * math.sqrt(o_cpu), r["l_err"] * math.sqrt(l_cpu)
    # below 1e-5 the error is RAW's rounding (the original writes 6 digits): no noise to compare
    r["eff"] = r["o_1s"] ** 2 / r["l_1s"] ** 2 if r["o_err"] > 1e-5 and r["l_err"] > 0 else None
    r["biased"] = abs(r["o_bias"]) > 0.5 * r["o_err"] > 1e-5  # noise alone: |signed median| << median |err|
    print("  original %.2f CPU-s (%.2f wall), lsqt-cl %.2f CPU-s (%.2f wall); CPU per path ratio %.1f; median "
          "|rel err| original %.2e (signed %+.1e, reference %.1e), lsqt-cl %.2e; efficiency ratio %s"
          % (o_cpu, o_wall, l_cpu, l_wall, r["speed"], r["o_err"], r["o_bias"], r["ref_err"], r["l_err"],
             "n/a" if r["eff"] is None else "%.3g" % r["eff"] + " (the original biased)" * r["biased"]), flush=True)
    return r


def table(rows):
    g = lambda v, spec: "n/a" if v is None else format(v, spec)
    t = ["| case | original CPU-s | its paths | lsqt-cl CPU-s | its paths | original CPU-µs/path | lsqt-cl CPU-µs/path "
         "| CPU/path ratio | original median \\|rel err\\| | its signed median | reference's rel stderr | lsqt-cl median "
         "\\|rel err\\| (0.674 σ) | original at 1 CPU-s | lsqt-cl at 1 CPU-s | efficiency ratio |",
         "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        t.append(f"| {r['case']} | {r['o_cpu']:.2f} | {r['o_paths']:.3g} | {r['l_cpu']:.2f} | {r['l_paths']:.3g} | "
                 f"{r['o_pp'] * 1e6:.3g} | {r['l_pp'] * 1e6:.3g} | {r['speed']:.3g} | {r['o_err']:.2e} | "
                 f"{r['o_bias']:+.1e} | {r['ref_err']:.1e} | {r['l_err']:.2e} | {r['o_1s']:.2e} | {r['l_1s']:.2e} | "
                 f"{g(r['eff'], '.3g')}{' †' * r['biased']} |")
    return "\n".join(t)


def write_doc(rows, k, ref, orig, cases):
    lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    model = (re.search(r"^Model name:\s*(.*)$", lscpu, re.M) or [None, "?"])[1].strip()
    block = f"""<!-- original:begin -->
## Beside the original layered-sqt

Written by `python3 tools/bench_original.py ORIGINAL build/lsqt-cl --doc` (`tools/bench.sh
original ORIGINAL --doc`); not by bench_study. The original (M. Grady Saunders, 2020, at
commit 2ec931b, preform f06367ac) built by `tools/original/build.sh /tmp/orig` (Release,
upstream's `-O2 -march=native`, one include added for g++ 12). Machine: {model},
{os.cpu_count()} cores, shared (hence CPU-s, user + sys, beside wall).

**How to read it.** Each case runs the original once at its defaults (`-p {ORIG_P} -wo 12 -wi 80
-rx 4 -rp 0.8 -s 0`, `-t 2`) and lsqt-cl at its defaults (the same, but for the RRSS pilot's
share, `-rp 0.3`) with {k} times the paths. *CPU/path ratio*:
the original's CPU-s per path over lsqt-cl's. The original's error is measured: |f − f_ref| /
f_ref against a reference run by lsqt-cl at the original's own directions, slice by slice
(`--wo-angles`, `--wi-file`, {ref} times the original's paths; *reference's rel stderr* is its
own noise), the median over all directions; *its signed median* near 0 says the
difference is noise, not a different model. lsqt-cl's is its own error bars (median relative
standard error × 0.674, the median |error| they imply). *at 1 CPU-s*: error × √(CPU-s), what
one CPU-second buys if error falls as 1/√time. *efficiency ratio*: lsqt-cl's 1/(err² · CPU-s)
over the original's, i.e. how many times fewer CPU-seconds lsqt-cl needs for the same error.
Lambertian and Silver (single scattering, analytic) have no noise in either program: the
original's error is its RAW's 6-digit rounding, so their ratio is n/a. † The original's
error is mostly bias (its signed median is over half its median |error|): more
paths would not reduce it, so its efficiency is worse than the ratio says. The cause, in
the original's `LayeredAssembly::compute` (src/layered_assembly.cpp): a path that crosses
a layer (a NullBsdf) and reaches the next non-null layer unscattered takes the layers
above it from the layer it sat on, so the next-event estimate at that layer omits the
medium's transmittance on the way out. A medium under a null layer over a reflector reads
high: Dust (lossless) reflects about 1.28 at normal incidence in the original, 1 in lsqt-cl;
with `Medium mua=1` over a white Lambertian the original's values are e^(1/cos θi) times
too large. Rough's large ratio is mostly lsqt-cl's `iter_count` (auto: 6 random walks per
estimate at alpha 2.4; the original makes 1), which lowers the error per path.

{table(rows)}

Both programs read the original's dialect of the input (short model names, no comments;
`use_multiple_scattering` written out, since the original's MicrosurfaceDielectric defaults
to false and lsqt-cl's to true). Commands, per case in a temporary folder:

<!-- doc-test: skip it needs the original layered-sqt (tools/original/build.sh) and an hour -->
```sh
tools/original/build.sh /tmp/orig
python3 tools/bench_original.py {orig} build/lsqt-cl --doc --k {k} --ref {ref} --cases {','.join(cases)}
# in it, per case (c.lsqt; the original's -o skips opening its input, so it writes c.raw):
ORIGINAL -p {ORIG_P} {' '.join(SETTINGS)} c.lsqt
lsqt-cl -q -R -p {k * ORIG_P} {' '.join(LSQT_SETTINGS)} --lss lsqt.lss -o lsqt.raw c.lsqt  # after -p 1000 untimed
lsqt-cl info lsqt.lss --json lsqt.json --bsdf
lsqt-cl -q -R -p {ref * ORIG_P} -s 1 -t 2 --wo-angles=THETA_k --wi-file wiK.txt --lss refK.lss -o refK.raw c.lsqt  # k = 0..11
```
<!-- original:end -->
"""
    path = os.path.join(ROOT, "docs", "speed-accuracy.md")
    old = open(path).read() if os.path.exists(path) else ""
    b, e = old.find("<!-- original:begin -->"), old.find("<!-- original:end -->")
    if 0 <= b < e:
        old = old[:b] + old[e + len("<!-- original:end -->"):].lstrip("\n")
    with open(path, "w") as f:
        f.write(old.rstrip("\n") + "\n\n" + block)
    print(f"wrote {path}")


def main():
    args = sys.argv[1:]
    opt = lambda k, d: args[args.index(k) + 1] if k in args else d
    pos = [a for i, a in enumerate(args) if not a.startswith("--") and (i == 0 or args[i - 1] not in ("--k", "--ref", "--cases"))]
    if len(pos) != 2:
        sys.exit(__doc__)
    orig, lsqt = (os.path.abspath(p) for p in pos)
    k, ref = int(opt("--k", "100")), int(opt("--ref", "100"))
    cases = opt("--cases", ",".join(TUTORIAL + ["slab"])).split(",")
    rows, stamp = [], os.stat(lsqt).st_mtime
    for name in cases:
        text = SLAB if name == "slab" else open(os.path.join(ROOT, "examples", "tutorial", name + ".lsqt")).read()
        rows.append(bench(orig, lsqt, name, original_text(text), k, ref))
    print(table(rows))
    if os.stat(lsqt).st_mtime != stamp:
        sys.exit(f"bench_original: {lsqt} changed during the run (rebuilt?): run again")
    if "--doc" in args:
        write_doc(rows, k, ref, pos[0], cases)
    return 0


if __name__ == "__main__":
    sys.exit(main())
