#!/usr/bin/env bash
# test_concurrent: a run owns the state it writes (lsqt_lock_take, util.h). While one run
# continues an LSS, a second run on it (continuing, or -R) is refused with exit 1 naming
# the first (process id and host), and once the first ends the second continues the
# first's paths: none lost. Shards: two shards of one index exclude each other, shards of
# other indexes run beside each other, and a plain run or a merge waits for them. The lock
# file goes with its last holder.
# usage: test_concurrent.sh LSQT_CL
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN -- "$@"
P=
cli_at_exit() { [ -n "$P" ] && kill -9 $P 2>/dev/null; }
cli_workdir
printf 'Medium\nLayer z=1 NullBsdf\nMedium mus=0.9 mua=0.1 HenyeyGreensteinPhase g=0.8\nLayer z=0 NullBsdf\nMedium\n' > s.lsqt
paths() { "$BIN" info "$1" --json - 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["paths"])'; }
# wait_for FILE: up to 60 s for FILE to appear (the first run has taken its lock).
wait_for() {
  for _ in $(seq 600); do [ -e "$1" ] && return 0; sleep 0.1; done
  return 1
}
RUN=(-q -t 1 -wo 4 -wi 16 --wi-spread)

expect 0 "" -- "$BIN" "${RUN[@]}" -p 1000 s.lsqt
# A long continuation, stopped later by SIGTERM (it then writes what it did).
"$BIN" "${RUN[@]}" -p 1000000000 s.lsqt > a.log 2>&1 &
P=$!
wait_for s.lsqt.lss.lock && ok || bad "the first run took no lock (no s.lsqt.lss.lock)"
expect 1 "'s.lsqt.lss' is in use by another run (process $P on $(hostname)" -- "$BIN" "${RUN[@]}" -p 2000 s.lsqt
expect 1 "in use by another run" -- "$BIN" "${RUN[@]}" -R -p 2000 s.lsqt
expect 1 "in use by another run" -- "$BIN" "${RUN[@]}" -p 2000 --shard 0/2 s.lsqt
sleep 1
kill -TERM $P
wait $P
rc=$?
P=
[ "$rc" = 1 ] && grep -q "interrupted (SIGTERM)" a.log && ok || bad "the first run: exit $rc, $(cat a.log)"
[ ! -e s.lsqt.lss.lock ] && ok || bad "the lock file outlived its holder"
n1=$(paths s.lsqt.lss)
[ -n "$n1" ] && [ "$n1" -gt 1000 ] && ok || bad "the first run's LSS holds '$n1' paths"
expect 0 "" -- "$BIN" "${RUN[@]}" -p 500 s.lsqt
[ "$(paths s.lsqt.lss)" = $((n1 + 500)) ] && ok || bad "after both runs: $(paths s.lsqt.lss) paths, not $((n1 + 500))"

# Shards of one run: shard 0 runs long; shard 0 again is refused, shard 1 runs beside it.
"$BIN" "${RUN[@]}" -p 1000000000 --shard 0/2 s.lsqt > s0.log 2>&1 &
P=$!
wait_for s.lsqt.shard-0-of-2.lss.lock && ok || bad "shard 0 took no lock"
expect 1 "'s.lsqt.shard-0-of-2.lss' is in use by another run (process $P on" -- \
  "$BIN" "${RUN[@]}" -p 1000000000 --shard 0/2 s.lsqt
expect 0 "" -- "$BIN" "${RUN[@]}" -p 1000000000 --time-limit 1 --shard 1/2 s.lsqt
[ -s s.lsqt.shard-1-of-2.lss ] && ok || bad "shard 1 wrote nothing beside shard 0"
# The state the shards read is theirs until they end: no plain run, no merge.
expect 1 "'s.lsqt.lss' is in use by another run (process $P, a shard reading it" -- "$BIN" "${RUN[@]}" -p 10 s.lsqt
expect 1 "in use by another run" -- "$BIN" merge m.lss s.lsqt.lss s.lsqt.shard-1-of-2.lss s.lsqt.shard-0-of-2.lss
kill -TERM $P
wait $P
P=
ls ./*.lock >/dev/null 2>&1 && bad "lock files left: $(ls ./*.lock)" || ok
finish test_concurrent
