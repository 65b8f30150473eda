#!/usr/bin/env bash
# Runs with bands (docs/guide.md, "Colour and spectra"). With LSQT_BAND_BLOCK=1 (every
# band on paths of its own) a band of a run with bands equals the one-band run of that
# band's values byte for byte (the same random numbers; --wi-spread, so that the
# directions do not depend on the other bands), for lists (R, G, B), for tables read at
# --wavelengths, and from below. With the bands sharing their paths (the default; their
# values are checked against an independent reference in test_band_blocks): which bands
# share, each band within the error bars of its one-band run, and a continued LSS, shards,
# a merge and a rerun byte for byte. The outputs' names (NAME.550nm.raw, NAME.R.raw), the
# JSON's lists, the worst band stopping --target-error; a one-band run still writes LSS
# version 6; and every bad input (exit 2, nothing written). The examples with bands run
# here.
# usage: test_bands.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir

# band.py IN B OUT [WL]: IN's band B as a one-band file, worked out here on its own: a
# KEY=a,b,c token becomes KEY=<element B>, KEY=@FILE the table row at WL (it must be a
# row, so that no interpolation is involved).
cat > band.py <<'PY'
import os, re, sys
src, b, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
wl = float(sys.argv[4]) if len(sys.argv) > 4 else None
def row(path):
    for line in open(os.path.join(os.path.dirname(src) or ".", path)):
        f = line.split("#")[0].replace(",", " ").split()
        if len(f) == 2 and float(f[0]) == wl: return f[1]
    sys.exit("no row at %g in %s" % (wl, path))
def one(m):
    key, val = m.group(1), m.group(2)
    if val.startswith("@"): return key + "=" + row(val[1:])
    if "," in val: return key + "=" + val.split(",")[b]
    return m.group(0)
with open(out, "w") as o:
    for line in open(src):
        code, _, _ = line.partition("#")
        o.write(re.sub(r"(\w+)=(\S+)", one, code).rstrip() + "\n")
PY

S="-p 3000 -wo 4 -wi 16 --wi-spread -q"
# same_band NAME FILE LABEL B [WL] [FLAGS]: FILE's RAW of band LABEL equals the one-band run.
same_band() {
  local name=$1 file=$2 label=$3 b=$4 wl=${5:-} flags=${6:-}
  python3 band.py "$file" "$b" "one-$b.lsqt" $wl || { bad "$name: band.py"; return; }
  "$BIN" one-$b.lsqt $S $flags -R || { bad "$name: one-band run"; return; }
  # the same lines after the header; the header's second line is the band's wavelength in
  # um when the run has wavelengths (0.5 otherwise, as in the one-band run)
  if cmp -s <(tail -n +3 "one-$b.lsqt.raw") <(tail -n +3 "${file}.${label}.raw"); then ok
  else bad "$name: band $label differs from its one-band run"; fi
  local want="1 0.5"
  [ -n "$wl" ] && want="1 $(python3 -c "print('%.9g' % ($wl / 1000.0))")"
  if [ "$(sed -n 2p "${file}.${label}.raw")" = "$want" ]; then ok; else bad "$name: band $label's header is not '$want'"; fi
}

# Lists: three bands without wavelengths are R, G, B; albedo 0.98 beside 0 (mus=0 in one
# band keeps the phase model, the others scatter).
cat > rgb.lsqt <<'L'
Medium
Layer z=1 NullBsdf
Medium mus=1.96,1.2,0 mua=0.04,0.3,0.5 HenyeyGreensteinPhase g=0.6,0.3,0.9
Layer z=0 LambertianBsdf fR=0.7,0.3,0.1
Medium
L
expect 0 "wrote rgb.lsqt.{R,...,B}.raw, rgb.lsqt.lss" -- env LSQT_BAND_BLOCK=1 "$BIN" rgb.lsqt ${S% -q} --json rgb.json
for b in 0 1 2; do same_band "rgb" rgb.lsqt "$(echo R G B | cut -d' ' -f$((b + 1)))" $b; done
expect 0 "format: LSS version 7" -- "$BIN" info rgb.lsqt.lss
expect 0 "bands: 3 (R, G, B)" -- "$BIN" info rgb.lsqt.lss
# JSON: R per slice is a list of three, and band 2's R (no scattering: fR e^{-2 tau / mu}...)
# is the one-band run's
python3 - rgb.json one-1.lsqt <<'PY' && ok || bad "rgb JSON"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["bands"] == 3 and d["wavelengths"] is None, (d["bands"], d["wavelengths"])
s = d["slices"][0]
assert len(s["R"]) == 3 and len(s["R_err"]) == 3 and len(s["max_rel_err"]) == 3, s
assert s["R"][0] > s["R"][1] > s["R"][2] > 0, s["R"]
PY
"$BIN" one-1.lsqt $S -R --json one.json
python3 - rgb.json one.json <<'PY' && ok || bad "band 1's JSON R is not the one-band run's"
import json, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
for x, y in zip(a["slices"], b["slices"]):
    assert x["R"][1] == y["R"] and x["R_err"][1] == y["R_err"] and x["T"][1] == y["T"], (x, y)
