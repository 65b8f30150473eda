#!/usr/bin/env python3
"""test_gpu_build: the GPU programs, compiled and linked offline without a GPU.

    test_gpu_build.py GPU_PROGRAM EXAMPLES_DIR [--jobs N]

GPU_PROGRAM (tests/gpu_program.c) gives the kernels' text and the build options the host
uses on the GPU code path (vector width 2, one RNG block, 64-bit atomics). Every model
family's program is compiled by Debian's clang-15 for AMD gfx90a (CDNA2, wave64) and
gfx1100 (RDNA3; its builtins from libclc: Debian's rocm-device-libs stop at RDNA2), linked by lld into a code object, and for nvptx64
with libclc (PTX; ptxas reports registers when the CUDA toolkit is present). Configurations:
the main program at -wi 16 and 1024, the RRSS pilot at -rx 8 -wi 1024 (8192 directions),
double at -wi 300 (gfx90a); gfx1100 at -wi 300; nvptx64 at -wi 16 and the pilot; gfx90a
at -O0 too (a program
that links only because the optimiser inlined every call fails there); and every band
block width the GPU code path uses (2 ... LSQT_GPU_BAND_BLOCK_MAX, include/lsqt/
band_blocks.h) at -wi 1024 on gfx90a.

Fails on: a compile or link error (an undefined symbol; a PTX `.extern .func`); local
memory (LDS, `.shared`) above 32 KB in any kernel; scratch (AMD) or `.local` memory (PTX)
that grows with the direction count (gfx90a, nvptx64), unless listed in KNOWN with the
reason; any scratch of a float kernel on gfx90a at -O3; a kernel above its VGPR ceiling
in CEILINGS (the ceilings hold what has been reached, so it cannot slip back; every
float kernel is at or below 128 on gfx90a, 4 waves per SIMD, and must stay there; a band
block's too, with no scratch, and fewer than 4 waves per SIMD for its local memory fails
as well); a KNOWN defect that is gone (remove it from KNOWN, so the test holds the gain).
Prints the table of every compile.
Exit 77 (skipped) when clang-15, ld.lld or the device libraries are missing."""
import concurrent.futures
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROCM = "/usr/lib/x86_64-linux-gnu/amdgcn/bitcode"
CLC = "/usr/lib/clc/nvptx64--nvidiacl.bc"
CLC_AMD = "/usr/lib/clc/amdgcn--amdhsa.bc"
KERNELS = ("lsqt_walk", "lsqt_estimate", "lsqt_exits", "lsqt_prepare")
LDS_MAX = 32768

# (family file, description). Each model of include/lsqt/model_list.h is in at least one
# (checked: the test fails on a model no family builds).
FAMILIES = [
    ("slab.lsqt", "slab"),
    ("tutorial/Dust.lsqt", "Dust"),
    ("tutorial/Rough.lsqt", "Rough"),
    ("tutorial/Substr.lsqt", "Substr"),
    ("tutorial/Dusty.lsqt", "Dusty"),
    ("tutorial/Silver.lsqt", "Silver"),
    ("sggx-dust.lsqt", "SGGX"),
    ("rayleigh-oren-nayar.lsqt", "Rayleigh-ON"),
    ("dust-over-cloud.lsqt", "Draine-HG2"),
    ("mie-fog.lsqt", "Tabulated"),
]

# Defects known and not yet fixed: (kernel, check) -> why. The check still runs and is
# reported; the test fails when the defect is gone, so that the entry is removed.
KNOWN = {}

# VGPRs on gfx90a at -O3 in float per family and kernel (the most over -wi 16, 1024 and
# the pilot): a rise fails the test. Lower them as kernels improve; a kernel at or below
# TARGET (4 waves per SIMD) must stay there, and every one is.
TARGET = 128
CEILINGS = {
    "slab": {"lsqt_walk": 70, "lsqt_estimate": 76, "lsqt_exits": 56, "lsqt_prepare": 26},
    "Dust": {"lsqt_walk": 72, "lsqt_estimate": 76, "lsqt_exits": 62, "lsqt_prepare": 26},
    "Rough": {"lsqt_walk": 118, "lsqt_estimate": 106, "lsqt_exits": 86, "lsqt_prepare": 26},
    "Substr": {"lsqt_walk": 118, "lsqt_estimate": 116, "lsqt_exits": 89, "lsqt_prepare": 26},
    "Dusty": {"lsqt_walk": 123, "lsqt_estimate": 116, "lsqt_exits": 94, "lsqt_prepare": 26},
    "Silver": {"lsqt_walk": 116, "lsqt_estimate": 93, "lsqt_exits": 81, "lsqt_prepare": 26},
    "SGGX": {"lsqt_walk": 78, "lsqt_estimate": 95, "lsqt_exits": 63, "lsqt_prepare": 26},
    "Rayleigh-ON": {"lsqt_walk": 88, "lsqt_estimate": 79, "lsqt_exits": 74, "lsqt_prepare": 26},
    "Draine-HG2": {"lsqt_walk": 71, "lsqt_estimate": 90, "lsqt_exits": 63, "lsqt_prepare": 26},
    "Tabulated": {"lsqt_walk": 67, "lsqt_estimate": 80, "lsqt_exits": 62, "lsqt_prepare": 26},
}


