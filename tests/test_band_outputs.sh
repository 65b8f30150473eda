#!/usr/bin/env bash
# The files of a run with bands (docs/guide.md, "Colour and spectra"): every band's RAW is
# named and checked before any work (a directory in a band's place, a clash with another
# output, the input, a table or --wi-file); per-band names are refused beside a device, a
# FIFO or stdout; --no-raw writes none; and when writing fails (a full file system) every
# file not written is named, no RAW older than the LSS is left, and the ones written are
# this run's, byte for byte (a reference run elsewhere). Device nodes are made here with
# mknod, never the system's.
# usage: test_band_outputs.sh LSQT_CL
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN -- "$@"
cli_workdir

printf 'Medium\nLayer z=0 LambertianBsdf fR=0.6,0.5,0.4 fT=0\nMedium\n' >x.lsqt
W=(--wavelengths 450,550,650)
R=(-p 500 -wo 4 -wi 16)
nothing_new() { # nothing_new NAME: only the files listed in keep.txt exist
  local now
  now=$(ls | grep -vx keep.txt | sort | tr '\n' ' ')
  [ "$now" = "$(sort keep.txt | tr '\n' ' ')" ] && ok || bad "$1: files written by a refused run: $now"
}
snapshot() { ls | grep -vx keep.txt | sort >keep.txt; }

# A directory where one band's RAW goes: refused before any work, naming it; two: both.
mkdir x.lsqt.550nm.raw
snapshot
expect 1 "cannot write 'x.lsqt.550nm.raw': it is a directory (nothing simulated)" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt
nothing_new "a directory at one band's RAW"
mkdir x.lsqt.650nm.raw
snapshot
expect 1 "cannot write 'x.lsqt.650nm.raw': it is a directory" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt
rmdir x.lsqt.550nm.raw x.lsqt.650nm.raw

# Clashes, each refused (exit 2) before anything is written: the LSS or the JSON on a
# band's RAW, the input, a table (one band too), --wi-file.
snapshot
expect 2 "two outputs would be written to 'x.450nm.raw'" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt -o x.raw --lss x.450nm.raw
expect 2 "two outputs would be written to 'x.550nm.raw'" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt -o x.raw --json x.550nm.raw
ln -s x.650nm.raw y.raw # a link to a band's RAW, not there yet
snapshot
expect 2 "(also named 'y.raw')" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt -o x.raw --json y.raw
nothing_new "clashes"
rm y.raw
cp x.lsqt x.450nm.raw
snapshot
expect 2 "the output 'x.450nm.raw' would replace the input 'x.450nm.raw'" -- "$BIN" "${W[@]}" "${R[@]}" x.450nm.raw -o x.raw
nothing_new "the input as a band's RAW"
cmp -s x.lsqt x.450nm.raw && ok || bad "the input named like a band's RAW was changed"
rm x.450nm.raw
printf '400 0.5\n700 0.7\n' >t2.raw
printf 'Medium\nLayer z=0 LambertianBsdf fR=@t2.raw fT=0\nMedium\n' >t.lsqt
snapshot
expect 2 "would replace the table './t2.raw'" -- "$BIN" --wavelengths 550 "${R[@]}" t.lsqt -o t2.raw
expect 2 "would replace the table './t2.raw'" -- "$BIN" --wavelengths 450,550 "${R[@]}" t.lsqt --json t2.raw
nothing_new "a table as an output"
[ "$(cat t2.raw)" = "$(printf '400 0.5\n700 0.7')" ] && ok || bad "the table was changed"
# a phase function's table (cos theta, value) is an input too, one band or several
printf -- '-1 1\n1 1\n' >ph.raw
printf 'Medium\nLayer z=1 NullBsdf\nMedium mus=1 TabulatedPhase table=@ph.raw\nLayer z=0 NullBsdf\nMedium\n' >p.lsqt
snapshot
expect 2 "would replace the phase table './ph.raw'" -- "$BIN" "${R[@]}" p.lsqt -o ph.raw
expect 2 "would replace the phase table './ph.raw'" -- "$BIN" --wavelengths 450,550 "${R[@]}" p.lsqt --json ph.raw
nothing_new "a phase table as an output"
[ "$(cat ph.raw)" = "$(printf -- '-1 1\n1 1')" ] && ok || bad "the phase table was changed"
rm ph.raw
printf '0 0 1\n0.6 0 0.8\n' >dirs.txt
snapshot
expect 2 "would replace the --wi-file 'dirs.txt'" -- "$BIN" "${W[@]}" -p 500 -wo 4 --wi-file dirs.txt x.lsqt --json dirs.txt
nothing_new "--wi-file as an output"

# Per-band names beside stdout, a device or a FIFO: refused, nothing made beside them.
snapshot
expect 2 "a run with 3 bands writes one RAW per band, named from the RAW name (OUT.450nm, ...), and '-' is stdout" -- \
  "$BIN" "${W[@]}" "${R[@]}" x.lsqt -o -
