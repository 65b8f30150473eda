#!/usr/bin/env python3
"""Mutation check: plants each error of tools/mutate/mutations.txt in a scratch copy and
runs the tests that should catch it. See tools/mutate/README.md.

usage: run.sh [-l] [-a] [-k] [-j N] [--no-baseline] [--ci] [NAME_REGEX]

Kernel files (kernels/*.cl, and shared headers the host never includes) are mutated in a
copy of kernels/ + include/ and tested with the release build (build/, or LSQT_BUILD_DIR)
through LSQT_KERNEL_DIR; everything else is mutated in a scratch copy of the source tree,
built once in a scratch build directory and rebuilt incrementally per mutation. A
mutation is killed when a test's checks fail on it (ctest: Failed), and the report names
those tests; it survived when they pass; tests that only time out or crash leave it
unkilled; the gates (GATES: test_gpu_build's register ceilings) never run against a
mutant. An error (a rotten entry, a mutant that does not build, a test that does not
exist, a baseline that fails) is a failure of the list. Exit status 0 only when every
selected mutation is killed."""

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
LIST = os.path.join(HERE, "mutations.txt")
FIELDS = ("name", "file", "find", "replace", "tests", "why")
MULTI = ("find", "replace")  # fields that take continuation lines (find+:, replace+:)
NAME_RE = re.compile(r"^[a-z0-9][a-z0-9._-]*$")
TEST_RE = re.compile(r"^[A-Za-z0-9_.*+?\[\]-]+$")  # a ctest name, or a simple pattern
# Tests that fail on any edit of what they watch, whatever its physics: test_gpu_build
# holds each kernel's register count at its ceiling. They are never run against a mutant
# (ctest -E), and no mutation may name them: a planted error must be seen by a test of
# values.
GATES = ("test_gpu_build",)
# ctest's reason for a failed test that means its checks saw something; anything else
# (Timeout, SEGFAULT, Subprocess aborted, Child aborted, ...) is a test that did not
# finish its checks, and does not kill a mutant.
FAILED_CHECK = "Failed"


class ListError(Exception):
    pass


# ---- the list -----------------------------------------------------------------------

def parse_list(path):
    """Returns the mutations of the file (dicts of FIELDS plus 'line') and a list of
    format errors ('mutations.txt:LINE: ...')."""
    muts, errors, cur = [], [], None
    short = os.path.relpath(path, ROOT) if path.startswith(ROOT + os.sep) else path

    def close(m):
        if m is None:
            return
        missing = [f for f in FIELDS if f not in m]
        if missing:
            errors.append("%s:%d: mutation '%s' lacks %s" % (short, m["line"], m.get("name", "?"),
                                                             ", ".join(missing)))
        else:
            muts.append(m)

    with open(path, encoding="utf-8") as f:
        for n, raw in enumerate(f, 1):
            line = raw.rstrip("\n").rstrip("\r")
            if not line.strip() or line.startswith("#"):
                continue
            m = re.match(r"^([a-z]+)(\+?):(.*)$", line)
            if not m:
                errors.append("%s:%d: not 'key: value': %r" % (short, n, line))
                continue
            key, cont, value = m.group(1), m.group(2), m.group(3)
            if value.startswith(" "):
                value = value[1:]
            value = value.rstrip(" \t")
            if key not in FIELDS or (cont and key not in MULTI):
                errors.append("%s:%d: unknown key '%s%s'" % (short, n, key, cont))
                continue
            if key == "name":
                close(cur)
                cur = {"line": n, "name": value}
                continue
            if cur is None:
                errors.append("%s:%d: '%s' before the first 'name:'" % (short, n, key))
                continue
            if cont:
                if key not in cur:
                    errors.append("%s:%d: '%s+:' without a '%s:' before it" % (short, n, key, key))
                else:
                    cur[key] += "\n" + value
            elif key in cur:
                errors.append("%s:%d: second '%s:' in mutation '%s'" % (short, n, key, cur["name"]))
            else:
                cur[key] = value
    close(cur)
    return muts, errors


