#!/usr/bin/env bash
# lsqt-cl info and lssinfo: the same text from both; the values they print equal those of
# the run's --json summary; info --json parses and has the stable fields; no OpenCL is
# needed; bad flags and every kind of bad file exit 2 with a message naming the file and
# the problem, and a FIFO is never opened.
# usage: test_info.sh LSQT_CL LSSINFO EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN INFO EX -- "$@"
cli_workdir

# Two runs: a Lambertian layer that reflects and transmits (R near 0.3, T near 0.5, R + T
# = 0.8, exact point estimates), and the slab with a seed that is not the default one
# (R, T, delta_T and their errors differ from slice to slice).
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.3 fT=0.5\nMedium\n' > L.lsqt
cp "$EX/slab.lsqt" S.lsqt
"$BIN" -q -p 2000 -wo 4 -wi 16 --json L.json L.lsqt && ok || bad "Lambertian run"
"$BIN" -q -p 2000 -wo 4 -wi 16 -s 7 --json S.json S.lsqt && ok || bad "slab run"

# The help of lsqt-cl names the subcommand; info's own help and usage.
expect 0 "lsqt-cl info FILE.lss" -- "$BIN" --help
expect 0 "usage: lsqt-cl info FILE.lss [--json PATH [--bsdf]]" -- "$BIN" info --help
expect 0 "usage: lssinfo FILE.lss [--json PATH [--bsdf]]" -- "$INFO" -h

# Both programs print the same text (they are one function, host/commands/info.c), to stdout.
for f in L S; do
  "$BIN" info $f.lsqt.lss >$f.info.txt 2>$f.info.err && ok || bad "lsqt-cl info $f: $(cat $f.info.err)"
  "$INFO" $f.lsqt.lss >$f.lssinfo.txt 2>&1 && ok || bad "lssinfo $f: $(cat $f.lssinfo.txt)"
  [ -s $f.info.txt ] && [ ! -s $f.info.err ] && cmp -s $f.info.txt $f.lssinfo.txt && ok \
    || bad "lsqt-cl info and lssinfo print different text for $f"
  "$INFO" $f.lsqt.lss --json $f.info.json >/dev/null && ok || bad "lssinfo --json $f"
  "$BIN" info --json=- $f.lsqt.lss >$f.stdout.json 2>$f.stderr.txt && ok || bad "info --json=- $f"
  python3 -m json.tool $f.stdout.json >/dev/null && cmp -s $f.stdout.json $f.info.json && ok \
    || bad "info --json - is not the same valid JSON as --json FILE"
  # With the JSON on stdout the text goes to stderr, whole.
  cmp -s $f.stderr.txt $f.info.txt && ok || bad "info --json -: text not on stderr"
done

# The values info prints must equal the run's --json values: the run's summary comes from
# lsqt_estimates of the state the run then writes as the LSS, and info computes
# lsqt_estimates of that same state read back (the LSS round-trips the integer tallies
# exactly, test_lss), with the same code on the same machine, so the doubles are equal.
# The JSONs print 17 significant digits and the text the shortest digits that read back as
# the same double, so even the parsed numbers are equal; the tolerance of 1e-12 relative
# is only a margin, far below any real error (another slice, R for T, a lost tally).
check_values() { # RUN.json INFO.txt INFO.json SEED TRANSMITS PATHS
  python3 - "$@" <<'PY'
import json, math, re, sys
run = json.load(open(sys.argv[1]))
text = open(sys.argv[2]).read()
info = json.load(open(sys.argv[3]))
seed, transmits, paths = int(sys.argv[4]), sys.argv[5] == "1", int(sys.argv[6])
p = []
def eq(a, b, what):
    if a is None or b is None or not math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-300):
        p.append("%s: %r vs %r" % (what, a, b))
# the text
blocks = re.findall(r"^slice (\d+): theta_o (\S+) deg \((\S+) rad\), (\d+) paths\n"
                    r"  R +(\S+) \+- (\S+)\n  T +(\S+) \+- (\S+)\n  delta_T +(\S+) \+- (\S+)\n"
                    r"  max rel err (\S+), non-finite (\d+), paths cut (\d+)$", text, re.M)