mkfifo fifo
snapshot
expect 2 "and 'fifo' is a FIFO: give -o a file name, or --no-raw" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt -o fifo
nothing_new "-o FIFO with bands"
if mknod null c 1 3 2>/dev/null; then
  snapshot
  expect 2 "and 'null' is a character device" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt -o null
  nothing_new "-o device with bands"
  # one band: the device takes the RAW, as before
  printf 'Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n' >one.lsqt
  expect 0 "" -- "$BIN" -q "${R[@]}" one.lsqt -o null
  rm one.lsqt*
else
  echo "skip: cannot mknod here (not root?): device checks skipped"
fi

# Published together: while one band's RAW waits for a FIFO's reader, the band before it
# is still the previous file (a kill now would leave no mix of old and new); once read,
# every band is this run's.
rm -f x.lsqt.*
mkfifo x.lsqt.550nm.raw
echo old >x.lsqt.450nm.raw
"$BIN" "${W[@]}" "${R[@]}" x.lsqt >held.log 2>&1 &
pid=$!
for _ in $(seq 300); do grep -q "waiting for a process to read the FIFO" held.log && break; sleep 0.1; done
grep -q "waiting for a process to read the FIFO" held.log && [ -s x.lsqt.lss ] && ok || bad "no FIFO wait: $(cat held.log)"
[ "$(cat x.lsqt.450nm.raw)" = old ] && ok || bad "a band's RAW was replaced before the others were written"
timeout 60 cat x.lsqt.550nm.raw >got550.raw
wait $pid
rc=$?
[ "$rc" = 0 ] && head -1 x.lsqt.450nm.raw | grep -q "^RAWBH10A" && head -1 got550.raw | grep -q "^RAWBH10A" &&
  head -1 x.lsqt.650nm.raw | grep -q "^RAWBH10A" && ok || bad "after the FIFO was read: exit $rc, $(cat held.log)"
rm -f x.lsqt.* got550.raw held.log