def check_entry(m, seen):
    """Problems of one entry against the real source tree (empty list: fine)."""
    why = []
    if not NAME_RE.match(m["name"]):
        why.append("name '%s' is not [a-z0-9._-]" % m["name"])
    if m["name"] in seen:
        why.append("name used twice")
    rel = m["file"]
    path = os.path.normpath(os.path.join(ROOT, rel))
    if os.path.isabs(rel) or not path.startswith(ROOT + os.sep) or not os.path.isfile(path):
        why.append("no file '%s' in the source tree" % rel)
    elif not m["find"]:
        why.append("empty find")
    else:
        with open(path, encoding="utf-8") as f:
            count = f.read().count(m["find"])
        if count != 1:
            why.append("find text occurs %d times in %s (must be exactly once): %r" % (count, rel, m["find"]))
    if m["find"] == m["replace"]:
        why.append("replace equals find")
    tests = m["tests"].split()
    if not tests or not all(TEST_RE.match(t) for t in tests):
        why.append("tests must be ctest names separated by spaces: %r" % m["tests"])
    gates = [t for t in tests if any(re.fullmatch(t, g) for g in GATES)]
    if gates:
        why.append("%s is a gate (a ceiling that any edit can cross), not a test of values; name the test "
                   "that sees the error" % ", ".join(gates))
    if not m["why"]:
        why.append("empty why")
    return why


def compiles(m, cc="cc"):
    """For a C file of the host or tests: the compiler's errors on the mutant (warnings
    allowed: scratch builds are not -Werror), or "" when it compiles or cannot be
    checked. A second, so a rotted replacement fails the list check, not a CI run."""
    if not m["file"].endswith(".c") or not shutil.which(cc):
        return ""
    path = os.path.join(ROOT, m["file"])
    with open(path, encoding="utf-8") as f:
        text = f.read()
    if text.count(m["find"]) != 1:
        return ""
    with tempfile.TemporaryDirectory(prefix="lsqt-mutant-cc.") as d:
        mut = os.path.join(d, os.path.basename(path))
        with open(mut, "w", encoding="utf-8") as f:
            f.write(text.replace(m["find"], m["replace"], 1))
        p = subprocess.run([cc, "-std=c11", "-fsyntax-only", "-w", "-D_POSIX_C_SOURCE=200809L",
                            "-DCL_TARGET_OPENCL_VERSION=120", "-iquote", os.path.dirname(path),
                            "-I", os.path.join(ROOT, "include"), "-I", os.path.join(ROOT, "tests"), mut],
                           capture_output=True, text=True)
    if p.returncode == 0:
        return ""
    errs = [l for l in p.stderr.splitlines() if "error" in l][:3]
    return "the mutant does not compile: " + " | ".join(e.replace(d + os.sep, "") for e in errs)


# ---- processes ----------------------------------------------------------------------

def kill_session(sid):
    """SIGKILL every process of session sid: the one we started with start_new_session,
    and all it started, even those that moved to a process group of their own
    (GNU timeout does)."""
    for _ in range(3):
        pids = []
        for d in os.listdir("/proc"):
            if not d.isdigit():
                continue
            try:
                with open("/proc/%s/stat" % d) as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[3]) == sid:  # after the name: state, ppid, pgrp, session
                pids.append(int(d))
        if not pids:
            return
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        time.sleep(0.2)


ACTIVE = set()  # sessions of the commands running now (several with parallel workers)


def run(cmd, cwd, env, limit=None):
    """Runs cmd in a session of its own; returns (rc, output, timed_out). On timeout, or
    when we are interrupted, the whole session (ctest and the tests it started) is
    killed."""
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         start_new_session=True)
    ACTIVE.add(p.pid)
    try:
        out, _ = p.communicate(timeout=limit)
        return p.returncode, out.decode("utf-8", "replace"), False
    except subprocess.TimeoutExpired:
        kill_session(p.pid)
        out, _ = p.communicate()
        return -9, out.decode("utf-8", "replace"), True
    except BaseException:
        kill_session(p.pid)
        p.wait()
        raise
    finally:
        ACTIVE.discard(p.pid)