if len(blocks) != len(run["slices"]) or len(blocks) != 4: p.append("text has %d slice blocks" % len(blocks))
for b, s in zip(blocks, run["slices"]):
    k = int(b[0])
    eq(float(b[2]), s["theta_o"], "text theta_o rad %d" % k)
    if abs(math.radians(float(b[1])) - s["theta_o"]) > 1e-5: p.append("text theta_o deg %d: %s" % (k, b[1]))
    if int(b[3]) != s["paths"] or s["paths"] != paths: p.append("text paths %d" % k)
    eq(float(b[4]), s["R"], "text R %d" % k)
    eq(float(b[6]), s["T"], "text T %d" % k)
    eq(float(b[8]), s["delta_T"], "text delta_T %d" % k)
    for v, w, what in ((b[5], s["R_err"], "R_err"), (b[7], s["T_err"], "T_err"), (b[10], s["max_rel_err"], "max_rel_err")):
        if not math.isclose(float(v), w, rel_tol=6e-3, abs_tol=0): p.append("text %s %d: %s vs %r" % (what, k, v, w))
    if not math.isclose(float(b[9]), info["slices"][k]["delta_T_err"] or 0.0, rel_tol=6e-3, abs_tol=0):
        p.append("text delta_T err %d: %s vs %r" % (k, b[9], info["slices"][k]["delta_T_err"]))
    if int(b[11]) != 0 or int(b[12]) != s["cut_paths"]: p.append("text non-finite / cut %d" % k)
for line in ("seed: %d" % seed, "assembly hash: %s" % run["assembly_hash"], "precision: float",
             "transmits: %s" % ("yes" if transmits else "no"), "slices: 4, wi per slice: 16",
             "paths: %d per slice" % paths, "flags: none", "ranges: [0, %d) on every slice" % paths,
             "format: LSS version 6; chunk 256 paths, 32 batches, 40 fixed-point bits, histogram 2 x 32 x 16 = 1024 bins"):
    if not re.search("^" + re.escape(line), text, re.M): p.append("text lacks '%s'" % line)
asm = re.search(r"^assembly:\n((?:  .*\n)+)", text, re.M)
def same_token(a, b):  # the text prints numbers in their shortest form, the JSON as stored
    if a == b:
        return True
    ka, _, va = a.partition("=")
    kb, _, vb = b.partition("=")
    try:
        return ka == kb and float(va) == float(vb)
    except ValueError:
        return False
shown = [l[2:].split(" ") for l in asm.group(1).splitlines()] if asm else []
stored = [l.split(" ") for l in info.get("assembly", "").rstrip("\n").split("\n")]
if len(shown) != len(stored) or not all(len(x) == len(y) and all(map(same_token, x, y)) for x, y in zip(shown, stored)):
    p.append("text assembly differs from the JSON's")
# the JSON: every stable field, equal to the run's
for k in ("version", "seed", "hash", "double", "transmits", "n_wi", "assembly", "flags", "ranges", "slices"):
    if k not in info: p.append("JSON lacks %s" % k)
if p: sys.exit("; ".join(p))
if info["version"] != 6 or info["seed"] != seed or info["seed"] != run["seed"]: p.append("JSON version/seed")
if info["hash"] != run["assembly_hash"] or not re.fullmatch(r"[0-9a-f]{16}", info["hash"]): p.append("JSON hash")
if info["double"] is not False or info["double"] != run["double"] or info["transmits"] is not transmits: p.append("JSON double/transmits")
if info["n_wi"] != 16 or info["flags"] != 0 or info["ranges"] != [[0, paths]]: p.append("JSON n_wi/flags/ranges")
if "LambertianBsdf" not in info["assembly"] and "NullBsdf" not in info["assembly"]: p.append("JSON assembly")
if len(info["slices"]) != 4: p.append("JSON slice count")
for k, (a, s) in enumerate(zip(info["slices"], run["slices"])):
    for f in ("theta_o", "R", "R_err", "T", "T_err", "delta_T", "max_rel_err"):
        eq(a.get(f), s[f], "JSON %s %d" % (f, k))
    if a.get("paths") != s["paths"] or a.get("n_nonfinite") != 0 or "delta_T_err" not in a: p.append("JSON paths/n_nonfinite/delta_T_err %d" % k)
if p: sys.exit("; ".join(p))
PY
}
check_values L.json L.info.txt L.info.json 0 1 2000 && ok || bad "Lambertian: info differs from the run"
check_values S.json S.info.txt S.info.json 7 1 2000 && ok || bad "slab: info differs from the run"
# The checks above can fail: the values differ between slices and R differs from T.
python3 - S.json L.json <<'PY' && ok || bad "the runs cannot tell R from T or one slice from another"
import json, sys
s, l = json.load(open(sys.argv[1]))["slices"], json.load(open(sys.argv[2]))["slices"]
assert len({x["R"] for x in s}) == 4 and len({x["T"] for x in s}) == 4 and all(x["R"] != x["T"] for x in s)
assert len({x["R"] for x in l}) == 4 and all(abs(x["R"] + x["T"] - 0.8) < 1e-6 for x in l)
assert all(abs(x["R"] - 0.3) < 5 * x["R_err"] and abs(x["T"] - 0.5) < 5 * x["T_err"] for x in l)
PY
# Continued: info follows the paths in all.
"$BIN" -q -p 1000 --json S2.json S.lsqt && "$INFO" S.lsqt.lss >S2.txt && "$INFO" S.lsqt.lss --json S2.info.json >/dev/null \
  && check_values S2.json S2.txt S2.info.json 7 1 3000 && ok || bad "continued slab: info differs from the run"
