#!/usr/bin/env bash
# Surviving a batch system: SIGTERM, SIGHUP and SIGUSR1 (what SLURM sends at, or with
# --signal before, a job's time limit) finish the launch, write LSS and RAW and exit 1,
# like Ctrl-C; the LSS then holds N paths exactly as a run of -p N leaves them, so
# continuing it gives the bytes of an uninterrupted run. --checkpoint S writes the LSS
# every S seconds, so even a SIGKILL loses at most S seconds of work.
# usage: test_signals.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
watchdogs=()
# (a watchdog's sleep is its child: kill it too, or it lingers for its 120 s)
cli_at_exit() { for w in "${watchdogs[@]}"; do pkill -P "$w" 2>/dev/null; kill "$w" 2>/dev/null; done; }
cli_workdir
cp "$EX/slab.lsqt" S.lsqt
F=(-wo 4 -wi 16 --wi-spread)

# paths FILE.lss: the paths per slice an LSS holds
paths() { "$BIN" info "$1" --json - 2>/dev/null | python3 -c 'import json, sys; print(json.load(sys.stdin)["paths"])'; }

# start NAME ARGS...: a run of (almost) endless paths in the background, once its kernel
# is built and a second has passed; its pid in $pid (lsqt-cl's own: a wrapper such as
# timeout would not pass SIGUSR1 on, and a SIGKILL of it would leave lsqt-cl running). A
# watchdog kills a run that outlives 120 s.
start() {
  local name=$1
  shift
  "$BIN" -v -R -p 1e12 "${F[@]}" "$@" --lss "$name.lss" -o "$name.raw" S.lsqt 2>"$name.err" >/dev/null &
  pid=$!
  (sleep 120; kill -KILL $pid 2>/dev/null) >/dev/null 2>&1 &
  watchdogs+=($!)
  for _ in $(seq 600); do grep -q "simulating" "$name.err" 2>/dev/null && break; sleep 0.1; done
  sleep 1
}

for sig in TERM HUP USR1; do
  start "s$sig" --checkpoint 0
  kill -"$sig" $pid
  wait $pid
  rc=$?
  [ "$rc" = 1 ] && grep -q "interrupted (SIG$sig)" "s$sig.err" && [ -s "s$sig.lss" ] && [ -s "s$sig.raw" ] && ok \
    || bad "SIG$sig: exit $rc: $(tail -3 "s$sig.err")"
done
# The interrupted LSS is a run of its N paths, and continuing it is the uninterrupted run.
N=$(paths sTERM.lss)
[ "$N" -gt 0 ] 2>/dev/null && ok || bad "SIGTERM: LSS holds '$N' paths"
"$BIN" -q -R -p "$N" "${F[@]}" --lss u.lss -o u.raw S.lsqt && cmp -s u.lss sTERM.lss && cmp -s u.raw sTERM.raw && ok \
  || bad "SIGTERM at $N paths: the LSS or RAW differs from a run of -p $N"
"$BIN" -q -p 5000 --lss sTERM.lss -o sTERM.raw S.lsqt && "$BIN" -q -R -p $((N + 5000)) "${F[@]}" --lss v.lss -o v.raw S.lsqt \
  && cmp -s v.lss sTERM.lss && cmp -s v.raw sTERM.raw && ok || bad "continuing the SIGTERM LSS differs from one run"

# SIGTERM during the RRSS pilot (RRSS with -rp 0.8, so most of a run is pilot): the LSS
# is the pilot so far, and continuing finishes the pilot, chooses and runs the rest: the
# bytes of the uninterrupted run.
"$BIN" -v -R -p 3e6 -rp 0.8 -wo 4 -wi 16 --lss p.lss -o p.raw S.lsqt 2>p.err >/dev/null &
pid=$!
(sleep 120; kill -KILL $pid 2>/dev/null) >/dev/null 2>&1 &
watchdogs+=($!)
for _ in $(seq 600); do grep -q "RRSS: .* pilot paths" p.err 2>/dev/null && break; sleep 0.1; done
sleep 0.3 # the pilot of 2.4e6 paths takes about 2 s on 2 cores
kill -TERM $pid
wait $pid
rc=$?
"$BIN" info p.lss > p.info 2>&1
[ "$rc" = 1 ] && grep -q "^stage: RRSS pilot" p.info && [ -s p.raw ] && ok ||
  bad "SIGTERM in the RRSS pilot: exit $rc, $(grep -E 'stage|paths:' p.info), $(tail -2 p.err)"
"$BIN" -q -p 3e6 --lss p.lss -o p.raw S.lsqt && "$BIN" -q -R -p 3e6 -rp 0.8 -wo 4 -wi 16 --lss q.lss -o q.raw S.lsqt &&
  cmp -s p.lss q.lss && cmp -s p.raw q.raw && ok || bad "continuing an interrupted RRSS pilot differs from one run"

# Checkpoints: a SIGKILL (nothing can be written then) still leaves the last checkpoint,
# a valid LSS of K paths equal to a run of -p K.
start ck --checkpoint 0.3
sleep 1
kill -KILL $pid
wait $pid 2>/dev/null
K=$(paths ck.lss)
[ "$K" -gt 0 ] 2>/dev/null && ok || bad "checkpoint: LSS holds '$K' paths: $(cat ck.err)"
"$BIN" -q -R -p "$K" "${F[@]}" --lss w.lss -o w.raw S.lsqt && cmp -s w.lss ck.lss && ok \
  || bad "the checkpoint at $K paths differs from a run of -p $K"
# (a SIGKILL during a checkpoint's write may leave its temporary file; a run that ends
# normally, with many checkpoints, leaves none)
rm -f ck.lss.* .ck.lss*
"$BIN" -q -R -p 300000 "${F[@]}" --checkpoint 0.05 --lss ck.lss -o ck.raw S.lsqt || bad "a checkpointed run failed"
ls ck.lss.* .ck.lss* 2>/dev/null | grep -q . && bad "a temporary file was left: $(ls -a)" || ok

expect 2 "bad value '-1' for --checkpoint" -- "$BIN" --checkpoint -1 S.lsqt
expect 2 "bad value 'x' for --checkpoint" -- "$BIN" --checkpoint x S.lsqt

finish test_signals