assert b["bands"] == 1 and b["wavelengths"] is None
PY
# A one-band run is today's: LSS version 6.
expect 0 "format: LSS version 6" -- "$BIN" info one-1.lsqt.lss
# One band at one wavelength keeps it: its RAW's header (um), the JSON, info, and the LSS
# (version 7, one band), which the same command continues and another wavelength does not.
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n' > w1.lsqt
"$BIN" w1.lsqt $S -R --wavelengths 550 --json w1.json
if [ "$(sed -n 2p w1.lsqt.raw)" = "1 0.55" ]; then ok; else bad "one band at 550 nm: RAW header '$(sed -n 2p w1.lsqt.raw)'"; fi
python3 -c 'import json, sys; j = json.load(open(sys.argv[1])); assert j["bands"] == 1 and j["wavelengths"] == [550] and isinstance(j["slices"][0]["R"], float), j["wavelengths"]' w1.json && ok || bad "one band at 550 nm: the JSON"
expect 0 "band: one, at 550 nm" -- "$BIN" info w1.lsqt.lss
expect 0 "format: LSS version 7" -- "$BIN" info w1.lsqt.lss
expect 0 "" -- "$BIN" w1.lsqt $S --wavelengths 550
expect 0 "paths: 6000 per slice" -- "$BIN" info w1.lsqt.lss
expect 2 "it holds one band at 550 nm, this run has one band at 650 nm (band 1: 550 nm there, 650 nm here)" -- "$BIN" w1.lsqt $S --wavelengths 650
expect 2 "it holds one band at 550 nm, this run has one band without a wavelength" -- "$BIN" w1.lsqt $S

# Shared paths: the three bands can share (their extinctions and HG's g differ: the
# block samples the hero's phase function; LSQT_BAND_DIVERGENCE=inf lets every band that
# can share do so); SGGX flakes that differ by band cannot (their sampler's density has
# no closed form to weigh the bands by).
expect 0 "3 bands in 1 block of up to 3 sharing their paths" -- env LSQT_BAND_DIVERGENCE=inf "$BIN" rgb.lsqt $S -R -v --lss sh3.lss -o sh3.raw
expect 1 "LSQT_BAND_DIVERGENCE is 'x': expected a number >= 0 or inf" -- env LSQT_BAND_DIVERGENCE=x "$BIN" rgb.lsqt $S -R --lss sh3.lss -o sh3.raw
printf 'Medium\nLayer z=1 NullBsdf\nMedium mus=1 mua=0.1 SggxPhase Apara=1,0.5 Aperp=0.2 type=Specular\nLayer z=0 NullBsdf\nMedium\n' > sggx2.lsqt
expect 0 "2 bands in 2 blocks of up to 1 sharing their paths" -- "$BIN" sggx2.lsqt -p 64 -wo 4 -wi 16 -q -R -v --lss sg.lss -o sg.raw
expect 1 "" -- env LSQT_BAND_BLOCK=0 "$BIN" rgb.lsqt $S -R --lss sh3.lss -o sh3.raw
# Each band of a block within the error bars of its one-band run (R and T of every slice:
# |z| < 4.5, two independent runs: another seed): a dusty coat (extinction, albedo and floor
# per band); gold under a rough coat (a hidden conductor, single scattering: each band's
# own Fresnel factor at the reflection; n and k from the example's tables); a diffuser over
# a rough conductor with multiple scattering whose index crosses k = n over the bands
# (each band's factor at every reflection of the walk).
printf 'Medium\nLayer z=1 NullBsdf\nMedium mus=1.96,1.2,0.48 mua=0.04,0.4,0.72 HenyeyGreensteinPhase g=0.6\nLayer z=0 LambertianBsdf fR=0.7,0.4,0.1 fT=0,0.3,0.05\nMedium\n' > dust.lsqt
printf 'Medium\nLayer z=1 LambertianBsdf fR=0 fT=1\nMedium\nLayer z=0 MicrosurfaceConductive alpha=0.8 use_multiple_scattering=true\nMedium eta=0.17,0.8,1.3,2.4 mua=3.15,1.6,1.3,0.4\n' > walk.lsqt
cp -r "$EX/tables" . && cp "$EX/gold-coat.lsqt" gold.lsqt
for c in "3 dust.lsqt" "3 gold.lsqt --wavelengths 450,550,650" "4 walk.lsqt"; do
  set -- $c
  nb=$1 && shift && name=${1%%.*}
  expect 0 "$nb bands in 1 block of up to $nb" -- env LSQT_BAND_DIVERGENCE=inf "$BIN" "$@" -p 20000 -wo 4 -wi 16 --wi-spread -R -v --json $name-shared.json
  env LSQT_BAND_BLOCK=1 "$BIN" "$@" -p 20000 -wo 4 -wi 16 --wi-spread -R -q --seed 7 --json $name-alone.json -o $name-alone.raw
  python3 - $name-shared.json $name-alone.json <<'PY' && ok || bad "$name: a shared band disagrees with its one-band run"