# A reflector in double precision: "precision: double", "transmits: no".
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.6\nMedium\n' > D.lsqt
"$BIN" -q --double -p 500 -wo 4 -wi 16 D.lsqt && ok || bad "double run"
expect 0 "precision: double" -- "$INFO" D.lsqt.lss
expect 0 "transmits: no" -- "$INFO" D.lsqt.lss
"$INFO" D.lsqt.lss --json - 2>/dev/null | python3 -c 'import json, sys; j = json.load(sys.stdin); sys.exit(not (j["double"] is True and j["transmits"] is False))' \
  && ok || bad "double reflector: JSON double/transmits"
# The assembly's numbers in their shortest form (alpha=0.2, eta=1.33), the JSON's canonical
# text as stored (its hash is of it: 0.20000000000000001).
printf 'Medium\nLayer z=0 MicrosurfaceDielectricBsdf alpha=0.2\nMedium eta=1.33\n' > A.lsqt
"$BIN" -q -p 100 -wo 4 -wi 16 --wi-spread A.lsqt && ok || bad "alpha 0.2 run"
expect 0 "  Layer z=0 MicrosurfaceDielectricBsdf alpha=0.2 kR=1 kT=1 iter_count=2 use_multiple_scattering=true" -- "$INFO" A.lsqt.lss
expect 0 "  Medium eta=1.33 mua=0 mus=0" -- "$INFO" A.lsqt.lss
"$INFO" A.lsqt.lss | grep -q "0000000" && bad "info prints a number longer than it needs: $("$INFO" A.lsqt.lss | grep 0000000)" || ok
"$INFO" A.lsqt.lss --json - 2>/dev/null | grep -q "alpha=0.20000000000000001" && ok || bad "JSON canonical text changed"
# stdin is read when FILE is -.
"$INFO" - <S.lsqt.lss | grep -q "^file: <stdin>" && ok || bad "lssinfo - (stdin)"

# No OpenCL: info works without any OpenCL platform (a run then exits 3).
mkdir -p novendors
expect 3 "" -- env OCL_ICD_VENDORS="$T/novendors" "$BIN" -p 100 -wo 4 -wi 16 --lss nov.lss -o nov.raw L.lsqt
env OCL_ICD_VENDORS="$T/novendors" "$BIN" info L.lsqt.lss >nocl.txt 2>&1 && cmp -s nocl.txt L.info.txt && ok \
  || bad "info needs OpenCL: $(cat nocl.txt)"

# Bad flags: exit 2 with the usage.
for prog in "$BIN info" "$INFO"; do
  # shellcheck disable=SC2086
  {
    expect 2 "no LSS file given" -- $prog
    expect 2 "usage:" -- $prog
    expect 2 "unknown option '--bogus'" -- $prog --bogus L.lsqt.lss
    expect 2 "usage:" -- $prog -x L.lsqt.lss
    expect 2 "--json needs a value" -- $prog L.lsqt.lss --json
    expect 2 "bad value '' for --json" -- $prog L.lsqt.lss --json=
    expect 2 "more than one file: 'L.lsqt.lss' and 'S.lsqt.lss'" -- $prog L.lsqt.lss S.lsqt.lss
    expect 2 "--json given twice" -- $prog L.lsqt.lss --json a.json --json b.json
  }
done
cp L.lsqt.lss keep.lss
expect 2 "the JSON output 'keep.lss' would replace the input" -- "$INFO" keep.lss --json keep.lss
cmp -s keep.lss L.lsqt.lss && ok || bad "--json over the input changed it"

