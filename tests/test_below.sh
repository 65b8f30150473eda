#!/usr/bin/env bash
# --from-below end to end: OUT.below.raw beside OUT, OUT byte for byte what it is without
# the flag (RRSS and the spread, -H too), the LSS slices flagged (info text and JSON, the
# run's JSON), a Lambertian layer's exact values on the side from below, a continued LSS
# continues both sides to the bytes of one run, the LSS decides the sides when continued,
# and the combinations that cannot work are refused with a message (exit 2).
# usage: test_below.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir

cp "$EX/slab.lsqt" S.lsqt
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.3 fT=0.5\nMedium\n' > L.lsqt
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.5\nMedium\n' > O.lsqt
F="-q -wo 4 -wi 16"

expect 0 "--from-below" -- "$BIN" --help

# The main RAW is the run without --from-below, with RRSS and with the spread.
"$BIN" $F -p 3000 -o a.raw --lss a.lss S.lsqt && "$BIN" $F -p 3000 --from-below -o b.raw --lss b.lss S.lsqt \
  && cmp -s a.raw b.raw && [ -s b.below.raw ] && [ ! -e a.below.raw ] && ok || bad "RRSS: main RAW differs or no below RAW"
"$BIN" $F -p 3000 --wi-spread -o c.raw --lss c.lss S.lsqt && "$BIN" $F -p 3000 --wi-spread --from-below -o d.raw \
  --lss d.lss S.lsqt && cmp -s c.raw d.raw && ok || bad "spread: main RAW differs"
head -1 b.below.raw | grep -qx 'RAWBS10A Layered-SQT' && [ "$(sed -n 3p b.below.raw)" = "$(sed -n 3p b.raw)" ] && ok \
  || bad "below RAW header"
# The stack is symmetric: the sides differ (their own paths) but not by much.
cmp -s b.raw b.below.raw && bad "the side from below repeats the paths from above" || ok

# The LSS: 4 slices from below after 4 from above, in info's text and JSON, and in the run's JSON.
out=$("$BIN" info b.lss --json bi.json)
[ "$(grep -c '^slice [4-7] (from below): theta_o' <<<"$out")" = 4 ] && ! grep -q '^slice [0-3] (from below)' <<<"$out" \
  && grep -q '4 from above, 4 from below' <<<"$out" && ok || bad "info text: $out"
python3 -c "import json,sys; s=json.load(open('bi.json'))['slices']; sys.exit(0 if [x['from_below'] for x in s]==[False]*4+[True]*4 else 1)" \
  && ok || bad "info JSON from_below"
"$BIN" $F -R -p 1000 --from-below -o e.raw --lss e.lss --json e.json L.lsqt && python3 -c "
import json,sys; s=json.load(open('e.json'))['slices']; sys.exit(0 if [x['from_below'] for x in s]==[False]*4+[True]*4 else 1)" \
  && ok || bad "run JSON from_below"
# A Lambertian layer from below: fR/pi back down (z > 0 in the view from below), fT/pi up.
python3 - <<'PY' && ok || bad "Lambertian values from below"
import math, sys
rows = [[float(x) for x in l.split()] for l in open("e.below.raw").read().splitlines()[3:]]
assert len(rows) == 4 * 16 * 2, len(rows)
for r in rows:
    want = (0.3 if r[3] > 0 else 0.5) / math.pi
    if abs(r[4] / want - 1) > 1e-5: sys.exit("value %s, expected %g" % (r, want))
PY
expect 0 "slices 'from below' are of light entering from the bottom medium" -- "$BIN" -wo 4 -wi 16 -R -p 500 \
  --from-below -o f.raw --lss f.lss L.lsqt

# -H: OUT.below.R.raw and OUT.below.T.raw beside OUT.R.raw and OUT.T.raw, those as without the flag.
"$BIN" $F -p 2000 -H -o h.raw --lss h.lss S.lsqt && "$BIN" $F -p 2000 -H --from-below -o g.raw --lss g.lss S.lsqt \
  && cmp -s h.R.raw g.R.raw && cmp -s h.T.raw g.T.raw && [ -s g.below.R.raw ] && [ -s g.below.T.raw ] \
  && [ ! -e g.below.raw ] && ok || bad "-H with --from-below"
# A RAW name without .raw gets .below.raw appended.
"$BIN" $F -p 500 --from-below -o plain --lss p.lss L.lsqt && [ -s plain.below.raw ] && ok || bad "plain.below.raw"