import json, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
worst = 0
for x, y in zip(a["slices"], b["slices"]):
    for k in ("R", "T"):
        for band in range(len(x[k])):
            e = (x[k + "_err"][band] ** 2 + y[k + "_err"][band] ** 2) ** 0.5
            if e > 0: worst = max(worst, abs(x[k][band] - y[k][band]) / e)
assert worst < 4.5, worst
PY
done
# Which bands share by default (host/sim/band_blocks.c: bands share where every pair's
# path divergence is within what the model allows a block of their number, 0.2 for two,
# 0.57 for eight): two bands of a coat of optical thickness 2 and 1 (albedo 0.98, g 0.6:
# about 3.6 collisions a path, a divergence of 0.69: the thinner band's paths are rare
# among the other's) run apart; eight bands whose extinction drifts 3.6 % and g 0.07 in
# all (a divergence of at most 0.078) share one block.
printf 'Medium\nLayer z=1 NullBsdf\nMedium mus=1.96,0.98 mua=0.04,0.02 HenyeyGreensteinPhase g=0.6\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n' > pair.lsqt
expect 0 "2 bands in 2 blocks of up to 1" -- "$BIN" pair.lsqt -p 64 -wo 4 -wi 16 -R -q -v --lss d2.lss -o d2.raw
expect 0 "1-2 (0.69)" -- env LSQT_BAND_DIVERGENCE=inf "$BIN" pair.lsqt -p 64 -wo 4 -wi 16 -R -q -v --lss d3.lss -o d3.raw
printf 'Medium\nLayer z=1 NullBsdf\nMedium mus=1.96,1.95,1.94,1.93,1.92,1.91,1.9,1.89 mua=0.04 HenyeyGreensteinPhase g=0.6,0.61,0.62,0.63,0.64,0.65,0.66,0.67\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n' > smooth.lsqt
expect 0 "8 bands in 1 block of up to 8" -- "$BIN" smooth.lsqt -p 64 -wo 4 -wi 16 -R -q -v --lss d8.lss -o d8.raw

# Continued: -p 3000 then 6000 more equals 9000 at once, in every band.
"$BIN" rgb.lsqt $S -R
"$BIN" rgb.lsqt -p 9000 -wo 4 -wi 16 --wi-spread -q -R --lss all.lss -o all.raw
"$BIN" rgb.lsqt -p 6000 -wo 4 -wi 16 --wi-spread -q
for l in R G B; do
  if cmp -s "rgb.lsqt.$l.raw" "all.$l.raw"; then ok; else bad "continued band $l differs"; fi