# Bad files: each exits 2, names the file and says what is wrong.
n=$(wc -c < L.lsqt.lss)
head -c 1000 L.lsqt.lss > trunc.lss
head -c 40 L.lsqt.lss > trunc_header.lss
head -c $((n - 1)) L.lsqt.lss > trunc_crc.lss
cp L.lsqt.lss flip.lss
mid=$((n / 2))
old=$(od -An -tu1 -j $mid -N1 flip.lss | tr -d ' ')
printf "$(printf '\\%03o' $(((old + 1) % 256)))" | dd of=flip.lss bs=1 seek=$mid conv=notrunc status=none
cmp -s flip.lss L.lsqt.lss && bad "the byte flip changed nothing"
cp L.lsqt.lss magic.lss
printf 'XSQT' | dd of=magic.lss bs=1 seek=0 conv=notrunc status=none
cp L.lsqt.lss v1.lss
printf '\001\000\000\000' | dd of=v1.lss bs=1 seek=8 conv=notrunc status=none
cp L.lsqt.lss v8.lss
printf '\010\000\000\000' | dd of=v8.lss bs=1 seek=8 conv=notrunc status=none
: > empty.lss
printf 'Medium\nLayer z=0 NullBsdf\nMedium\n' > text.lss
mkdir dir.lss
mkfifo fifo.lss
cp L.lsqt.lss long.lss
printf 'x' >> long.lss
while IFS='|' read -r file text; do
  [ -z "$file" ] && continue
  for prog in "$BIN info" "$INFO"; do
    # A FIFO with no writer would block an open for reading: 10 s is a hang.
    # shellcheck disable=SC2086
    out=$(timeout -k 2 10 $prog "$file" 2>&1)
    rc=$?
    if [ "$rc" = 2 ] && grep -qF -- "'$file'" <<<"$out" && grep -qF -- "$text" <<<"$out"; then ok
    else bad "[$prog $file] exit $rc, expected 2 with '$file' and '$text': $out"; fi
  done
done <<TABLE
trunc.lss|truncated at byte 1000 (its header announces $n bytes
trunc_header.lss|truncated at byte 40 (inside the 132-byte header)
trunc_crc.lss|truncated at byte $((n - 1))
flip.lss|corrupt LSS file (CRC mismatch
long.lss|corrupt LSS file: $((n + 1)) bytes where its header announces $n
magic.lss|not an LSS file (bad magic)
text.lss|not an LSS file (bad magic)
v1.lss|LSS version 1, this lsqt-cl reads versions 5 to 7
v8.lss|LSS version 8, this lsqt-cl reads versions 5 to 7
empty.lss|empty file (not an LSS file)
dir.lss|is a directory, not an LSS file
fifo.lss|is a FIFO, not an LSS file
/dev/null|is a character device, not an LSS file
missing.lss|cannot open 'missing.lss': No such file or directory
TABLE
# Files with a valid CRC whose content this build cannot take, and raised device flags
# (each made with the CRC recomputed: zlib's CRC-32 is the LSS's; offsets from lss.h: flags at
# byte 60, n_slices at 64).
python3 - L.lsqt.lss <<'PY' || bad "could not make the patched LSS files"
import struct, sys, zlib
d = open(sys.argv[1], "rb").read()[:-4]
def put(name, off, value):
    b = bytearray(d)
    b[off:off + 4] = struct.pack("<I", value)
    open(name, "wb").write(bytes(b) + struct.pack("<I", zlib.crc32(bytes(b))))
put("chunk128.lss", 12, 128)     # layout: chunk
put("noslices.lss", 80, 0)       # n_slices (after flags, direction method, rx, pilot paths)
put("flags.lss", 60, 2 | 8)      # flags: non-finite and an unknown bit
put("same.lss", 60, 0)           # unchanged (flags 0): proves the CRC is recomputed right
PY
expect 0 "flags: none" -- "$INFO" same.lss
expect 2 "'chunk128.lss': LSS tally layout differs from this build's (chunk 128, this build 256)" -- "$INFO" chunk128.lss
expect 2 "'noslices.lss': corrupt LSS header (slices 0," -- "$BIN" info noslices.lss
expect 0 "flags: 0xa (non-finite, unknown 0x8)" -- "$INFO" flags.lss
"$INFO" flags.lss --json - 2>/dev/null | python3 -c 'import json, sys; j = json.load(sys.stdin); sys.exit(not (j["flags"] == 10 and j["flag_names"] == ["non-finite", "unknown 0x8"]))' \
  && ok || bad "JSON flags of flags.lss"

# Nothing was written for any of them, and the FIFO is still a FIFO (never opened).
[ -p fifo.lss ] && ok || bad "fifo.lss is no longer a FIFO"
ls ./*.json.tmp* ./*.tmp.* >/dev/null 2>&1 && bad "temporary files left behind" || ok

# --bsdf: the directions with values and errors, only in the JSON
expect 2 "give --json PATH too" -- "$BIN" info --bsdf L.lsqt.lss
"$BIN" info L.lsqt.lss --json b.json --bsdf >/dev/null
python3 -c 'import json, sys; j = json.load(open(sys.argv[1])); s = j["slices"][0]; assert len(s["bsdf"]) == j["n_wi"] and all(len(d) == 5 for d in s["bsdf"])' b.json && ok || bad "--bsdf: no direction list of n_wi entries"
finish test_info
