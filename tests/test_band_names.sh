#!/usr/bin/env bash
# The names of a run's bands and the rules around them (docs/guide.md, "Colour and
# spectra"): every band's RAW has a label of its own, one format for all the bands of a
# run, so that `ls` lists them in wavelength order (0400nm before 1000nm, 400.0nm before
# 400.5nm; unnamed bands 00..11); wavelengths that no 9 decimals tell apart, a list of
# more than 4096 values and a --wavelengths STEP that does not divide the range are
# refused before any work; a table's errors (a NUL byte, the ends it covers, nm vs um,
# an empty path, a path with a space, a missing file with the OS's reason); continuing
# an LSS of other bands names the difference; merge names the RAWs it wrote.
# usage: test_band_names.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir

S="-p 1000 -wo 4 -wi 16 --wi-spread -q"
# lamb FILE FR: a Lambertian layer whose fR is FR (a list or @TABLE)
lamb() { printf 'Medium\nLayer z=0 LambertianBsdf fR=%s fT=0\nMedium\n' "$2" > "$1"; }
# raws NAME: the band RAWs of NAME, in ls order, one line
raws() { (ls -1 | grep -F "$1." | grep '\.raw$' | tr '\n' ' ') 2>/dev/null; }
# nothing NAME WHAT: no output of NAME was written
nothing() { if ls "$1"* 2>/dev/null | grep -qv '\.lsqt$'; then bad "$2: wrote $(ls "$1"*)"; else ok; fi; }

# ---- 1. labels: unique, one format, sorted by ls ----
lamb c.lsqt 0.5,0.4,0.3,0.2
expect 0 "" -- "$BIN" c.lsqt $S --wavelengths 500,500.0001,500.5,500.50000001
want="c.lsqt.500.00000000nm.raw c.lsqt.500.00010000nm.raw c.lsqt.500.50000000nm.raw c.lsqt.500.50000001nm.raw "
if [ "$(raws c.lsqt)" = "$want" ]; then ok; else bad "4 close bands: RAWs '$(raws c.lsqt)', want '$want'"; fi
# the RAW of 500.5 is band 3's: its header's wavelength in um
[ "$(sed -n 2p c.lsqt.500.50000000nm.raw)" = "1 0.5005" ] && ok || bad "500.5 nm's RAW is not band 3's"
lamb w.lsqt 0.5,0.4,0.3
expect 0 "" -- "$BIN" w.lsqt $S --wavelengths 412.5,1000,2500
want="w.lsqt.0412.5nm.raw w.lsqt.1000.0nm.raw w.lsqt.2500.0nm.raw "
if [ "$(raws w.lsqt)" = "$want" ]; then ok; else bad "412.5,1000,2500: RAWs '$(raws w.lsqt)', want '$want'"; fi
lamb u.lsqt 0.5,0.5,0.5,0.5,0.5,0.5,0.5,0.5,0.5,0.5,0.5,0.4
expect 0 "" -- "$BIN" u.lsqt $S
want="u.lsqt.00.raw u.lsqt.01.raw u.lsqt.02.raw u.lsqt.03.raw u.lsqt.04.raw u.lsqt.05.raw u.lsqt.06.raw u.lsqt.07.raw u.lsqt.08.raw u.lsqt.09.raw u.lsqt.10.raw u.lsqt.11.raw "
if [ "$(raws u.lsqt)" = "$want" ]; then ok; else bad "12 unnamed bands: RAWs '$(raws u.lsqt)', want '$want'"; fi
# no decimals up to 9 tell them apart: refused, naming the two bands
lamb t.lsqt 0.5,0.4,0.3
expect 2 "bands 2 and 3 (500 and 500.0000000001 nm) are too close" -- "$BIN" t.lsqt $S --wavelengths 400,500,500.0000000001
nothing t.lsqt "bands too close"

# ---- 2. one limit of 4096 bands, for lists too ----
# line 3 is wrong too: a list let through gets there, before any work, instead of running
for n in 4096 4097; do
  python3 -c "print('Medium\nLayer z=0 LambertianBsdf fT=0 fR=' + ','.join(['0.5'] * $n) + '\nMedium nope=1')" > big$n.lsqt
done
expect 2 "big4096.lsqt:3: error: band 1: unknown key at 'nope=1'" -- "$BIN" big4096.lsqt $S
mv big4097.lsqt big.lsqt
expect 2 "big.lsqt:2: error: too many values in a list" -- "$BIN" big.lsqt $S
expect 2 "at most 4096 comma-separated values, one per band (this list has 4097)" -- "$BIN" big.lsqt $S
nothing big.lsqt "4097 values"
expect 2 "--wavelengths: '1:4097:1': 4097 bands, at most 4096" -- "$BIN" big.lsqt $S --wavelengths 1:4097:1