class Ctest:
    """ctest in one build directory."""

    def __init__(self, bdir, env, jobs, timeout):
        self.bdir, self.env, self.jobs, self.timeout = bdir, env, jobs, timeout
        self.count_cache = {}

    def count(self, name):
        """How many tests ^name$ selects."""
        if name not in self.count_cache:
            rc, out, _ = run(["ctest", "-N", "-R", "^(%s)$" % name], self.bdir, self.env, 120)
            m = re.search(r"Total Tests: (\d+)", out)
            if rc != 0 or not m:
                raise ListError("ctest -N failed in %s:\n%s" % (self.bdir, out))
            self.count_cache[name] = int(m.group(1))
        return self.count_cache[name]

    def missing(self, names):
        return [t for t in names if self.count(t) == 0]

    def run(self, names):
        """Runs ^(names)$ but the GATES; returns (status, failed, output): status 'pass',
        'fail' (some test failed), 'hang' (ctest itself ran past its limit) or 'error'
        (ctest failed without a failing test); failed lists (test, ctest's reason:
        FAILED_CHECK, 'Timeout', 'SEGFAULT', ...)."""
        regex = "^(%s)$" % "|".join(names)
        n = sum(self.count(t) for t in names)
        cmd = ["ctest", "--output-on-failure", "--no-tests=error", "-j", str(self.jobs),
               "--timeout", str(self.timeout), "-R", regex, "-E", "^(%s)$" % "|".join(GATES)]
        # ctest --timeout does not override a test's own TIMEOUT property (up to 300 s
        # here), so ctest as a whole gets a hard limit too: the per-test limit for every
        # test it runs, plus 15 s. A mutant that hangs is stopped (and not killed).
        rc, out, hung = run(cmd, self.bdir, self.env, self.timeout * max(n, 1) + 15)
        failed = re.findall(r"^\s*\d+ - (\S+) \(([^)]*)\)", out, re.M)
        if hung:
            return "hang", failed, out
        if rc == 0:
            return "pass", [], out
        if failed:
            return "fail", failed, out
        return "error", [], out


def verdict(status, failed):
    """A mutant's status from its tests' outcome: 'killed' only when a test's checks
    failed (ctest's FAILED_CHECK); a mutant whose tests only timed out or crashed is
    'unkilled'; 'hung' when ctest ran past its limit. Returns (status, note)."""
    checks = [t for t, why in failed if why == FAILED_CHECK]
    others = ["%s (%s)" % (t, why) for t, why in failed if why != FAILED_CHECK]
    rest = ("; not counted: " + ", ".join(others)) if others else ""
    if checks:
        return "killed", "killed by " + " ".join(checks) + rest
    if status == "hang":
        return "hung", "ctest ran past its limit" + rest
    return "unkilled", "no test's checks failed" + rest


# ---- scratch trees ------------------------------------------------------------------

def kernel_files():
    """The kernel sources in the order they are embedded (CMakeLists.txt: the core list,
    every kernels/phase_*.cl and kernels/bsdf_*.cl but the core's in name order, the engine)."""
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as f:
        text = f.read()
    lists = {}
    for name in ("CORE", "ENGINE"):
        m = re.search(r"set\(LSQT_KERNEL_%s\s+([^)]*)\)" % name, text)
        if not m:
            raise ListError("CMakeLists.txt has no set(LSQT_KERNEL_%s ...)" % name)
        lists[name] = m.group(1).split()
    kdir = os.path.join(ROOT, "kernels")
    models = sorted("kernels/" + f for f in os.listdir(kdir)
                    if f.endswith(".cl") and f.startswith(("phase_", "bsdf_")))
    return lists["CORE"] + [f for f in models if f not in lists["CORE"]] + lists["ENGINE"]


def host_includes():
    """Headers the host C code includes ("lsqt/x.h" as include/lsqt/x.h)."""
    inc = set()
    for d in ("host", "include", "tests", "tools"):
        for dirpath, _, files in os.walk(os.path.join(ROOT, d)):
            for fn in files:
                if fn.endswith((".c", ".h")):
                    with open(os.path.join(dirpath, fn), encoding="utf-8", errors="replace") as f:
                        for m in re.finditer(r'#\s*include\s+"(lsqt/[^"]+)"', f.read()):
                            inc.add("include/" + m.group(1))
    return inc


def is_kernel_side(rel, kfiles, hinc):
    """Mutated without a host rebuild: a kernel source the host never compiles."""
    return rel in kfiles and rel not in hinc and not rel.endswith(".c")


