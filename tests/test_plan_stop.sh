#!/usr/bin/env bash
# An interrupted --plan keeps nothing and says so: a stop signal (SIGTERM, Ctrl-C) during
# its calibration runs removes its folder in TMPDIR (lsqt-plan.PID.*), a second signal
# (stop at once) too, and the folder of a --plan that was killed outright (its PID gone)
# is removed by the next --plan.
# usage: test_plan_stop.sh LSQT_CL
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN -- "$@"
cli_workdir
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n' >L.lsqt
mkdir tmp

# plan_stop SIG [SIG2]: a --plan of 31 bands (seconds of calibration) stopped by SIG once
# its first calibration run has begun (its LSS lock is taken; ctest's timeout guards it), then SIG2 at once if given; its status in $rc, stderr in plan.err.
plan_stop() {
  TMPDIR=$PWD/tmp "$BIN" --plan --wavelengths 400:700:10 L.lsqt >plan.out 2>plan.err &
  local pid=$!
  for _ in $(seq 300); do compgen -G "tmp/lsqt-plan.*/c.lss*" >/dev/null && break; sleep 0.05; done
  kill -"$1" "$pid" 2>/dev/null
  if [ $# -gt 1 ]; then sleep 0.05; kill -"$2" "$pid" 2>/dev/null; fi
  wait "$pid"
  rc=$?
}

# the folder of a --plan whose process is gone (a PID that ran and ended)
true &
dead=$!
wait $dead
mkdir "tmp/lsqt-plan.$dead.AbCdEf" && touch "tmp/lsqt-plan.$dead.AbCdEf/x.raw" "tmp/lsqt-plan.$dead.AbCdEf/x.lss.lock"
mkdir "tmp/lsqt-plan.$$.AbCdEf" # this shell's: it runs, so it stays

plan_stop TERM
[ "$rc" = 1 ] && ok || bad "--plan stopped by SIGTERM: exit $rc, expected 1: $(cat plan.err)"
grep -q "^lsqt-cl: --plan interrupted (SIGTERM): no plan" plan.err && ok || bad "--plan's message: $(cat plan.err)"
grep -q "done so far" plan.err && bad "--plan says it wrote paths it removes: $(cat plan.err)" || ok
[ "$(ls -A tmp)" = "lsqt-plan.$$.AbCdEf" ] && ok || bad "TMPDIR after a stopped --plan: $(ls -A tmp)"

plan_stop INT INT
[ "$rc" = 130 ] && ok || bad "--plan stopped at once by a second SIGINT: exit $rc, expected 130: $(cat plan.err)"
[ "$(ls -A tmp)" = "lsqt-plan.$$.AbCdEf" ] && ok || bad "TMPDIR after a --plan stopped at once: $(ls -A tmp)"

finish test_plan_stop
