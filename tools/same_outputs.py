#!/usr/bin/env python3
"""same_outputs.py: proof that a change of code left the results alone.

Runs one lsqt-cl binary on every LSQT file under examples/ in several ways (RRSS, an even
spread, double precision, the side from below, a regular grid and its NetCDF export, -H,
a continued LSS, three bands, the GPU code path) with fixed seeds, and writes a manifest: the SHA-256 of every RAW, LSS,
NetCDF and JSON file it made (JSON without its clock and device fields, which change from
run to run), and each command's exit status. Two manifests, one from the binary before a
change and one from after, must be equal for a change that claims not to alter behaviour.

  python3 tools/same_outputs.py BUILD/lsqt-cl OUT.manifest [--keep DIR]
  python3 tools/same_outputs.py --compare BEFORE.manifest AFTER.manifest

The runs are small (seconds each): byte equality needs no statistics.
"""
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLOCK_KEYS = ("seconds", "paths_per_second", "events_per_second", "nee_evaluations_per_second", "device", "file")

# name, flags; every run is small and seeded. "+" runs twice on one LSS (the second adds paths).
RUNS = [
    ("rrss", ["-p", "1500", "-wo", "4", "-wi", "16", "-s", "11"]),
    ("spread", ["-p", "1000", "-wo", "4", "-wi", "16", "--wi-spread", "-s", "12"]),
    ("double", ["-p", "800", "-wo", "4", "-wi", "16", "--double", "-s", "13"]),
    ("below", ["-p", "800", "-wo", "4", "-wi", "16", "--from-below", "-s", "14"]),
    ("grid", ["-p", "500", "--grid", "3,3,4", "-s", "15"]),
    ("hemi", ["-p", "800", "-wo", "4", "-wi", "16", "-H", "-s", "16"]),
    ("continued+", ["-p", "700", "-wo", "4", "-wi", "16", "-s", "17"]),
    ("bands", ["-p", "600", "-wo", "4", "-wi", "16", "--wavelengths", "450:650:100", "-s", "18"]),
    ("gpu", ["-p", "600", "-wo", "4", "-wi", "16", "-s", "19"]),
]
# Runs made through another code path: the GPU's (next-event records), on this device.
ENV = {"gpu": {"LSQT_GPU_PATH": "1"}}


def clean_json(path):
    def strip(v):
        if isinstance(v, dict):
            return {k: strip(x) for k, x in v.items() if k not in CLOCK_KEYS}
        if isinstance(v, list):
            return [strip(x) for x in v]
        return v

    with open(path) as f:
        return json.dumps(strip(json.load(f)), sort_keys=True).encode()


def digest(path):
    data = clean_json(path) if path.endswith(".json") else open(path, "rb").read()
    return hashlib.sha256(data).hexdigest()


def run_all(exe, manifest, keep):
    exe = os.path.abspath(exe)
    examples = sorted(os.path.relpath(os.path.join(d, f), ROOT)
                      for d, _, fs in os.walk(os.path.join(ROOT, "examples")) for f in fs if f.endswith(".lsqt"))
    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        work = keep or tmp
        for ex in examples:
            for name, flags in RUNS:
                d = os.path.join(work, ex.replace("/", "_") + "." + name)
                os.makedirs(d, exist_ok=True)
                src = os.path.join(d, "in.lsqt")
                with open(os.path.join(ROOT, ex), "rb") as f, open(src, "wb") as g:
                    g.write(f.read())
                # the tables an example names (@tables/...) beside it
                tables = os.path.join(ROOT, os.path.dirname(ex), "tables")
                if os.path.isdir(tables) and not os.path.exists(os.path.join(d, "tables")):
                    shutil.copytree(tables, os.path.join(d, "tables"))
                # an example with spectral tables (KEY=@FILE) is read at wavelengths
                spectral = "=@" in open(src).read() and "--wavelengths" not in flags
                extra = ["--wavelengths", "450:650:100"] if spectral else []
                for rep in range(2 if name.endswith("+") else 1):
                    cmd = [exe, "-q", "--json", "run%d.json" % rep] + flags + extra + ["in.lsqt"]
                    r = subprocess.run(cmd, cwd=d, capture_output=True, env=dict(os.environ, **ENV.get(name, {})))
                    lines.append("%s %s run%d exit %d" % (ex, name, rep, r.returncode))
                if os.path.exists(os.path.join(d, "in.lsqt.lss")):
                    subprocess.run([exe, "info", "in.lsqt.lss", "--json", "info.json"], cwd=d, capture_output=True)
                    if name == "grid":
                        r = subprocess.run([exe, "export", "in.lsqt.lss", "-o", "out.nc"], cwd=d, capture_output=True)
                        lines.append("%s %s export exit %d" % (ex, name, r.returncode))
                for f in sorted(os.listdir(d)):
                    if f not in ("in.lsqt", "tables") and not f.endswith(".lock"):
                        lines.append("%s %s %s %s" % (ex, name, f, digest(os.path.join(d, f))))
                print("%-40s %-11s done" % (ex, name), file=sys.stderr)
    with open(manifest, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("%s: %d lines, %d files" % (manifest, len(lines), sum(" exit " not in x for x in lines)))


def compare(a, b):
    la, lb = open(a).read().splitlines(), open(b).read().splitlines()
    if la == lb:
        print("identical: %d lines (%d files hashed, %d exit statuses)"
              % (len(la), sum(" exit " not in x for x in la), sum(" exit " in x for x in la)))
        return 0
    import difflib
    sys.stdout.writelines(difflib.unified_diff([x + "\n" for x in la], [x + "\n" for x in lb], a, b))
    return 1


def main(argv):
    if len(argv) == 3 and argv[0] == "--compare":
        return compare(argv[1], argv[2])
    if len(argv) in (2, 4) and (len(argv) == 2 or argv[2] == "--keep"):
        run_all(argv[0], argv[1], os.path.abspath(argv[3]) if len(argv) == 4 else None)
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
