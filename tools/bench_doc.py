#!/usr/bin/env python3
"""docs/performance.md from the rows of tools/bench_targets.py (`bash tools/bench.sh targets
--doc`): the machine, the OpenCL device, the build measured and one table. Everything in the
page is generated; the page is written atomically (a temporary file in docs/, then a rename)."""
import os
import platform
import re
import subprocess
import tempfile
import textwrap
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, "docs", "performance.md")


def split_args(argv):
    """The command line of a benchmark script (bench_targets.py, bench_study.py): its own
    arguments, and lsqt-cl's after a `--` ([] without one)."""
    cut = argv.index("--") if "--" in argv else len(argv)
    return argv[:cut], argv[cut + 1:]


def _out(cmd, **kw):
    """stdout of CMD, or '' when it cannot run or fails."""
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=60, **kw)
    except (OSError, subprocess.SubprocessError):
        return ""
    return r.stdout if r.returncode == 0 else ""


def _read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return ""


def cpu_info():
    """CPU model (with family/model on x86), physical cores, logical CPUs, CPUs available to
    this process (nproc), and the hypervisor if any."""
    text = _read("/proc/cpuinfo")
    field = lambda k: (re.search(r"^" + k + r"\s*:\s*(.*)$", text, re.M) or [None, ""])[1].strip()
    model = field("model name") or platform.processor() or platform.machine()
    fam, mod = field("cpu family"), field("model")
    if fam and mod.isdigit():
        model += f" (family {fam}, model {mod})"
    cores = set()
    for block in text.split("\n\n"):
        p = re.search(r"^physical id\s*:\s*(\S+)", block, re.M)
        c = re.search(r"^core id\s*:\s*(\S+)", block, re.M)
        if p and c:
            cores.add((p[1], c[1]))
    lscpu = _out(["lscpu"])
    lf = lambda k: (re.search(r"^" + k + r":\s*(.*)$", lscpu, re.M) or [None, ""])[1].strip()
    n_cores = len(cores)
    if not n_cores and lf("Core\\(s\\) per socket").isdigit() and lf("Socket\\(s\\)").isdigit():
        n_cores = int(lf("Core\\(s\\) per socket")) * int(lf("Socket\\(s\\)"))
    logical = os.cpu_count() or 0
    try:
        nproc = len(os.sched_getaffinity(0))
    except AttributeError:
        nproc = logical
    return {"model": model, "cores": n_cores or None, "logical": logical, "nproc": nproc,
            "hypervisor": lf("Hypervisor vendor")}


def memory_gib():
    m = re.search(r"^MemTotal:\s*(\d+)\s*kB", _read("/proc/meminfo"), re.M)
    return int(m[1]) / 2**20 if m else None


def os_name():
    m = re.search(r'^PRETTY_NAME="?([^"\n]*)"?', _read("/etc/os-release"), re.M)
    return f"{m[1] if m else platform.system()}, kernel {platform.release()}"


def opencl_info(binary, device_name):
    """The measured device (the name lsqt-cl's --json reports) as --list-devices shows it, and
    its platform and driver from `clinfo --raw` when clinfo is there."""
    listed = [l.strip() for l in _out([binary, "--list-devices"]).splitlines() if l.strip()]
    line = next((l for l in listed if device_name and device_name in l), listed[0] if listed else "")
    info = {"list_line": line, "platform": "", "platform_version": "", "driver": "", "type": ""}
    if "(cpu," in line:
        info["type"] = "CPU"
    elif "(gpu," in line:
        info["type"] = "GPU"
    raw = _out(["clinfo", "--raw"])
    entries, platforms = {}, []  # "[P/D]" -> {key: value}; the leading list of platforms
    for l in raw.splitlines():
        m = re.match(r"\s*\[([^\]/]+)/([^\]]+)\]\s+(CL_\w+)\s+(.*)$", l)
        if m:
            entries.setdefault((m[1], m[2]), {})[m[3]] = re.sub(r"\s+", " ", m[4]).strip()
            continue
        m = re.match(r"\s+(CL_PLATFORM_\w+)\s+(.*)$", l)
        if m:
            if m[1] == "CL_PLATFORM_NAME":
                platforms.append({})
            if platforms:
                platforms[-1][m[1]] = re.sub(r"\s+", " ", m[2]).strip()
    m = re.match(r"(.*?)\s*\[([^\]]*)\]$", device_name or "")  # lsqt-cl's "DEVICE [PLATFORM]"
    dev_name, plat_name = (m[1], m[2]) if m else (device_name, None)
    for (plat, dev), e in entries.items():
        if (dev != "*" and e.get("CL_DEVICE_NAME") == dev_name
                and plat_name in (None, entries.get((plat, "*"), {}).get("CL_PLATFORM_NAME"))):
            name = entries.get((plat, "*"), {}).get("CL_PLATFORM_NAME", "")
            p = next((p for p in platforms if p.get("CL_PLATFORM_ICD_SUFFIX_KHR") == plat),
                     next((p for p in platforms if p.get("CL_PLATFORM_NAME") == name), {}))
            info["platform"] = name or p.get("CL_PLATFORM_NAME", "")
            info["platform_version"] = p.get("CL_PLATFORM_VERSION", "")
            info["driver"] = e.get("CL_DRIVER_VERSION", "")
            t = e.get("CL_DEVICE_TYPE", "")
            info["type"] = "GPU" if "GPU" in t else "CPU" if "CPU" in t else info["type"]
            break
    return info


