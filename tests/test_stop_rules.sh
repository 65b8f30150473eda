#!/usr/bin/env bash
# Stop rules of lsqt-cl: --target-error reaches the requested error and stops there, at a
# path count that depends only on the tallies (so the run is reproducible and equals a
# plain -p run of that count); -p caps it; a target is judged only from 2 chunks in each
# batch on (16384 paths); an error that cannot be estimated (one batch: 256 paths or
# fewer) is "n/a".
# usage: test_stop_rules.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir
cp "$EX/slab.lsqt" S.lsqt
# The even spread: with RRSS the pilot is a share of -p (10000 without it), so a target
# run equals a -p run only on given directions.
F=(-wo 4 -wi 16 -s 3 --wi-spread)

# json FILE EXPR: evaluates a Python expression over the JSON summary j.
json() { python3 -c "import json, sys; j = json.load(open(sys.argv[1])); sys.exit(0 if ($2) else 1)" "$1"; }

# Reaches the target: every slice's largest relative error at most E, stopped by it, on a
# check count (a multiple of 8192 paths, at least 16384), and not far beyond it (checks
# aim 5 % past the 1/sqrt(N) prediction, so the error at the stop is well above E / 2).
# E is small enough that the first check (16384 paths, error about 0.018) does not meet it.
E=0.01
expect 0 "stopped by the target error" -- "$BIN" -R --target-error $E "${F[@]}" --lss a.lss -o a.raw --json a.json S.lsqt
json a.json "all(s['max_rel_err'] <= $E for s in j['slices']) and max(s['max_rel_err'] for s in j['slices']) > $E / 2" \
  && ok || bad "target $E: max_rel_err $(python3 -c "import json; print([s['max_rel_err'] for s in json.load(open('a.json'))['slices']])")"
json a.json "j['stopped_by'].startswith('the target error') and j['paths_added'] % 8192 == 0 and j['paths_added'] >= 16384" \
  && ok || bad "target $E: stopped_by / paths: $(cat a.json)"
N=$(python3 -c "import json; print(json.load(open('a.json'))['paths_added'])")
# Reproducible, and the same as a plain run of that many paths.
"$BIN" -q -R --target-error $E "${F[@]}" --lss b.lss -o b.raw S.lsqt && cmp -s a.lss b.lss && cmp -s a.raw b.raw \
  && ok || bad "target $E: a second run differs"
"$BIN" -q -R -p "$N" "${F[@]}" --lss c.lss -o c.raw S.lsqt && cmp -s a.lss c.lss && ok \
  || bad "target $E: differs from -p $N"
# A continued LSS that already meets the target adds nothing; a smaller target goes on.
expect 0 "0 added per slice" -- "$BIN" --target-error $E --lss a.lss -o a2.raw S.lsqt
cmp -s a.lss c.lss && ok || bad "continuing at the target changed the LSS"
expect 0 "stopped by the target error" -- "$BIN" --target-error 0.007 --lss a.lss -o a3.raw --json a3.json S.lsqt
json a3.json "all(s['max_rel_err'] <= 0.007 for s in j['slices']) and j['slices'][0]['paths'] > $N" && ok \
  || bad "continued to 0.007: $(cat a3.json)"

# -p caps a target that is not reached.
expect 0 "stopped by the path count" -- "$BIN" -R --target-error 0.001 -p 20000 "${F[@]}" --lss d.lss -o d.raw --json d.json S.lsqt
json d.json "j['paths_added'] == 20000 and all(s['max_rel_err'] > 0.001 for s in j['slices'])" && ok || bad "cap: $(cat d.json)"

# A target met by any estimate still waits for an error that can be estimated.
expect 0 "stopped by the target error" -- "$BIN" -R --target-error 10 "${F[@]}" --lss e.lss -o e.raw --json e.json S.lsqt
json e.json "j['paths_added'] == 16384" && ok || bad "target 10: $(cat e.json)"
# ... also when it continues a state of a few chunks, whose errors are already numbers.
"$BIN" -q -R -p 1100 "${F[@]}" --lss e2.lss -o e2.raw S.lsqt
expect 0 "stopped by the target error" -- "$BIN" --target-error 10 --lss e2.lss -o e2.raw --json e2.json S.lsqt
json e2.json "j['slices'][0]['paths'] == 16384" && ok || bad "target 10 after 1100 paths: $(cat e2.json)"

