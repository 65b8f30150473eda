#!/usr/bin/env python3
"""RRSS against the even spread on error per second.

What a renderer sees is the BSDF between the RAW's directions, so the error measured is
that of the BSDF rebuilt from the RAW (nearest RAW direction of the slice, both mirror
images) against a reference, in reflected energy:

    E = integral |f_rebuilt - f_ref| |cos| dw / integral f_ref |cos| dw   (per slice)

The integrals are estimated at test directions drawn, with a fixed seed, from a mixture
of the uniform density on the domain and Gaussian caps (8 deg) around the slice's peaks
(the largest RAW values of each hemisphere in a pilot run), weighted by 1 / density, so a
narrow lobe is resolved. The reference is a --wi-file run at exactly the test directions
(one per slice, --wo-angles) with many paths. Per method and -p: E over the slices (rms),
the run's seconds, and efficiency = 1 / (E^2 * seconds): higher is better.

usage: tools/rrss_bench.py LSQT_CL FILE [PATHS...]   (default: 2e4 1e5)
environment: LSQT_FLAGS (default "-wo 4 -wi 80"), LSQT_REF_PATHS (default 4e5),
             LSQT_TESTS (test directions per slice, default 900), LSQT_RRSS_FLAGS (more
             flags for the RRSS runs, e.g. "-rp 0.3"; several sets apart by ';' compare
             them: "-rp 0.8;-rp 0.3").
Where the rebuilt BSDF's error is mostly that of the directions' placement (a narrow lobe),
E does not fall with more paths: compare E at equal seconds, not the efficiency."""
import json, math, os, random, subprocess, sys, tempfile

SIGMA = math.radians(8.0)


def read_raw(path):
    lines = open(path).read().split("\n")
    n = int(lines[2].split()[0])
    thetas = [float(t) for t in lines[2].split()[1:1 + n]]
    pts = [[] for _ in range(n)]
    for l in lines[3:]:
        if l.strip():
            s, x, y, z, v = l.split()[:5]
            pts[int(s)].append((float(x), float(y), float(z), float(v)))
    return thetas, pts


def frame(a):
    """Two unit vectors orthogonal to a."""
    t = (1.0, 0.0, 0.0) if abs(a[0]) < 0.9 else (0.0, 1.0, 0.0)
    u = (a[1] * t[2] - a[2] * t[1], a[2] * t[0] - a[0] * t[2], a[0] * t[1] - a[1] * t[0])
    n = math.sqrt(sum(c * c for c in u))
    u = tuple(c / n for c in u)
    v = (a[1] * u[2] - a[2] * u[1], a[2] * u[0] - a[0] * u[2], a[0] * u[1] - a[1] * u[0])
    return u, v


def cap_pdf(w, a):
    """Solid-angle density of the Gaussian cap around a (Rayleigh angle, uniform azimuth)."""
    c = max(-1.0, min(1.0, sum(p * q for p, q in zip(w, a))))
    th = math.acos(c)
    if th < 1e-9:
        return 1.0 / (2 * math.pi * SIGMA * SIGMA)
    return th / (SIGMA * SIGMA) * math.exp(-th * th / (2 * SIGMA * SIGMA)) / (2 * math.pi * math.sin(th))


def test_dirs(peaks, sphere, n, rng):
    """n directions with y >= 0 off the horizon, and the (mirror-folded) mixture density."""
    domain = 4 * math.pi if sphere else 2 * math.pi
    comps = 1 + len(peaks)
    out = []
    while len(out) < n:
        k = rng.randrange(comps)
        if k == 0:
            z = rng.uniform(-1.0, 1.0) if sphere else rng.uniform(0.0, 1.0)
            ph = rng.uniform(0, 2 * math.pi)
            r = math.sqrt(max(0.0, 1 - z * z))
            w = (r * math.cos(ph), r * math.sin(ph), z)
        else:
            a = peaks[k - 1]
            th = SIGMA * math.sqrt(-2 * math.log(1 - rng.random()))
            if th >= math.pi:
                continue
            ph = rng.uniform(0, 2 * math.pi)
            u, v = frame(a)
            w = tuple(math.cos(th) * a[i] + math.sin(th) * (math.cos(ph) * u[i] + math.sin(ph) * v[i]) for i in range(3))
        if abs(w[2]) < 2e-3 or (not sphere and w[2] < 0):
            continue
        w = (w[0], abs(w[1]), w[2])
        m = (w[0], -w[1], w[2])
        p = 0.0
        for x in (w, m):
            p += (1.0 / domain) / comps
            for a in peaks:
                p += cap_pdf(x, a) / comps
        out.append((w, p))
    return out