def copy_tree(dst):
    """The source tree without .git and build directories."""
    def ignore(d, names):
        if os.path.abspath(d) == ROOT:
            return [n for n in names if n == ".git" or n == "build" or n.startswith("build-")]
        return [n for n in names if n.endswith((".lsqt.raw", ".lsqt.lss")) or ".tmp." in n]
    shutil.copytree(ROOT, dst, symlinks=True, ignore=ignore)


def patcher(root):
    """(apply, restore) for mutations of the copy at root: apply plants m's replacement,
    restore puts the file back as it was."""
    originals = {}

    def apply(m):
        p = os.path.join(root, m["file"])
        with open(p, encoding="utf-8") as f:
            originals[p] = f.read()
        write(p, originals[p].replace(m["find"], m["replace"], 1))

    def restore(m):
        p = os.path.join(root, m["file"])
        write(p, originals.pop(p))

    return apply, restore


def write(path, text):
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    os.utime(path, None)


def git(*args):
    """Output of a git command in ROOT, or None where git or the history is missing."""
    try:
        return subprocess.run(["git"] + list(args), cwd=ROOT, capture_output=True, text=True,
                              check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None


def test_sources(name):
    """The source file of a ctest test: tests/NAME(.c|.sh|.py), else that of the part
    before the first dot (a section: test_phases.hg2 -> tests/test_phases.c)."""
    for base in (name, name.split(".")[0]):
        for ext in ("", ".c", ".sh", ".py"):
            rel = "tests/" + base + ext
            if os.path.isfile(os.path.join(ROOT, rel)):
                return rel
    return None


def recent_files(hours):
    """Files changed by the commits of the last `hours` hours before HEAD's commit (a
    session's work), and any uncommitted change; None without git history."""
    t = git("log", "-1", "--format=%ct")
    if not t or not t.strip():
        return None
    since = int(t.strip()) - int(hours * 3600)
    out = git("log", "--since=@%d" % since, "--name-only", "--format=")
    dirty = git("diff", "--name-only", "HEAD") or ""
    return {l.strip() for l in (out or "").splitlines() + dirty.splitlines() if l.strip()}


def ci_select(muts, shares, seed, hours, cap):
    """CI's choice: every mutation whose file, or whose tests' source, changed recently,
    plus the share (seed mod shares) of the rest; each mutation belongs to the share
    crc32(name) mod shares, so a mutation keeps its share when others are added. At most
    cap in all (CI's time budget): the recent ones first, each group cut in an order that
    the seed rotates, so the ones left out run on later seeds. Returns (selected, lines
    that say what was chosen)."""
    changed = recent_files(hours)
    why = []
    if changed is None:
        changed = {m["file"] for m in muts}
        why.append("no git history: every mutation counts as recent")
    share = seed % shares
    recent, rest = [], []
    for m in muts:
        srcs = {m["file"]} | {test_sources(t) for t in m["tests"].split()}
        if srcs & changed:
            recent.append(m)
        elif zlib.crc32(m["name"].encode()) % shares == share:
            rest.append(m)

    def rotated(group):
        return sorted(group, key=lambda m: zlib.crc32(("%s/%d" % (m["name"], seed)).encode()))

    n_recent = min(len(recent), cap)
    n_share = min(len(rest), cap - n_recent)
    picked = rotated(recent)[:n_recent] + rotated(rest)[:n_share]
    names = {m["name"] for m in picked}
    sel = [m for m in muts if m["name"] in names]  # in the list's order
    why.append("%d of %d mutations: %d of the %d whose file or tests changed in the commits of the "
               "%g hours before HEAD (or are uncommitted), and %d of the %d in share %d of %d of the "
               "rest (at most %d in all, LSQT_MUTATE_MAX; seed %d: LSQT_MUTATE_SEED, default the "
               "commit count of HEAD, which rotates the shares and the cut); the other %d run on "
               "other seeds" % (len(sel), len(muts), n_recent, len(recent), hours, n_share, len(rest),
                                share, shares, cap, seed, len(muts) - len(sel)))
    return sel, why


def clang_check(kdir, kfiles, scratch):
    """Compiles the kernel sources as lsqt does (one unit, in order) with clang's OpenCL
    front end for each precision/atomics variant; returns None or the first error. A
    mutant that does not compile would otherwise look killed."""
    clang = shutil.which("clang") or shutil.which("clang-15") or shutil.which("clang-14")
    if not clang:
        return None
    src = os.path.join(scratch, "all.cl")
    with open(src, "w", encoding="utf-8") as out:
        for rel in kfiles:
            with open(os.path.join(kdir, rel), encoding="utf-8") as f:
                out.write(f.read() + "\n")
    base = ["-x", "cl", "-cl-std=CL1.2", "-Xclang", "-finclude-default-header", "-fsyntax-only",
            "-DLSQT_NWI=16", "-DLSQT_HAS_BSDF_LAMBERTIAN=1", "-DLSQT_HAS_PHASE_HG=1"]
    for extra in ([], ["-DLSQT_NO_INT64_ATOMICS=1"], ["-DLSQT_DOUBLE=1"]):
        rc, out, _ = run([clang] + base + extra + [src], scratch, os.environ.copy(), 120)
        if rc != 0:
            return "the mutant kernel does not compile (clang, %s):\n%s" % (" ".join(extra) or "default options",
                                                                           out[-3000:])
    return None


# ---- main ---------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("regex", nargs="?", default="", help="run only mutations whose name matches (re.search)")
    ap.add_argument("-l", "--list", action="store_true", help="check the list and print it; run nothing")
    ap.add_argument("-a", "--all-tests", action="store_true",
                    help="run every test for each mutation and print which fail (to pick the smallest set)")
    ap.add_argument("-k", "--keep", action="store_true", help="keep the scratch directory")
    ap.add_argument("-f", "--file", default=LIST, help="the list to run (default tools/mutate/mutations.txt)")
    ap.add_argument("-j", "--parallel", type=int, default=int(os.environ.get("LSQT_MUTATE_PARALLEL") or 2),
                    help="kernel mutants tested at once, each in its own kernel directory with ctest -j 1 "
                         "(default 2, LSQT_MUTATE_PARALLEL); host mutants share one scratch build and "
                         "run one at a time with ctest -j LSQT_MUTATE_JOBS")
    ap.add_argument("--no-baseline", action="store_true",
                    help="skip running the unmutated tests first (for a caller that has just passed the "
                         "whole suite on this tree, as .ci/run has)")
    ap.add_argument("--ci", action="store_true",
                    help="CI's selection: the mutations of recently changed files and tests, and a "
                         "rotating share of the rest, at most LSQT_MUTATE_MAX (default 120) in all "
                         "(LSQT_MUTATE_SHARES, default 2; LSQT_MUTATE_SEED; LSQT_MUTATE_RECENT_HOURS, "
                         "default 6)")
    args = ap.parse_args()

    t_start = time.time()
    muts, errors = parse_list(os.path.abspath(args.file))
    for e in errors:
        print("error: " + e)
    if errors:
        print("0 passed, %d failed (%s does not parse)" % (len(errors), args.file))
        return 1
    bad, seen = {}, set()
    for m in muts:
        why = check_entry(m, seen)
        if args.list and not why:
            cc = compiles(m)
            why = [cc] if cc else []
        seen.add(m["name"])
        if why:
            bad[m["name"]] = "; ".join(why)
    try:
        sel = [m for m in muts if re.search(args.regex, m["name"])]
    except re.error as e:
        print("error: bad NAME_REGEX: %s" % e)
        return 2
    if not sel:
        print("error: no mutation matches '%s'" % args.regex)
        return 2
    if args.ci:
        shares = max(1, int(os.environ.get("LSQT_MUTATE_SHARES") or 2))
        seed_env = os.environ.get("LSQT_MUTATE_SEED")
        seed = int(seed_env) if seed_env else int((git("rev-list", "--count", "HEAD") or "0").strip() or 0)
        hours = float(os.environ.get("LSQT_MUTATE_RECENT_HOURS") or 6)
        cap = max(1, int(os.environ.get("LSQT_MUTATE_MAX") or 120))
        sel, lines = ci_select(sel, shares, seed, hours, cap)
        for l in lines:
            print("mutation check: " + l)
        # An entry that has rotted is reported whatever the share: the list must not rot.
        names = {m["name"] for m in sel}
        sel += [m for m in muts if m["name"] in bad and m["name"] not in names]
    kfiles, hinc = kernel_files(), host_includes()
    for m in sel:
        m["kernel"] = is_kernel_side(m["file"], kfiles, hinc)

    if args.list:
        for m in sel:
            print("%-34s %-6s %-28s %s" % (m["name"], "kernel" if m["kernel"] else "host", m["file"], m["tests"]))
            print("    %s%s" % (m["why"], ("\n    ERROR: " + bad[m["name"]]) if m["name"] in bad else ""))
        print("%d mutations, %d with errors" % (len(sel), sum(m["name"] in bad for m in sel)))
        return 1 if any(m["name"] in bad for m in sel) else 0

    bdir = os.path.abspath(os.environ.get("LSQT_BUILD_DIR") or os.path.join(ROOT, "build"))
    if any(m["kernel"] for m in sel) and not os.path.isfile(os.path.join(bdir, "CTestTestfile.cmake")):
        print("error: no release build in %s (run bash tools/build.sh first)" % bdir)
        return 2
    jobs = int(os.environ.get("LSQT_MUTATE_JOBS") or 2)
    limit = int(os.environ.get("LSQT_MUTATE_TIMEOUT") or 300)
    build_jobs = str(os.environ.get("LSQT_MUTATE_BUILD_JOBS") or os.cpu_count() or 2)
    par = max(1, args.parallel)

    scratch = tempfile.mkdtemp(prefix="lsqt-mutate.")
    env = os.environ.copy()
    env.pop("LSQT_KERNEL_DIR", None)
    if not env.get("POCL_CACHE_DIR"):
        env["POCL_CACHE_DIR"] = os.path.join(scratch, "pocl-cache")
        os.makedirs(env["POCL_CACHE_DIR"])
    # A mutant's tests stop at their first failed check (tests/check.h, tests/cli_lib.sh):
    # being caught once is all the check asks. The baselines run without it.
    mut_env = dict(env, LSQT_CHECK_FAIL_FAST="1")
    passed = failed = 0
    width = max(len(m["name"]) for m in sel)
    lock = threading.Lock()

    def report(m, status, secs, note=""):
        nonlocal passed, failed
        with lock:
            if status == "killed":
                passed += 1
            else:
                failed += 1
            note = note.rstrip().replace("\n", "\n        ")
            print("%-*s  %-8s %6.1f s%s" % (width, m["name"], status, secs, ("  " + note) if note else ""),
                  flush=True)

    def tests_of(m, ct):
        return [".*"] if args.all_tests else m["tests"].split()

    def one(m, ct, apply, restore, rebuild=None):
        t0 = time.time()
        if m["name"] in bad:
            return report(m, "error", 0.0, bad[m["name"]])
        names = tests_of(m, ct)
        miss = ct.missing(names)
        if miss:
            return report(m, "error", time.time() - t0, "no test named %s in %s" % (", ".join(miss), ct.bdir))
        apply(m)
        try:
            if rebuild:
                problem = rebuild(m)
                if problem:
                    return report(m, "error", time.time() - t0, problem)
            status, killers, out = ct.run(names)
        finally:
            restore(m)
        secs = time.time() - t0
        if m["kernel"] and "the OpenCL kernels failed to build" in out:
            return report(m, "error", secs, "the mutant kernel does not build on the device:\n" + out[-3000:])
        if status == "pass":
            return report(m, "survived", secs, "(%s pass)" % " ".join(names) if not args.all_tests else "")
        if status == "error":
            return report(m, "error", secs, "ctest failed without a failing test:\n" + out[-3000:])
        v, note = verdict(status, killers)
        return report(m, v, secs, "(%s)" % note)

    def baseline(ct, group, label):
        """The unmutated tree must pass the tests the group names; else nothing it
        says is meaningful."""
        if args.no_baseline:
            return True
        names = sorted({t for m in group for t in tests_of(m, ct)})
        names = [t for t in names if ct.count(t) > 0]
        if not names:
            return True
        t0 = time.time()
        status, killers, out = ct.run(names)
        if status != "pass":
            print("error: unmutated baseline fails in %s (%s):\n%s" % (ct.bdir, " ".join("%s (%s)" % k for k in killers),
                                                                  out[-5000:]))
            return False
        print("%-*s  %-8s %6.1f s  (%s)" % (width, "(baseline, %s)" % label, "ok",
                                           time.time() - t0, " ".join(names)), flush=True)
        return True

    def kernel_worker(k, queue, use_clang):
        """Tests kernel mutants from the shared queue in kernel directory k."""
        kdir = os.path.join(scratch, "kernel-dir-%d" % k)
        ct = Ctest(bdir, dict(mut_env, LSQT_KERNEL_DIR=kdir), 1 if par > 1 else jobs, limit)
        k_apply, k_restore = patcher(kdir)
        cdir = os.path.join(scratch, "clang-%d" % k)
        os.makedirs(cdir)

        def k_check(m):
            return clang_check(kdir, kfiles, cdir) if use_clang else None

        while True:
            with lock:
                if not queue:
                    return
                m = queue.pop(0)
            one(m, ct, k_apply, k_restore, k_check)

    try:
        kern = [m for m in sel if m["kernel"]]
        host = [m for m in sel if not m["kernel"]]
        if kern:
            for k in range(par):
                kdir = os.path.join(scratch, "kernel-dir-%d" % k)
                for d in ("kernels", "include"):
                    shutil.copytree(os.path.join(ROOT, d), os.path.join(kdir, d))
            ct = Ctest(bdir, dict(env, LSQT_KERNEL_DIR=os.path.join(scratch, "kernel-dir-0")), jobs, limit)
            use_clang = True
            problem = clang_check(os.path.join(scratch, "kernel-dir-0"), kfiles, scratch)
            if problem:  # this clang cannot judge the clean sources: rely on the device
                print("note: clang's check fails on the unmutated kernels; skipped:\n" + problem)
                use_clang = False
            if baseline(ct, [m for m in kern if m["name"] not in bad], "release build"):
                queue = list(kern)
                workers = [threading.Thread(target=kernel_worker, args=(k, queue, use_clang))
                           for k in range(par)]
                for w in workers:
                    w.start()
                try:
                    for w in workers:
                        while w.is_alive():
                            w.join(0.5)
                except KeyboardInterrupt:
                    with lock:
                        queue.clear()
                    for sid in list(ACTIVE):
                        kill_session(sid)
                    for w in workers:
                        w.join()
                    raise
            else:
                for m in kern:
                    report(m, "error", 0.0, "baseline fails")
        if host:
            src, hb = os.path.join(scratch, "src"), os.path.join(scratch, "build")
            t0 = time.time()
            copy_tree(src)
            rc, out, _ = run(["cmake", "-S", src, "-B", hb, "-DCMAKE_BUILD_TYPE=RelWithDebInfo",
                              "-DLSQT_WERROR=OFF"], scratch, env, 600)
            if rc == 0:
                rc, out, _ = run(["cmake", "--build", hb, "-j", build_jobs], scratch, env, 1200)
            ok = rc == 0
            if not ok:
                print("error: the unmutated scratch copy does not build:\n" + out[-5000:])
            else:
                print("%-*s  %-8s %6.1f s" % (width, "(scratch build)", "ok", time.time() - t0), flush=True)
            ct = Ctest(hb, env, jobs, limit)
            mct = Ctest(hb, mut_env, jobs, limit)
            h_apply, h_restore = patcher(src)

            def h_build(m):
                rc, out, _ = run(["cmake", "--build", hb, "-j", build_jobs], scratch, env, 1200)
                return None if rc == 0 else "the mutant does not build:\n" + out[-3000:]

            if ok and baseline(ct, [m for m in host if m["name"] not in bad], "scratch build"):
                for m in host:
                    one(m, mct, h_apply, h_restore, h_build)
            else:
                for m in host:
                    report(m, "error", 0.0, "scratch build or baseline fails")
    except ListError as e:
        print("error: %s" % e)
        failed += 1
    except KeyboardInterrupt:
        print("interrupted")
        failed += 1
    finally:
        if args.keep:
            print("scratch kept in %s" % scratch)
        else:
            shutil.rmtree(scratch, ignore_errors=True)
    print("mutation check: %.0f s in all" % (time.time() - t_start))
    print("%d passed, %d failed" % (passed, failed))
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