def build_info():
    cache = _read(os.path.join(ROOT, "build", "CMakeCache.txt"))
    g = lambda k: (re.search(r"^" + k + r":\w+=(.*)$", cache, re.M) or [None, ""])[1].strip()
    version = g("CMAKE_PROJECT_VERSION")
    if not version:
        m = re.search(r"project\(lsqt-cl\s+VERSION\s+([\w.]+)", _read(os.path.join(ROOT, "CMakeLists.txt")))
        version = m[1] if m else "unknown"
    commit = _out(["git", "describe", "--always", "--dirty"], cwd=ROOT).strip() or "unknown"
    return {"version": version, "build_type": g("CMAKE_BUILD_TYPE") or "unknown", "commit": commit}


def sci(x, digits=2, short=False):
    """2.8e5 style: DIGITS significant figures, a bare exponent; plain for 0.01 <= x < 1000.
    SHORT: without trailing zeros (2e7)."""
    if x is None or x != x:
        return "—"
    if x == 0:
        return "0"
    if short and 0.01 <= abs(x) < 1000:
        return f"{x:g}"
    if 10 ** (digits - 1) <= abs(x) < 1000:
        return f"{x:.0f}"
    if 0.01 <= abs(x) < 1000:
        return f"{x:#.{digits}g}"
    m, e = f"{x:.{digits - 1}e}".split("e")
    if short and "." in m:
        m = m.rstrip("0").rstrip(".")
    return f"{m}e{int(e)}"