# With all paths in one batch (256 or fewer) the errors are n/a (JSON null), never +-inf or 0;
# from two batches on they are numbers.
expect 0 "+- n/a" -- "$BIN" -R -p 256 "${F[@]}" --lss f.lss -o f.raw --json f.json S.lsqt
json f.json "all(s['R_err'] is None and s['max_rel_err'] is None for s in j['slices'])" && ok || bad "n/a: $(cat f.json)"
expect 0 "errors need paths in 2 of the 32 batches" -- "$BIN" -R -p 256 "${F[@]}" --lss f.lss -o f.raw S.lsqt
"$BIN" -q -R -p 300 "${F[@]}" --lss g.lss -o g.raw --json g.json S.lsqt
json g.json "all(s['R_err'] > 0 and s['max_rel_err'] > 0 for s in j['slices'])" && ok || bad "300 paths: $(cat g.json)"

# Bad values.
for v in 0 -0.1 abc nan; do
  expect 2 "bad value '$v' for --target-error" -- "$BIN" -R --target-error "$v" S.lsqt
done
ls S.lsqt.* >/dev/null 2>&1 && bad "a refused run wrote output" || ok

# A time limit inside the RRSS pilot: the summary says what the LSS holds (the pilot, so
# far) and what continuing with and without -p will do.
expect 0 "note: the run stopped in its RRSS pilot: 'P.lss' holds" -- \
  "$BIN" -R -wo 4 -wi 16 -p 1e9 --time-limit 1 -o P.raw --lss P.lss S.lsqt
expect 0 "Continuing without -p finishes the pilot and then this run (1000000000 paths per slice in all)" -- \
  "$BIN" -R -wo 4 -wi 16 -p 1e9 --time-limit 1 -o P.raw --lss P.lss S.lsqt
"$BIN" info P.lss | grep -q "^stage: RRSS pilot" && ok || bad "the time-limited pilot's LSS: $("$BIN" info P.lss | grep stage)"
# --total-paths of the whole run continues a stopped pilot as the same command without -p.
expect 0 "this run finishes it, then the run (1000000000 paths per slice)" -- \
  "$BIN" --total-paths 1e9 --time-limit 1 -o P.raw --lss P.lss S.lsqt
# A run that ends short of its target says so, with the paths the 1/sqrt(paths) law says
# it needs (checked here from the JSON's own largest error: N = ceil(paths (err/goal)^2)),
# and the command that gets them; one that reaches it says met.
expect 0 "target error 0.001: not met (largest relative error" -- \
  "$BIN" -R -wo 4 -wi 16 --wi-spread -p 20000 --target-error 0.001 --json short.json -o short.raw --lss short.lss S.lsqt
json short.json "j['target_met'] is False and j['target_error'] == 0.001 and j['paths_needed'] == __import__('math').ceil(20000 * (max(s['max_rel_err'] for s in j['slices']) / 0.001) ** 2)" \
  && ok || bad "short of the target: $(cat short.json | head -c 600)"
n=$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['paths_needed'])" short.json)
expect 0 "continue with --total-paths $n" -- \
  "$BIN" -R -wo 4 -wi 16 --wi-spread -p 20000 --target-error 0.001 -o s2.raw --lss s2.lss S.lsqt
expect 0 "target error 0.5: met (largest relative error" -- \
  "$BIN" -R -wo 4 -wi 16 --wi-spread -p 20000 --target-error 0.5 --json met.json -o met.raw --lss met.lss S.lsqt
json met.json "j['target_met'] is True and j['paths_needed'] == 16384" && ok || bad "met: $(head -c 300 met.json)"
expect 0 "target error 0.001: not met (not judged yet: the largest error counts from 16384 paths per slice on)" -- \
  "$BIN" -R -wo 4 -wi 16 --wi-spread -p 3000 --target-error 0.001 -o few.raw --lss few.lss S.lsqt