# --no-raw: the LSS and the JSON only; with -o or -H it contradicts itself; from stdin
# without --lss or --json it would write nothing.
rm -f ./*.lss
snapshot
expect 0 "" -- "$BIN" -q "${W[@]}" "${R[@]}" x.lsqt --no-raw --json n.json
[ -s x.lsqt.lss ] && [ -s n.json ] && ok || bad "--no-raw: no LSS or JSON"
ls ./*.raw >/dev/null 2>&1 && [ "$(ls ./*.raw)" != "./t2.raw" ] && bad "--no-raw wrote a RAW: $(ls ./*.raw)" || ok
rm -f x.lsqt.lss n.json
expect 2 "--no-raw writes no RAW file, and -o names one" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt --no-raw -o a.raw
expect 2 "--no-raw writes no RAW file, and -H names one" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt --no-raw -H
expect 2 "--no-raw: this run would write nothing" -- "$BIN" "${W[@]}" "${R[@]}" - --no-raw <x.lsqt
nothing_new "refused --no-raw runs"

# A rename that fails when the files are published (the 550 nm RAW is a bind mount:
# EBUSY): that file is named, the others are published.
rm -f x.lsqt.*.raw
touch x.lsqt.550nm.raw && echo old >bm.src
if mount --bind bm.src x.lsqt.550nm.raw 2>/dev/null; then
  cli_mounts+=("$(pwd -P)/x.lsqt.550nm.raw")
  expect 1 "1 output could not be written: x.lsqt.550nm.raw" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt
  [ -s x.lsqt.450nm.raw ] && [ -s x.lsqt.650nm.raw ] && ok || bad "the RAW files beside the failed rename were not published"
  [ -z "$(find . -name '*.tmp.*')" ] && ok || bad "temporaries left after a failed rename: $(find . -name '*.tmp.*')"
else
  echo "skip: cannot bind-mount here (not root?): the failed rename is not checked"
fi

# Merge plans its files as a run does: every band's RAW checked before anything is
# written (a directory in one band's place: nothing written), no output on another or on
# an input shard (OUT.lss may be one: the sum replaces it), no per-band names beside stdout.
for k in 0 1; do expect 0 "" -- "$BIN" "${W[@]}" "${R[@]}" x.lsqt --wi-spread --lss m.lss --shard $k/2; done
mkdir mm.550nm.raw
snapshot
expect 1 "cannot write 'mm.550nm.raw': it is a directory (nothing written)" -- "$BIN" merge mm.lss m.shard-0-of-2.lss m.shard-1-of-2.lss -o mm.raw
nothing_new "merge with a directory at one band's RAW"
rmdir mm.550nm.raw
snapshot
expect 2 "two outputs would be written to 'mm.450nm.raw'" -- "$BIN" merge mm.lss m.shard-0-of-2.lss m.shard-1-of-2.lss -o mm.raw --json mm.450nm.raw
expect 2 "the output 'm.shard-1-of-2.lss' would replace the input 'm.shard-1-of-2.lss'" -- "$BIN" merge mm.lss m.shard-0-of-2.lss m.shard-1-of-2.lss --json m.shard-1-of-2.lss
expect 2 "writes one RAW per band, named from the RAW name (OUT.450nm, ...), and '-' is stdout" -- "$BIN" merge mm.lss m.shard-0-of-2.lss m.shard-1-of-2.lss -o -
nothing_new "refused merges"
expect 0 "wrote m.shard-0-of-2.{450nm,...,650nm}.raw, m.shard-0-of-2.lss" -- "$BIN" merge m.shard-0-of-2.lss m.shard-0-of-2.lss m.shard-1-of-2.lss
"$BIN" info m.shard-0-of-2.lss | grep -q "^paths: 500 per slice" && ok || bad "the sum did not replace the input it was named after: $("$BIN" info m.shard-0-of-2.lss | head -5)"

# A full file system (a small tmpfs, as root). 32 bands; the reference continues in a
# folder of its own, so each RAW of this run has a reference with the same bytes.
if cli_tmpfs small 4m; then
  vals=$(python3 -c "print(','.join('%.3f' % (0.2 + 0.02 * i) for i in range(32)))")
  printf 'Medium\nLayer z=0 LambertianBsdf fR=%s fT=0\nMedium\n' "$vals" >s.lsqt
  S=(--wavelengths 400:710:10 -wo 4 -wi 16 -q)
  mkdir ref
  "$BIN" "${S[@]}" -p 500 s.lsqt -o ref/s.raw --lss ref/s.lss && "$BIN" "${S[@]}" -p 500 s.lsqt -o ref/s.raw --lss ref/s.lss &&
    ok || bad "reference runs"
  expect 0 "" -- "$BIN" "${S[@]}" -p 500 s.lsqt -o small/s.raw --lss s.lss
  [ "$(ls small/s.*.raw | wc -l)" = 32 ] && ok || bad "the first run wrote $(ls small/s.*.raw | wc -l) RAW files, not 32"
  # Room for ROOM RAW files (0.5: not one), not for 32: the run continues the LSS (on
  # another file system). Every RAW present must be this run's (the reference's bytes),
  # every one absent named, and the count right.
  size=$(stat -c %s "$(ls small/s.*.raw | head -1)")
  cp s.lss s0.lss
  mkdir prev && cp small/s.*.raw prev/ # the previous RAW files, at 500 paths
  for room in 0.5 6; do
    cp s0.lss s.lss
    rm -f small/filler
    cp prev/* small/
    avail=$(df -B1 --output=avail small | tail -1)
    fill=$(python3 -c "print(int($avail - $room * $size))")
    fallocate -l "$fill" small/filler 2>/dev/null || head -c "$fill" /dev/zero >small/filler
    "$BIN" "${S[@]}" -p 500 s.lsqt -o small/s.raw --lss s.lss >full.log 2>&1
    rc=$?
    python3 - full.log "$rc" "$room" <<'PY' && ok || bad "full file system, room for $room RAW: exit $rc: $(tail -3 full.log)"
import glob, os, re, sys
log, rc = open(sys.argv[1]).read(), int(sys.argv[2])
m = re.search(r"(\d+) outputs? could not be written: (.*)", log)
named = set(m.group(2).split(", ")) if m else set()
present, missing = 0, 0
for ref in sorted(glob.glob("ref/s.*.raw")):
    mine = "small/" + os.path.basename(ref)
    if os.path.exists(mine):
        present += 1
        if open(mine, "rb").read() != open(ref, "rb").read(): sys.exit("%s is not this run's RAW" % mine)
    else:
        missing += 1
        if mine not in named: sys.exit("%s is missing and not named" % mine)
if present + missing != 32: sys.exit("present %d, missing %d" % (present, missing))
if rc != (1 if missing else 0): sys.exit("exit %d with %d RAW files missing" % (rc, missing))
if missing and int(m.group(1)) != missing: sys.exit("the count says %s, %d are missing" % (m.group(1), missing))
if missing and "removed the previous" not in log: sys.exit("the stale RAW files were not said to be removed")
print("room for %s RAW: %d written, %d not" % (sys.argv[3], present, missing))
PY
    no_tmp=$(find small -name '*.tmp.*')
    [ -z "$no_tmp" ] && ok || bad "temporaries left: $no_tmp"
  done
  # The LSS on the full file system too: nothing moves on, the previous RAW files stay
  # whole (they match the LSS that is still there), and the message says so.
  rm -f small/s.*.raw small/filler s.lss
  expect 0 "" -- "$BIN" "${S[@]}" -p 500 s.lsqt -o small/s.raw --lss small/s.lss
  mkdir keep && cp small/s.* keep/
  dd if=/dev/zero of=small/filler bs=4k 2>/dev/null
  expect 1 "the LSS was not written: it still holds the previous state" -- "$BIN" "${S[@]}" -p 500 s.lsqt -o small/s.raw --lss small/s.lss
  for f in keep/*; do cmp -s "$f" "small/$(basename "$f")" || bad "$f changed although the LSS was not written"; done
  ok
else
  echo "skip: cannot mount a tmpfs here (not root?): full file system checks skipped"
fi

finish test_band_outputs