# Continuing: 3000 + 3000 paths are the bytes of 6000 on both sides and in the LSS, and a
# continued LSS with slices from below continues both without the flag.
"$BIN" $F -p 3000 --wi-spread --from-below -o i.raw --lss i.lss S.lsqt
expect 0 "both sides are continued" -- "$BIN" -wo 4 -wi 16 -p 3000 -o i.raw --lss i.lss S.lsqt
"$BIN" $F -p 6000 --wi-spread --from-below -o j.raw --lss j.lss S.lsqt
cmp -s i.raw j.raw && cmp -s i.below.raw j.below.raw && cmp -s i.lss j.lss && ok || bad "3000 + 3000 is not 6000"
# Ctrl-C: both sides stop at the same path count, and that LSS is a run of that count.
"$BIN" $F -p 3e7 --wi-spread --from-below -o s.raw --lss s.lss S.lsqt 2>/dev/null &
pid=$!
sleep 2
kill -INT "$pid"
wait "$pid"
n=$("$BIN" info s.lss --json - 2>/dev/null | python3 -c "import json,sys; print(json.load(sys.stdin)['paths'])")
"$BIN" $F -p "$n" --wi-spread --from-below -o r.raw --lss r.lss S.lsqt && cmp -s s.lss r.lss && cmp -s s.raw r.raw \
  && cmp -s s.below.raw r.below.raw && ok || bad "an interrupted two-sided LSS of $n paths is not a -p $n run"
# Ctrl-C in a two-sided RRSS pilot: the LSS is the pilot of both sides (the same paths);
# continuing with the same -p finishes it: the bytes of the uninterrupted run, both RAWs.
"$BIN" -v -wo 4 -wi 16 -p 1.2e6 -rp 0.8 --from-below -o q.raw --lss q.lss S.lsqt 2>q.err >/dev/null &
pid=$!
for _ in $(seq 600); do grep -q "RRSS: .* pilot paths" q.err 2>/dev/null && break; sleep 0.1; done
sleep 0.3 # the pilot of 9.6e5 paths per side takes about 1.5 s on 2 cores
kill -INT "$pid"
wait "$pid"
"$BIN" info q.lss >q.info 2>&1
grep -q "^stage: RRSS pilot" q.info && ok || bad "Ctrl-C in a two-sided pilot: $(grep -E 'stage|paths:' q.info)"
"$BIN" -q -p 1.2e6 -o q.raw --lss q.lss S.lsqt && "$BIN" -q -wo 4 -wi 16 -p 1.2e6 -rp 0.8 --from-below -o u.raw --lss u.lss S.lsqt &&
  cmp -s q.lss u.lss && cmp -s q.raw u.raw && cmp -s q.below.raw u.below.raw && ok ||
  bad "continuing an interrupted two-sided RRSS pilot differs from one run"
# A one-sided LSS stays one-sided: --from-below contradicts it (exit 2, nothing written).
rm -f a.below.raw
expect 2 "--from-below contradicts 'a.lss' (it has no slices from below)" -- \
  "$BIN" -wo 4 -wi 16 -p 1000 --from-below -o a.raw --lss a.lss S.lsqt
[ ! -e a.below.raw ] && ok || bad "a one-sided LSS got a below RAW"

# Refused: a RAW on stdout or a device (the second name comes from it); nothing written.
expect 2 "give -o a file name" -- "$BIN" $F -p 500 --from-below -o - --lss k.lss S.lsqt
expect 2 "give -o a file name" -- "$BIN" $F -p 500 --from-below -o /dev/null --lss k.lss S.lsqt
[ ! -e k.lss ] && ok || bad "a refused run wrote its LSS"
# A stack that transmits nothing: a note, the run from above only.
expect 0 "the stack transmits nothing" -- "$BIN" -wo 4 -wi 16 -p 500 --from-below -o o.raw --lss o.lss O.lsqt
[ -s o.raw ] && [ ! -e o.below.raw ] && ok || bad "opaque stack"
"$BIN" info o.lss | grep -q 'from below' && bad "opaque stack has slices from below" || ok
# The target error applies to both sides.
expect 0 "stopped by the target error" -- "$BIN" -wo 4 -wi 16 --wi-spread --target-error 0.2 --from-below -o t.raw \
  --lss t.lss L.lsqt

finish test_below.sh