def model_names():
    """PHASE_<ID> and BSDF_<ID> of every model in include/lsqt/model_list.h."""
    header = open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "include", "lsqt",
                               "model_list.h")).read()
    models = set()
    for cls, macro in (("PHASE", "LSQT_PHASES"), ("BSDF", "LSQT_BSDFS")):
        body = header[header.index("#define %s(X)" % macro):]
        body = body[:body.index("\n\n")]
        models |= {"%s_%s" % (cls, m) for m in re.findall(r"X\((\w+),", body)}
    return models


def have_tools():
    need = [shutil.which("clang-15"), shutil.which("ld.lld") or shutil.which("ld.lld-15"),
            os.path.isfile(os.path.join(ROCM, "ocml.bc")), os.path.isfile(CLC), os.path.isfile(CLC_AMD)]
    return all(need)


def amd_compile(src, opts, mcpu, olevel, out):
    # Debian's rocm-device-libs (5.2) stop at RDNA2; gfx1100 links libclc's builtins, as
    # Mesa's OpenCL does.
    libs = (["--rocm-device-lib-path=" + ROCM] if os.path.isfile(os.path.join(ROCM, "oclc_isa_version_%s.bc" % mcpu[3:]))
            else ["-nogpulib", "-Xclang", "-mlink-builtin-bitcode", "-Xclang", CLC_AMD])
    cmd = ["clang-15", "-x", "cl", "-Xclang", "-finclude-default-header", "-target", "amdgcn-amd-amdhsa",
           "-mcpu=" + mcpu, olevel, *libs, "-Rpass-analysis=kernel-resource-usage", *opts.split(), src, "-o", out]
    p = subprocess.run(cmd, capture_output=True, text=True)
    res, cur = {}, None
    for line in p.stderr.splitlines():
        m = re.search(r"remark: Function Name: (\w+)", line)
        if m:
            cur = m.group(1)
            res[cur] = {}
            continue
        m = re.search(r"remark:\s+([A-Za-z ]+?)(?: \[bytes/(?:lane|block)\])?(?: \[waves/SIMD\])?: (\d+)", line)
        if m and cur:
            res[cur][m.group(1).strip()] = int(m.group(2))
    errors = [l for l in p.stderr.splitlines() if "error" in l]
    return p.returncode, res, errors


