#!/usr/bin/env python3
"""Memory: the peak RSS of a run against its bands and its grid, beside the size of the LSS
it writes and the run's own estimate of its peak (memory.h, what --max-memory judges;
docs/performance.md, "Memory").

    python3 tools/bench_memory.py [LSQT_CL] [-p PATHS] [--max-memory SIZE] [--csv PATH]

Every run is a Lambertian base (fR 0.6) with --wavelengths over 400 nm onwards in 10 nm
steps (or none for one band), -p PATHS (default 1000: the tallies' size does not depend on
the paths), seed 0, a fresh LSS. Cases: 1, 32 and 200 bands on the default grid (-wo 12
-wi 80, RRSS), 1051 bands at -wo 5, the grid -wo 90 -wi 1024 with 1 and 200 bands, 32
bands at 100000 paths and 200 at 10000 (every one of the 32 batches reached: the tallies'
full size).
--max-memory (default 6G) is passed on, so a case whose estimate exceeds it is refused by
lsqt-cl itself (exit 2, reported as such) instead of taking the machine's memory. Peak RSS
is the lsqt-cl process's ru_maxrss (os.wait4), after a run of the case at -p 1 has built its
kernels into PoCL's cache (a build of them adds LLVM's memory to the peak)."""
import argparse
import csv
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TEXT = "Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n"
# (label, bands, flags, paths: None for -p)
CASES = [
    ("default grid", 1, [], None),
    ("default grid", 32, [], None),
    ("default grid", 200, [], None),
    ("-wo 5", 1051, ["-wo", "5"], None),
    ("-wo 90 -wi 1024", 1, ["-wo", "90", "-wi", "1024"], None),
    ("-wo 90 -wi 1024", 200, ["-wo", "90", "-wi", "1024"], None),
    ("default grid, -p 100000", 32, [], 100000),
    ("default grid, -p 10000", 200, [], 10000),
]
UNITS = {"MB": 2**20, "GB": 2**30}


def run(exe, bands, flags, paths, max_memory, work):
    lsqt = os.path.join(work, "L.lsqt")
    with open(lsqt, "w") as f:
        f.write(TEXT)
    for name in os.listdir(work):
        if name != "L.lsqt":
            os.unlink(os.path.join(work, name))
    cmd = [exe, lsqt, "-p", str(paths), "-s", "0", "-R", "-v", "--max-memory", max_memory,
           "-o", os.path.join(work, "o.raw"), "--lss", os.path.join(work, "o.lss")] + flags
    if bands > 1:
        cmd += ["--wavelengths", "400:%d:10" % (400 + 10 * (bands - 1))]
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = p.stderr.read()
    _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    m = re.search(r"(?:memory: about|need about) ([0-9.]+) (MB|GB)", err)
    est = float(m.group(1)) * UNITS[m.group(2)] / 2**20 if m else float("nan")
    lss = os.path.join(work, "o.lss")
    size = os.path.getsize(lss) / 2**20 if p.returncode == 0 and os.path.exists(lss) else float("nan")
    return {"rc": p.returncode, "rss_mb": ru.ru_maxrss / 1024, "lss_mb": size, "estimate_mb": est,
            "cmd": " ".join(os.path.basename(c) if c.startswith(work) else c for c in cmd[1:])}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("exe", nargs="?", default=os.path.join(ROOT, "build", "lsqt-cl"))
    ap.add_argument("-p", type=int, default=1000)
    ap.add_argument("--max-memory", default="6G")
    ap.add_argument("--csv")
    a = ap.parse_args()
    rows = []
    print("| case | bands | peak RSS (MB) | LSS (MB) | 2 LSS + 300 MB | estimate (MB) | exit |")
    print("|---|---:|---:|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as work:
        for label, bands, flags, paths in CASES:
            run(a.exe, bands, flags, 1, a.max_memory, work)  # the kernel cache
            r = run(a.exe, bands, flags, paths or a.p, a.max_memory, work)
            r.update(case=label, bands=bands)
            rows.append(r)
            refused = r["rc"] == 2
            print("| %s | %d | %s | %s | %s | %.0f | %s |" % (
                label, bands, "-" if refused else "%.0f" % r["rss_mb"],
                "-" if refused else "%.1f" % r["lss_mb"],
                "-" if refused else "%.0f" % (2 * r["lss_mb"] + 300), r["estimate_mb"],
                "refused (--max-memory %s)" % a.max_memory if refused else r["rc"]), flush=True)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
    return 0 if all(r["rc"] in (0, 2) for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