# ---- 3. a range includes both ends: STEP must divide it; one prefix ----
expect 2 "--wavelengths: '400:2500:2000': STEP 2000 does not divide STOP - START (2100; both ends are included): use a STEP of 2100 or 1050, or STOP 2400 or 4400" -- "$BIN" c.lsqt $S --wavelengths 400:2500:2000
expect 2 "--wavelengths: bad wavelength 'a' (band 1)" -- "$BIN" c.lsqt $S --wavelengths a,500
for w in 400:2500:2000 400:700:x 400,400; do
  out=$("$BIN" c.lsqt $S --wavelengths $w 2>&1)
  if grep -qF -- "--wavelengths: --wavelengths" <<<"$out" || grep -qF -- "--wavelengths '" <<<"$out"; then
    bad "$w: the prefix repeats: $out"; else ok; fi
done
lamb r.lsqt 0.5,0.4,0.3,0.2
expect 0 "" -- "$BIN" r.lsqt $S --wavelengths 400:700:100
want="r.lsqt.400nm.raw r.lsqt.500nm.raw r.lsqt.600nm.raw r.lsqt.700nm.raw "
if [ "$(raws r.lsqt)" = "$want" ]; then ok; else bad "400:700:100: RAWs '$(raws r.lsqt)', want '$want'"; fi

# ---- 4. tables ----
printf '400 0.5\n500 0.4\0009\n700 0.3\n' > nul.txt
lamb tn.lsqt @nul.txt
expect 2 "nul.txt:2: a NUL byte (column 8)" -- "$BIN" tn.lsqt $S --wavelengths 450,650
nothing tn.lsqt "a table with a NUL byte"
printf '400 0.5\n699.9999 0.5\n' > short.txt
lamb ts.lsqt @short.txt
expect 2 "a table that covers 700 nm (it covers 400 to 699.9999 nm)" -- "$BIN" ts.lsqt $S --wavelengths 450,700
printf '0.4 0.5\n2.5 0.5\n' > um.txt
lamb tu.lsqt @um.txt
expect 2 "(it covers 0.4 to 2.5 nm; its wavelengths look like um: a table's wavelengths are in nm" -- "$BIN" tu.lsqt $S --wavelengths 450,650
lamb te.lsqt @
expect 2 "an empty table path at 'fR=@'" -- "$BIN" te.lsqt $S --wavelengths 450,650
printf '400 0.5\n700 0.5\n' > "my t.txt"
lamb tp.lsqt "@my t.txt"
expect 2 "No such file or directory (a token ends at a space: a table's path cannot contain spaces" -- "$BIN" tp.lsqt $S --wavelengths 450,650
lamb tm.lsqt @missing.txt
expect 2 "cannot open './missing.txt': No such file or directory" -- "$BIN" tm.lsqt $S --wavelengths 450,650

# ---- 5. continuing an LSS of other bands names the difference ----
lamb k.lsqt 0.5
expect 0 "" -- "$BIN" k.lsqt $S --wavelengths 450,550,650
cp k.lsqt.lss keep.lss
expect 2 "it holds 3 bands at 450 to 650 nm, this run has 3 bands at 450 to 650 nm (band 2: 550 nm there, 560 nm here); to keep it, give this run a state of its own (--lss OTHER.lss); -R would discard the state of 3 bands at 450 to 650 nm" -- "$BIN" k.lsqt $S --wavelengths 450,560,650
expect 2 "it holds 3 bands at 450 to 650 nm, this run has 4 bands at 450 to 750 nm" -- "$BIN" k.lsqt $S --wavelengths 450,550,650,750 -o x.raw
expect 0 "" -- "$BIN" k.lsqt $S --wavelengths 450,560,650 --lss side.lss -o side.raw
lamb k.lsqt 0.5,0.4,0.3
expect 2 "it holds 3 bands at 450 to 650 nm, this run has 3 bands without wavelengths (lists)" -- "$BIN" k.lsqt $S
cmp -s keep.lss k.lsqt.lss && ok || bad "the LSS changed after a refused run"

# ---- 6. merge names the RAWs it wrote ----
for k in 0 1; do "$BIN" k.lsqt $S --wavelengths 450,550,650 --lss sh.lss --shard $k/2 || bad "shard $k"; done
expect 0 "wrote m1.{450nm,...,650nm}.raw, m1.lss" -- "$BIN" merge m1.lss sh.shard-0-of-2.lss sh.shard-1-of-2.lss -o m1.raw
[ -f m1.450nm.raw ] && [ -f m1.650nm.raw ] && [ ! -e m1.raw ] && ok || bad "merge: m1's RAWs: $(ls m1*)"

finish test_band_names.sh