def render(rows, workloads, extra, started, binary):
    """The page's text. ROWS: one dict per workload (tools/bench_targets.py), in WORKLOADS' order;
    BINARY: the lsqt-cl measured."""
    cpu, mem, b = cpu_info(), memory_gib(), build_info()
    cl = opencl_info(binary, rows[0]["device"])
    gpu = cl["type"] == "GPU"
    command = "bash tools/bench.sh targets --doc" + ((" -- " + " ".join(extra)) if extra else "")
    cores = f"{cpu['cores']} cores, " if cpu["cores"] else ""
    vm = f", a {cpu['hypervisor']} virtual machine" if cpu["hypervisor"] else ""
    platform_line = (f"{cl['platform']}, `{cl['platform_version']}`, driver {cl['driver']}" if cl["platform"]
                     else "(clinfo not available)")
    table = ["| workload | command | wall s | CPU s | paths/s | events per CPU-s | NEE/s | start-up cold / cached s "
             "| error | efficiency | target |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
    for r, w in zip(rows, workloads):
        unit = "CPU-s" if w["kind"] == "cpu_s" else "events per CPU-s"
        target = (f"{'≤' if w['kind'] == 'cpu_s' else '≥'} {sci(w['target'], short=True)} {unit}: "
                  f"**{'met' if r['met'] else 'not met'}** ({w['reference']})")
        table.append(f"| {w['label']} | `{r['command']}` | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | "
                     f"{sci(r['paths_per_s'])} | {sci(r['events_per_cpu_s'])} | {sci(r['nee_per_s'])} | "
                     f"{r['startup_cold_wall_s']:.2f} / {r['startup_wall_s']:.2f} | {sci(r['max_rel_err'])} | "
                     f"{sci(r['efficiency'])} | {target} |")
    files = []
    for w in workloads:
        if w["file"]:
            files.append(f"- {w['name']}: `{w['file']}`, {w['about']}")
        else:
            files.append(f"- {w['name']}: {w['about']}\n\n  ```\n  " + "\n  ".join(w["text"].strip().splitlines())
                         + "\n  ```")
    files = "\n".join(files)
    kept = kept_gpu_section()
    if gpu:
        gpu_line = ("**GPUs.** The device measured here is a GPU: CPU s is then the host's time (the launches,\n"
                    "the RRSS choice) and wall s is the measure. The CPU figures come from\n"
                    "`bash tools/bench.sh targets --doc` with a CPU device.")
    elif kept:
        gpu_line = ("**GPUs.** A GPU runs the GPU code path\n"
                    "([architecture.md](architecture.md#the-cpu-and-gpu-code-paths)). Its figures are in\n"
                    "[GPUs](#gpus) below: `tools/bench_targets.py` run on the GPU machine with `-- -d gpu`, and\n"
                    "this command keeps that section as it is when it rewrites the page for a CPU.")
    else:
        gpu_line = ("**GPUs.** No GPU has been measured yet. NVIDIA and AMD figures will come from the same\n"
                    "command on a machine with such a GPU, the device chosen by lsqt-cl's `-d` after `--`:\n"
                    "`bash tools/bench.sh targets --doc -- -d gpu` (`-d` takes an index of\n"
                    "`lsqt-cl --list-devices`, a name substring, `cpu` or `gpu`). A GPU runs the GPU code path\n"
                    "([architecture.md](architecture.md#the-cpu-and-gpu-code-paths)); what its programs use\n"
                    "(registers, scratch, local memory per kernel, from offline builds for AMD and NVIDIA) is\n"
                    "tabled there.")
    text = f"""# Performance

Generated by `{command}` (`tools/bench_targets.py`, `tools/bench_doc.py`);
do not edit by hand: that command measures again and rewrites this page. Measured on {time.strftime('%Y-%m-%d', started)} at
commit `{b['commit']}` (lsqt-cl {b['version']}, {b['build_type']} build in `build/`).

## The machine

- CPU: {cpu['model']}; {cores}{cpu['logical']} logical CPUs, {cpu['nproc']} available to the process (nproc){vm}
- memory: {f'{mem:.1f} GiB' if mem else 'unknown'}
- OS: {os_name()}
- OpenCL device: `{cl['list_line'] or rows[0]['device']}`{(', flags `' + ' '.join(extra) + '`') if extra else ''}
- OpenCL platform: {platform_line}

## The targets

{chr(10).join(table)}

**How to read this.** Each workload runs four times: a 1-path run with an empty PoCL kernel
cache (`POCL_CACHE_DIR` in a fresh folder), an untimed full run that fills the cache, a
1-path run with the cache filled, and the timed full run, the row. *wall s* is the timed
run's elapsed time; *CPU s* is the user + sys time of the whole process (all its threads,
start-up included), so with PoCL's one thread per core it can exceed wall s. The machine
may be shared: other work lengthens wall s much more than CPU s, so CPU s is the fair measure
and the targets are set in it. Repeated runs still spread by several percent (5 to 10 % on a busy
machine), so compare rows measured together, not across pages. *paths/s*: paths of all
slices per second of the simulation (lsqt-cl's own clock, without start-up); *events per
CPU-s*: scattering events (layer and medium) of all paths per CPU second; *NEE/s*:
next-event evaluations per second of the simulation; *start-up cold / cached s*: wall
seconds of the 1-path runs (the OpenCL context, PoCL's compile when cold, the tables, the
RRSS pilot's walks and choice, the launches). *error*: the largest relative standard error
of the stored BSDF values over the slices (`max_rel_err` of the run's `--json`, the same as
`lsqt-cl info --json`), set by the least often reached stored direction, so it compares a
workload with itself (another run, device or build), not one workload with another;
*efficiency*: 1 / (error² × CPU s), the same for any `-p` once start-up is small, and twice
as large when the same error takes half the time. The target
column gives the target of the speed issue, met or not, and the original layered-sqt's CPU
seconds for the same workload as stated by the speed issue (another machine: an order of magnitude, not a ratio to trust to 10 %) (for the MCX-like slab, MCX-CL's
rate in events per second) for comparison.

{gpu_line}

## The workloads

Their sizes are those the targets are set at; `command` above runs each (`-R` starts over).

{files}
"""
    # the prose paragraphs filled to 92 columns (code spans may break: Markdown joins lines)
    def fill(p):  # no break inside a code span
        p = re.sub(r"`[^`]*`", lambda m: m[0].replace(" ", "\0"), " ".join(p.split()))
        return textwrap.fill(p, 92, break_long_words=False, break_on_hyphens=False).replace("\0", " ")
    text = "\n\n".join(fill(p) if p.startswith(("**How", "**GPUs")) else p for p in text.split("\n\n"))
    return text + ("\n" + kept if kept and not gpu else "")


def kept_gpu_section(path=DOC):
    """The page's "## GPUs", "## Bands", "## The RRSS pilot", "## Memory" and "## Beside the
    original" sections, each to the next "## " heading or the end: measured on a GPU machine,
    or by tools/bench_bands.py, bench_pilot.py, bench_memory.py and bench_original.py, which
    this command does not run, so they are kept."""
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError:
        return ""
    found = [m.group(0).rstrip("\n") + "\n" for m in re.finditer(r"^## (?:GPUs|Bands|The RRSS pilot|Memory|Beside the original)\n.*?(?=^## |\Z)", text, re.S | re.M)]
    return "\n".join(found)


def write_atomic(text, path=DOC):
    """Write TEXT to PATH through a temporary file beside it and a rename."""
    d = os.path.dirname(path)
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp", dir=d)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    return path