done
if cmp -s rgb.lsqt.lss all.lss; then ok; else bad "continued LSS differs from the run at once"; fi
# Reruns are byte-identical.
"$BIN" rgb.lsqt -p 9000 -wo 4 -wi 16 --wi-spread -q -R --lss again.lss -o again.raw
if cmp -s again.lss all.lss && cmp -s again.G.raw all.G.raw; then ok; else bad "a rerun differs"; fi
# Shards and a merge give the run at once.
"$BIN" rgb.lsqt -p 9000 -wo 4 -wi 16 --wi-spread -q -R --lss sh.lss -p 0 2>/dev/null
rm -f sh.lss
for k in 0 1 2; do "$BIN" rgb.lsqt -p 9000 -wo 4 -wi 16 --wi-spread -q --lss sh.lss --shard $k/3 || bad "shard $k"; done
expect 0 "" -- "$BIN" merge merged.lss sh.shard-0-of-3.lss sh.shard-1-of-3.lss sh.shard-2-of-3.lss -o merged.raw
if cmp -s merged.lss all.lss && cmp -s merged.B.raw all.B.raw; then ok; else bad "merged shards differ from the run at once"; fi

# A layer opaque in one band only is kept (pruning is where every band is stopped): band 1
# sees the floor through it, band 0 does not, each as its own run.
printf 'Medium\nLayer z=1 LambertianBsdf fR=0.3 fT=0,0.5\nMedium eta=1.3\nLayer z=0 LambertianBsdf fR=0.8\nMedium\n' > op.lsqt
expect 0 "" -- env LSQT_BAND_BLOCK=1 "$BIN" op.lsqt $S
same_band "opaque in one band" op.lsqt 0 0
same_band "opaque in one band" op.lsqt 1 1

# Tables at --wavelengths (rows of the tables, so band.py needs no interpolation), and
# light from below.
mkdir -p t
printf '# made-up paint\n400 0.10\n500 0.30\n600 0.60\n700 0.90\n' > t/fr.txt
printf '400,0.5\n700,0.05\n' > t/ft.txt
printf 'Medium\nLayer z=0 LambertianBsdf fR=@t/fr.txt fT=@t/ft.txt\nMedium\n' > tab.lsqt
expect 0 "wrote tab.lsqt.{400nm,700nm}.raw" -- env LSQT_BAND_BLOCK=1 "$BIN" tab.lsqt ${S% -q} --wavelengths 400:700:300
same_band "table" tab.lsqt 400nm 0 400
same_band "table" tab.lsqt 700nm 1 700
expect 0 "" -- env LSQT_BAND_BLOCK=1 "$BIN" tab.lsqt $S -R --wavelengths 400,700 --from-below
python3 band.py tab.lsqt 0 below-0.lsqt 400
"$BIN" below-0.lsqt $S -R --from-below
if cmp -s <(tail -n +3 below-0.lsqt.below.raw) <(tail -n +3 tab.lsqt.below.400nm.raw); then ok
else bad "from below: band 400nm differs"; fi

# --target-error stops when the worst band reaches it.
"$BIN" rgb.lsqt -wo 4 -wi 16 --wi-spread -q -R --lss te.lss -o te.raw --target-error 0.05 -p 2e6 --json te.json
python3 - te.json <<'PY' && ok || bad "target error: not every band reached it"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["stopped_by"] == "the target error (--target-error)", d["stopped_by"]
worst = max(max(s["max_rel_err"]) for s in d["slices"])
assert worst <= 0.05, worst
PY