def ptx_compile(src, opts, out):
    cmd = ["clang-15", "-x", "cl", "-Xclang", "-finclude-default-header", "-target", "nvptx64-unknown-nvidiacl",
           "-O3", "-Xclang", "-mlink-builtin-bitcode", "-Xclang", CLC, *opts.split(), "-S", src, "-o", out]
    p = subprocess.run(cmd, capture_output=True, text=True)
    errors = [l for l in p.stderr.splitlines() if "error" in l]
    res = {}
    if p.returncode != 0:
        return p.returncode, res, errors
    ptx = open(out).read()
    externs = re.findall(r"\.extern \.func[^(]*?(\w+)\s*\(", ptx)
    if externs:
        errors.append("undefined functions in the PTX: " + ", ".join(sorted(set(externs))))
    # Each entry's .local depot (bytes per thread) and .shared arrays.
    for m in re.finditer(r"\.entry (\w+)\((.*?)\n\}", ptx, re.S):
        body = m.group(2)
        local = sum(int(x) for x in re.findall(r"\.local \.align \d+ \.b8\s+\w+\[(\d+)\]", body))
        shared = sum(int(x) for x in re.findall(r"\.shared \.align \d+ \.b8\s+\w+\[(\d+)\]", body))
        res[m.group(1)] = {"local": local, "shared": shared}
    # Module-level .shared (kernel-scope __local arrays) count for the kernel naming them.
    for name, size in re.findall(r"\.shared \.align \d+ \.b8 (\w+)\[(\d+)\]", ptx):
        for k in res:
            if name.startswith(k + "."):
                res[k]["shared"] += int(size)
    if shutil.which("ptxas"):
        q = subprocess.run(["ptxas", "-arch=sm_90", "-v", out, "-o", out + ".cubin"], capture_output=True, text=True)
        cur = None
        for line in q.stderr.splitlines():
            m = re.search(r"Compiling entry function '(\w+)'", line)
            if m:
                cur = m.group(1)
            m = re.search(r"(\d+) bytes spill stores", line)
            if m and cur in res:
                res[cur]["spill"] = int(m.group(1))
            m = re.search(r"Used (\d+) registers", line)
            if m and cur in res:
                res[cur]["regs"] = int(m.group(1))
                cur = None
        if q.returncode != 0:
            errors.append("ptxas: " + q.stderr.strip().splitlines()[-1])
    return (1 if errors else 0), res, errors


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        print(__doc__)
        return 2
    gpu_program, examples = args[0], args[1]
    jobs = int(args[args.index("--jobs") + 1]) if "--jobs" in args else (os.cpu_count() or 2)
    if not have_tools():
        print("test_gpu_build: SKIPPED: clang-15, ld.lld, rocm-device-libs or libclc-15 missing "
              "(bash tools/setup.sh installs them)")
        return 77
    tmp = tempfile.mkdtemp(prefix="lsqt-gpu-build-")
    src = os.path.join(tmp, "lsqt.cl")
    subprocess.run([gpu_program, "--source", src], check=True)

    def options(fam, nwi, group, dbl):
        p = subprocess.run([gpu_program, os.path.join(examples, fam), str(nwi), str(group), str(dbl)],
                           capture_output=True, text=True, check=True)
        return p.stdout.strip()

    # The kernels are OpenCL C 1.2 as the standard has it, not as clang or PoCL accept it:
    # NVIDIA's compiler refuses what -pedantic flags (variadic macros, say), so any such
    # warning fails here, in each precision and atomics variant, with every model built.
    every = " ".join("-DLSQT_HAS_%s=1" % m for m in sorted(model_names()))
    for extra in ("", "-DLSQT_DOUBLE=1", "-DLSQT_NO_INT64_ATOMICS=1", "-DLSQT_NEE_RECORDS=1 -DLSQT_VW=2",
                  "-DLSQT_NEE_RECORDS=1 -DLSQT_VW=2 -DLSQT_NB=3", "-DLSQT_NB=4",
                  "-DLSQT_NB=16 -DLSQT_DOUBLE=1 -DLSQT_ITEMS=2"):
        p = subprocess.run(["clang-15", "-x", "cl", "-cl-std=CL1.2", "-Xclang", "-finclude-default-header",
                            "-fsyntax-only", "-pedantic", "-Werror", "-DLSQT_NWI=16", *every.split(), *extra.split(),
                            src], capture_output=True, text=True)
        if p.returncode != 0:
            print("test_gpu_build: FAILED: the kernels are not strict OpenCL C 1.2 (clang-15 -pedantic %s):\n%s"
                  % (extra or "default options", p.stderr[-3000:]))
            return 1

    # Every model of the model list is in some family's program, so a new model is built
    # for the GPUs too (it needs an example and a line in FAMILIES).
    models = model_names()
    built = set()
    for fam, _ in FAMILIES:
        built |= set(re.findall(r"-DLSQT_HAS_(\w+)=1", options(fam, 16, 1, 0)))
    missing = sorted(models - built)
    if missing:
        print("test_gpu_build: FAILED: no family builds %s: add an example that uses it to FAMILIES"
              % ", ".join(missing))
        return 1

    # (family, config label, target, olevel, nwi, group, double); a band block's label is
    # "bands N" and its options get -DLSQT_NB=N.
    gpu_band_max = int(re.search(r"#define LSQT_GPU_BAND_BLOCK_MAX (\d+)", open(os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "include", "lsqt", "band_blocks.h")).read()).group(1))
    jobs_list = []
    for fam, name in FAMILIES:
        for nb in range(2, gpu_band_max + 1):
            jobs_list.append((name, fam, "bands %d" % nb, "gfx90a", "-O3", 1024, 1, 0))
        for label, nwi, group, dbl in (("wi 16", 16, 1, 0), ("wi 1024", 1024, 1, 0), ("pilot 8x1024", 1024, 8, 0),
                                       ("double wi 300", 300, 1, 1)):
            jobs_list.append((name, fam, label, "gfx90a", "-O3", nwi, group, dbl))
        jobs_list.append((name, fam, "wi 16 -O0", "gfx90a", "-O0", 16, 1, 0))
        jobs_list.append((name, fam, "wi 300", "gfx1100", "-O3", 300, 1, 0))
        jobs_list.append((name, fam, "wi 16", "nvptx64", "-O3", 16, 1, 0))
        jobs_list.append((name, fam, "pilot 8x1024", "nvptx64", "-O3", 1024, 8, 0))

    def run(j):
        name, fam, label, target, olevel, nwi, group, dbl = j
        opts = options(fam, nwi, group, dbl)
        if label.startswith("bands "):
            opts += " -DLSQT_NB=" + label.split()[1]
        out = os.path.join(tmp, "%s-%s-%s%s" % (name, target, label.replace(" ", "_"), ".ptx" if target == "nvptx64" else ".co"))
        if target == "nvptx64":
            return j, ptx_compile(src, opts, out)
        return j, amd_compile(src, opts, target, olevel, out)

    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as ex:
        results = list(ex.map(run, jobs_list))

    failures, known_seen = [], set()
    print("%-12s %-14s %-8s %-12s %5s %5s %7s %6s %6s %5s" %
          ("family", "config", "target", "kernel", "VGPR", "SGPR", "scratch", "LDS", "waves", "spill"))
    scratch, vgpr_max = {}, {}
    for (name, fam, label, target, olevel, nwi, group, dbl), (rc, res, errors) in results:
        where = "%s %s %s" % (name, label, target)
        if rc != 0:
            failures.append("%s: the build failed: %s" % (where, "; ".join(errors[:5]) or "rc %d" % rc))
            continue
        for k in KERNELS:
            r = res.get(k)
            if r is None:
                failures.append("%s: no resource report for %s" % (where, k))
                continue
            if target == "nvptx64":
                print("%-12s %-14s %-8s %-12s %5s %5s %7d %6d %6s %5s" % (
                    name, label, target, k, r.get("regs", "-"), "-", r["local"], r["shared"], "-", r.get("spill", "-")))
                lds, scr = r["shared"], r["local"]
            else:
                print("%-12s %-14s %-8s %-12s %5d %5d %7d %6d %6d %5d" % (
                    name, label, target, k, r["VGPRs"], r["SGPRs"], r["ScratchSize"], r["LDS Size"],
                    r["Occupancy"], r["VGPRs Spill"]))
                lds, scr = r["LDS Size"], r["ScratchSize"]
                if label.startswith("bands "):
                    if r["VGPRs"] > TARGET or scr or r["Occupancy"] < 4:
                        failures.append("%s: %s uses %d VGPRs, %d bytes of scratch, %d waves per SIMD (a band block "
                                        "must stay within %d, none and 4)" % (where, k, r["VGPRs"], scr, r["Occupancy"],
                                                                             TARGET))
                elif target == "gfx90a" and olevel == "-O3" and not dbl:
                    if scr:
                        failures.append("%s: %s uses %d bytes of scratch per lane (float on gfx90a must use none)"
                                        % (where, k, scr))
                    ceiling = CEILINGS[name][k]
                    if r["VGPRs"] > ceiling:
                        failures.append("%s: %s uses %d VGPRs, above its ceiling %d" % (where, k, r["VGPRs"], ceiling))
                    vgpr_max[(name, k)] = max(vgpr_max.get((name, k), 0), r["VGPRs"])
            if lds > LDS_MAX:
                failures.append("%s: %s uses %d bytes of local memory (at most %d)" % (where, k, lds, LDS_MAX))
            if (target == "gfx90a" and olevel == "-O3" and not dbl) or target == "nvptx64":
                scratch.setdefault((name + " " + target, k), {})[label] = scr
    # Scratch may not grow with the direction count.
    for (name, k), by in sorted(scratch.items()):
        grows = by.get("wi 1024", 0) > by.get("wi 16", 0) or by.get("pilot 8x1024", 0) > by.get("wi 16", 0)
        key = (k, "scratch grows")
        if grows and key in KNOWN:
            known_seen.add(key)
        elif grows:
            failures.append("%s %s: scratch grows with the direction count: %s" % (name, k, by))
    for key, why in KNOWN.items():
        if key in known_seen:
            print("known: %s %s (%s)" % (key[0], key[1], why))
        else:
            failures.append("known defect %s %s is gone: remove it from KNOWN in %s" % (key[0], key[1], __file__))
    met = sorted("%s %s" % nk for nk, v in vgpr_max.items() if v <= TARGET)
    print("gfx90a float at most %d VGPRs (4 waves per SIMD): %d of %d kernels: %s" % (TARGET, len(met), len(vgpr_max), ", ".join(met)))
    shutil.rmtree(tmp, ignore_errors=True)
    print("test_gpu_build: %d compiles (%d families x gfx90a -O3/-O0, gfx1100, nvptx64)" % (len(results), len(FAMILIES)))
    for f in failures:
        print("FAIL:", f)
    print("test_gpu_build:", "FAILED" if failures else "passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
