#!/usr/bin/env python3
"""The docs' commands run as written: every ```sh block of README.md and docs/*.md, each in
a fresh folder of its own (so one block cannot lean on another's files), under bash -e
with the build's programs first on PATH, and must exit 0.

The folder holds a copy of the source's examples/ as ./examples, unless the line before
the block says otherwise:
  <!-- doc-test: cwd examples/tutorial -->   the folder is a copy of that folder
  <!-- doc-test: skip REASON -->             not run here (a cluster, two GPUs, the
                                             installed tree, a tool this machine lacks);
                                             the reason is printed
Blocks in other languages (python: xarray, Mitsuba) are listed as not run.

usage: test_docs.py BUILD_DIR [FILE.md ...]   (default: README.md and docs/*.md)
"""
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DIRECTIVE = re.compile(r"^<!-- doc-test: (skip|cwd) ?(.*?) -->$")


def blocks(path):
    """(line, language, directive, argument, text) of every fenced block of PATH."""
    lines = open(path, encoding="utf-8").read().split("\n")
    out, i = [], 0
    while i < len(lines):
        m = re.match(r"^```(\S*)", lines[i])
        if not m:
            i += 1
            continue
        lang, start = m.group(1), i
        j = i + 1
        while j < len(lines) and not lines[j].startswith("```"):
            j += 1
        d = DIRECTIVE.match(lines[start - 1]) if start > 0 else None
        out.append((start + 1, lang, d.group(1) if d else None, d.group(2) if d else "", "\n".join(lines[start + 1:j])))
        i = j + 1
    return out


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    build = os.path.abspath(sys.argv[1])
    files = sys.argv[2:] or [os.path.join(ROOT, "README.md")] + sorted(glob.glob(os.path.join(ROOT, "docs", "*.md")))
    env = dict(os.environ, PATH=build + os.pathsep + os.path.join(ROOT, "tools") + os.pathsep + os.environ["PATH"])
    env.pop("LSQT_CL", None)
    ran = failed = 0
    for path in files:
        rel = os.path.relpath(path, ROOT)
        for line, lang, directive, arg, text in blocks(path):
            where = "%s:%d" % (rel, line)
            if lang != "sh":
                if lang in ("python", "bash", "console"):
                    print("not run  %s (%s)" % (where, lang))
                continue
            if directive == "skip":
                print("skip     %s: %s" % (where, arg or "no reason given"))
                if not arg:
                    failed += 1
                continue
            with tempfile.TemporaryDirectory(prefix="lsqt-doc-") as d:
                if directive == "cwd":
                    work = os.path.join(d, "w")
                    shutil.copytree(os.path.join(ROOT, arg), work)
                else:
                    work = d
                    shutil.copytree(os.path.join(ROOT, "examples"), os.path.join(d, "examples"))
                t0 = time.time()
                p = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", text], cwd=work, env=env,
                                   stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=600)
                ran += 1
                if p.returncode:
                    failed += 1
                    print("FAIL     %s: exit %d\n%s\n--- output ---\n%s%s" % (where, p.returncode, text, p.stdout[-1500:],
                                                                         p.stderr[-1500:]))
                else:
                    print("ok       %s (%.1f s)" % (where, time.time() - t0))
    print("test_docs: %d blocks ran, %d failed" % (ran, failed))
    return 1 if failed or not ran else 0


if __name__ == "__main__":
    sys.exit(main())