# Bad input: exit 2 with file, line, token and band; nothing written.
bad_input() {
  local text=$1 flags=$2 says=$3
  printf "$text" > bad.lsqt
  expect 2 "$says" -- "$BIN" bad.lsqt -p 1000 $flags
  if ls bad.lsqt.* >/dev/null 2>&1; then bad "[$text $flags] wrote output"; rm -f bad.lsqt.*; fi
}
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=0.1,0.2 fT=0.1,0.2,0.3\nMedium\n' "" \
  "bad.lsqt:2: error: band 1: lists of different lengths at 'fT=0.1,0.2,0.3'; expected 2 comma-separated values, as the list on line 2"
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=0.1,0.2\nMedium\n' "--wavelengths 450,550,650" \
  "bad.lsqt:2: error: band 1 (450 nm): wrong number of values at 'fR=0.1,0.2'; expected 3 comma-separated values"
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=@t/fr.txt\nMedium\n' "" "a table without wavelengths at 'fR=@t/fr.txt'"
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=@nosuch.txt\nMedium\n' "--wavelengths 500" "unreadable table at 'fR=@nosuch.txt'"
printf '400 0.1\n300 0.2\n' > t/down.txt
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=@t/down.txt\nMedium\n' "--wavelengths 350" "t/down.txt:2:"
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=@t/fr.txt\nMedium\n' "--wavelengths 450,750" \
  "band 2 (750 nm): wavelength outside the table at 'fR=@t/fr.txt'; expected a table that covers 750 nm (it covers 400 to 700 nm)"
printf '400 0.5\n1300 0.95\n' > t/wide.txt
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=@t/wide.txt fT=0.1\nMedium\n' "--wavelengths 400,700,1250" \
  "bad.lsqt:2: error: band 3 (1250 nm): fR + fT = 1.025 exceeds 1 at 'fT=0.1'"
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=0.5,0.8 fT=0.2,0.3\nMedium\n' "" \
  "bad.lsqt:2: error: band 2: fR + fT = 1.1 exceeds 1"
bad_input 'Medium\nLayer z=0,1 LambertianBsdf\nMedium\n' "" "z as a value per band"
bad_input 'Medium\nLayer z=0 LambertianBsdf\nMedium\n' "--wavelengths 550,450" "--wavelengths: "
bad_input 'Medium\nLayer z=0 LambertianBsdf fR=0.1,0.2\nMedium\n' "-o -" "one RAW per band"

# The examples with bands.
cp "$EX/paint-rgb.lsqt" . && cp -r "$EX/tables" .
expect 0 "band 3 (B):" -- "$BIN" paint-rgb.lsqt -p 2000 -wo 4 -wi 16
cp "$EX/gold-coat.lsqt" .
expect 0 "band 3 (700 nm):" -- "$BIN" gold-coat.lsqt -p 1000 -wo 4 -wi 16 --wavelengths 500:700:100
expect 2 "a table without wavelengths" -- "$BIN" gold-coat.lsqt -p 1000 -R
# The Mie paint's suggested run reads every one of its 106 bands (three tables at 1 nm
# rows), then --max-memory refuses it before any kernel is built (a run would build a
# program of its own: 8 s on 2 cores with an empty kernel cache), writing nothing.
cp "$EX/tio2-paint.lsqt" .
expect 2 "106 bands x 12 slices" -- "$BIN" tio2-paint.lsqt --wavelengths 400:2500:20 --max-memory 1
ls tio2-paint.lsqt.* >/dev/null 2>&1 && bad "tio2-paint.lsqt refused, but wrote $(ls tio2-paint.lsqt.*)" || ok
# Many bands: the summary gives a line a band (R and T over the slices, from the same
# numbers as the JSON), -v every band's table.
"$BIN" -R gold-coat.lsqt -p 1000 -wo 4 -wi 16 --wavelengths 400:650:50 --json six.json -o six.raw --lss six.lss >six.out &&
  grep -q "^6 bands, over the slices" six.out && [ "$(grep -c '^band [1-6] ([0-9]* nm) ' six.out)" = 6 ] &&
  ! grep -q "^slice " six.out && ok || bad "six bands' summary: $(head -12 six.out)"
python3 - six.json six.out <<'PY' && ok || bad "six bands' summary lines differ from the JSON"
import json, re, sys
j = json.load(open(sys.argv[1]))
lines = [l for l in open(sys.argv[2]) if re.match(r"^band \d+ \(", l)]
for b, l in enumerate(lines):
    r = [s["R"][b] for s in j["slices"]]
    nums = re.findall(r"\d+\.\d{6}", l)
    assert nums[:2] == ["%.6f" % min(r), "%.6f" % max(r)], (l, r)
PY
"$BIN" -v -R gold-coat.lsqt -p 1000 -wo 4 -wi 16 --wavelengths 400:650:50 -o six.raw --lss six.lss 2>/dev/null | grep -q "^band 6 (650 nm):" &&
  ok || bad "-v does not give every band's table"
finish test_bands.sh