"$BIN" -R -wo 4 -wi 16 --wi-spread -p 3000 --json none.json -o none.raw --lss none.lss S.lsqt >/dev/null &&
  json none.json "j['target_met'] is None and j['paths_needed'] is None and j['target_error'] is None" && ok ||
  bad "without --target-error the JSON's target fields are not null"
# --plan: calibrates in a temporary folder (TMPDIR; left empty), writes nothing beside the
# input, and predicts by 1/sqrt(paths): a run of the paths it gives for 1 % has its
# largest relative error near 1 % (within 0.7-1.4: the largest of 64 errors is noisy).
mkdir -p plantmp && cp S.lsqt PL.lsqt
TMPDIR=$PWD/plantmp "$BIN" --plan -wo 4 -wi 16 --wi-spread PL.lsqt >plan.out 2>plan.err && ok || bad "--plan failed: $(cat plan.err)"
grep -q "^time per 1e6 paths per slice: .* s wall, .* CPU-s" plan.out && [ "$(grep -cE '^ +[0-3] +[0-9.]+d ' plan.out)" = 4 ] &&
  ok || bad "--plan output: $(cat plan.out)"
ls PL.lsqt.* >/dev/null 2>&1 && bad "--plan wrote beside its input: $(ls PL.lsqt.*)" || ok
[ -z "$(ls -A plantmp)" ] && ok || bad "--plan left files in TMPDIR: $(ls -A plantmp)"
n=$(sed -n 's/^  target 0.01 *\([0-9.e+]*\) paths per slice.*/\1/p' plan.out)
n=$(python3 -c "import sys; print(int(float(sys.argv[1])))" "$n")
"$BIN" -q -R -wo 4 -wi 16 --wi-spread --total-paths "$n" --json plan.json -o PL.raw --lss PL.lss PL.lsqt &&
  json plan.json "0.7 < max(s['max_rel_err'] for s in j['slices']) / 0.01 < 1.4" && ok ||
  bad "--plan's paths for 1 % ($n) gave a largest error of $(python3 -c "import json; print(max(s['max_rel_err'] for s in json.load(open('plan.json'))['slices']))")"
# with bands the runs write a RAW per band: all removed with the folder
mkdir -p plantmp2
TMPDIR=$PWD/plantmp2 "$BIN" --plan -wo 4 -wi 16 --wi-spread --wavelengths 500,600 PL.lsqt >planb.out 2>&1 &&
  grep -q "4 slices x 16 directions, 2 bands" planb.out && [ -z "$(ls -A plantmp2)" ] && ok ||
  bad "--plan with bands: $(head -3 planb.out), left: $(ls -A plantmp2)"
expect 2 "--plan runs the input twice: give a file, not stdin" -- bash -c "\"$BIN\" --plan - < S.lsqt"
expect 2 "--plan predicts a whole run: drop --shard" -- "$BIN" --plan --shard 0/2 S.lsqt
# The progress line (drawn on a terminal: script(1) gives one) names the phase, and with a
# target error the time 1/sqrt(paths) predicts to it.
if command -v script >/dev/null; then
  script -qec "\"$BIN\" -R -wo 4 -wi 16 -p 3e5 -o pg.raw --lss pg.lss S.lsqt" /dev/null | tr '\r' '\n' >pg.out
  grep -aq "^RRSS pilot: \[" pg.out && grep -aq "^refining the chosen directions: \[" pg.out && ok ||
    bad "the progress line does not name the RRSS pilot and the refinement: $(head -c 300 pg.out)"
  script -qec "\"$BIN\" -R -wo 4 -wi 16 --wi-spread --target-error 0.003 -p 1e6 -o pg.raw --lss pg.lss S.lsqt" /dev/null |
    tr '\r' '\n' >pt.out
  grep -aqE "max rel err [0-9.e-]+ \(target 0.003, about [0-9]+ s to it\)" pt.out && ok ||
    bad "the progress line does not predict the time to the target: $(tail -c 300 pt.out)"
else
  echo "SKIP (this part only): script(1) is not installed"
fi
finish test_stop_rules
