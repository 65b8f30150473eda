#!/usr/bin/env python3
"""The validation suite's reference numbers (tests/data/validation_fixtures.json, written by
tools/validate/validate.py --write-fixtures from closed forms, iadpython, mitsuba and an
independent numpy random walk) against lsqt-cl at each case's fixture_paths, with the
standard library only: no network, no PyPI package.

    test_fixtures.py [--double] [--group NAME] [--every N] LSQT_CL [FIXTURES]

(--every N: every N-th case only; the sanitizer build, where each process costs seconds.
--double: every case in double precision, --group NAME: only the cases of that reference
group; for the power test of the double path, test_fixtures.double.)

Each row: z = (lsqt-cl - reference) / sqrt(std_err^2 + ref_err^2). The seeds are fixed, so
the result is reproducible; the tolerance is a family one: all rows together fail by
chance with probability 1e-3 (two-sided normal, Bonferroni over the rows: |z| about 4.6
for 300 rows). Rows the suite marks as known limitations are printed, not judged."""
import json
import math
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools", "validate"))
import common  # noqa: E402


def z_family(n, alpha=1e-3):
    """|z| whose two-sided normal tail is alpha / n (bisection on erfc)."""
    lo, hi = 0.0, 40.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if math.erfc(mid / math.sqrt(2)) > alpha / n:
            lo = mid
        else:
            hi = mid
    return hi


def main():
    argv, extra, group = sys.argv[1:], [], None
    while argv[:1] in (["--double"], ["--group"]):
        if argv[0] == "--double":
            extra, argv = ["--double"], argv[1:]
        else:
            group, argv = argv[1], argv[2:]
    every, binary, path = common.test_args(argv, "test_fixtures.py [--double] [--group NAME] [--every N] LSQT_CL [FIXTURES]")
    path = path or os.path.join(ROOT, "tests", "data", "validation_fixtures.json")
    cases = [c for c in json.load(open(path))["cases"] if group is None or c["group"] == group]
    if extra:  # leave out the cases that run in double anyway (test_fixtures has them)
        cases = [c for c in cases if "--double" not in c.get("args", [])]
    cases = cases[::every]
    n_rows = sum(len(c["checks"]) for c in cases)
    zmax = z_family(n_rows)
    common.Z_MAX = zmax
    print(f"{len(cases)} cases, {n_rows} rows; |z| <= {zmax:.2f} (family 1e-3)" + (" in double" if extra else ""))
    print(common.HEADER)
    t0 = time.time()
    failed = passed = known = 0
    worst = 0.0
    groups = {}
    for c in cases:
        t = time.time()
        for r in common.rows_of_case(c, c["fixture_paths"], binary, extra):
            print(common.format_row(r), flush=True)
            if r["verdict"] == "known":
                known += 1
                continue
            worst = max(worst, abs(r["z"]))
            if r["verdict"] == "pass":
                passed += 1
            else:
                failed += 1
        groups[c["group"]] = groups.get(c["group"], 0.0) + time.time() - t
    print("seconds per group: " + ", ".join(f"{g} {s:.1f}" for g, s in groups.items()))
    print(f"largest |z| {worst:.2f}; {time.time() - t0:.1f} s")
    print(f"{passed} passed, {failed} failed, {known} skipped")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
