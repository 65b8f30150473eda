#!/usr/bin/env python3
"""RRSS against the even spread on error per second (issue 10).

The error is that of the directional albedo rebuilt from the RAW point estimates, which is
what a renderer or raw2sqt sees: R' = sum f_i |cos| A_i over each hemisphere, with A_i the
share of the hemisphere nearest to direction i (A_i proportional to 1 / its 6-nearest-
neighbour density, summing to 2 pi). It is compared with R (and T - delta_T) from the exit
tallies of the same run, which need no directions. Per method and -p: the mean of
(R' - R)^2 over slices and hemispheres, the seconds of the run, and
efficiency = 1 / (mean err^2 * seconds).
usage: tools/rrss_bench.py LSQT_CL FILE [PATHS...] (default 2e4 1e5); extra lsqt-cl
flags from LSQT_FLAGS (default: -wo 4 -wi 80)."""
import json, math, os, subprocess, sys, tempfile


def rebuild(raw):
    lines = open(raw).read().split("\n")
    n = int(lines[2].split()[0])
    pts = [[] for _ in range(n)]
    for l in lines[3:]:
        if l.strip():
            s, x, y, z, v = l.split()[:5]
            pts[int(s)].append((float(x), float(y), float(z), float(v)))
    out = []
    for p in pts:
        res = []
        for up in (1, 0):
            h = [q for q in p if (q[2] > 0) == bool(up)]
            if len(h) < 8:
                res.append(0.0 if not h else float("nan"))
                continue
            inv = []
            for a in h:
                d = sorted(-(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) for b in h if b is not a)[5]
                cap = 2 * math.pi * (1 + min(d, -1e-12) * 1) if False else 2 * math.pi * (1 - min(-d, 1.0))
                inv.append(cap / 6)  # 1 / density, up to a constant
            tot = sum(inv)
            res.append(sum(q[3] * abs(q[2]) * 2 * math.pi * w / tot for q, w in zip(h, inv)))
        out.append(res)
    return out


def main():
    binp, f = sys.argv[1], sys.argv[2]
    paths = sys.argv[3:] or ["2e4", "1e5"]
    flags = os.environ.get("LSQT_FLAGS", "-wo 4 -wi 80").split()
    work = tempfile.mkdtemp()
    print("%-8s %-8s %12s %9s %12s" % ("method", "paths", "mean err^2", "seconds", "efficiency"))
    for p in paths:
        for method, extra in (("rrss", []), ("spread", ["--wi-spread"])):
            raw, js = os.path.join(work, "o.raw"), os.path.join(work, "o.json")
            subprocess.run([binp, "-q", "-R", "-p", p, *flags, *extra, "--lss", os.path.join(work, "o.lss"), "-o", raw,
                            "--json", js, f], check=True)
            j = json.load(open(js))
            est = rebuild(raw)
            e2 = []
            for s, (ru, rd) in zip(j["slices"], est):
                e2.append((ru - s["R"]) ** 2)
                if s["T"] > 0:
                    e2.append((rd - (s["T"] - s["delta_T"])) ** 2)
            m = sum(e2) / len(e2)
            print("%-8s %-8s %12.3g %9.3f %12.4g" % (method, p, m, j["seconds"], 1 / (m * j["seconds"]) if m > 0 else float("inf")))


if __name__ == "__main__":
    main()