def run(binp, args):
    subprocess.run([binp, "-q", "-R", *args], check=True, stdout=subprocess.DEVNULL)


def main():
    binp, f = sys.argv[1], os.path.abspath(sys.argv[2])
    paths = sys.argv[3:] or ["2e4", "1e5"]
    flags = os.environ.get("LSQT_FLAGS", "-wo 4 -wi 80").split()
    ref_paths = os.environ.get("LSQT_REF_PATHS", "4e5")
    n_tests = int(os.environ.get("LSQT_TESTS", "900"))
    work = tempfile.mkdtemp()
    o = lambda name: os.path.join(work, name)
    # A pilot run: the slices' angles, whether the stack transmits, and its peaks.
    run(binp, ["-p", "2e4", *flags, "--lss", o("p.lss"), "-o", o("p.raw"), "--json", o("p.json"), f])
    thetas, pts = read_raw(o("p.raw"))
    sphere = any(q[2] < 0 for q in pts[0])  # RAWBS: directions below the horizon too
    rng = random.Random(12345)
    tests, refs = [], []
    for s, th in enumerate(thetas):
        peaks = []
        for up in ((True, False) if sphere else (True,)):
            h = [q for q in pts[s] if (q[2] > 0) == up]
            if h:
                b = max(h, key=lambda q: q[3])
                peaks.append((b[0], abs(b[1]), b[2]))
        t = test_dirs(peaks, sphere, n_tests, rng)
        tests.append(t)
        with open(o("t%d.txt" % s), "w") as fh:
            for w, _ in t:
                fh.write("%.9f %.9f %.9f\n" % w)
        run(binp, ["-p", ref_paths, "--wo-angles=%.12f" % math.degrees(th), "--wi-file", o("t%d.txt" % s),
                   "-s", "99", "--lss", o("r.lss"), "-o", o("r.raw"), f])
        _, rp = read_raw(o("r.raw"))
        # the RAW holds both mirror images: the reference is the y >= 0 one of each test
        ref = {}
        for q in rp[0]:
            if q[1] >= 0:
                ref[(round(q[0], 5), round(q[1], 5), round(q[2], 5))] = q[3]
        vals = []
        for w, _ in t:
            key = (round(w[0], 5), round(w[1], 5), round(w[2], 5))
            best = ref.get(key)
            if best is None:  # rounding at the 5th digit: the nearest one
                best = min(rp[0], key=lambda q: -(q[0] * w[0] + q[1] * w[1] + q[2] * w[2]))[3]
            vals.append(best)
        refs.append(vals)
    print("reference: %s paths per slice at %d test directions per slice; %s" % (ref_paths, n_tests, " ".join(flags)))
    print("%-16s %-8s %10s %9s %9s %12s" % ("method", "paths", "E (rms)", "seconds", "CPU s", "efficiency"))
    sets = os.environ.get("LSQT_RRSS_FLAGS", "").split(";")
    methods = [(("rrss " + fl.strip()).strip(), fl.split()) for fl in sets] + [("spread", ["--wi-spread"])]
    for p in paths:
        for method, extra in methods:
            t0 = os.times()
            run(binp, ["-p", p, *flags, *extra, "--lss", o("m.lss"), "-o", o("m.raw"), "--json", o("m.json"), f])
            t1 = os.times()
            cpu = (t1.children_user - t0.children_user) + (t1.children_system - t0.children_system)
            secs = json.load(open(o("m.json")))["seconds"]
            _, mp = read_raw(o("m.raw"))
            e2 = []
            for s in range(len(thetas)):
                num = den = 0.0
                for (w, pd), fr in zip(tests[s], refs[s]):
                    near = max(mp[s], key=lambda q: q[0] * w[0] + q[1] * w[1] + q[2] * w[2])
                    num += abs(near[3] - fr) * abs(w[2]) / pd
                    den += fr * abs(w[2]) / pd
                e2.append((num / den) ** 2 if den > 0 else float("nan"))
            e = math.sqrt(sum(e2) / len(e2))
            print("%-16s %-8s %10.4g %9.3f %9.2f %12.4g" % (method, p, e, secs, cpu, 1 / (e * e * secs) if e > 0 else float("inf")))


if __name__ == "__main__":
    main()
