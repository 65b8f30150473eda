#!/usr/bin/env bash
# The SLURM round trip: a single-node SLURM on this machine (tools/slurm/single-node.sh) runs
# tools/slurm/submit.sh --wait 4 (shard, merge, refine, merge as dependent job arrays), and
# FILE.lss and FILE.raw must be byte for byte those of one process with the same flags.
# Skips (exit 77, shown by ctest as skipped) where SLURM cannot be started: not root, the
# slurm-wlm and munge packages missing, or the daemons failing to come up.
# LSQT_STEPS, if set, replaces tools/slurm/steps.sh (as in submit.sh).
# usage: test_slurm.sh LSQT_CL EXAMPLES_DIR
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: $0 LSQT_CL EXAMPLES_DIR" >&2; exit 2; }
BIN=$(cd "$(dirname "$1")" && pwd -P)/$(basename "$1")
EX=$2
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)
SN=$REPO/tools/slurm/single-node.sh

skip() {
  echo "SKIP: $*"
  exit 77
}
[ "$(id -u)" = 0 ] || skip "needs root to start a single-node SLURM (slurmd runs jobs as their user)"
for p in slurmctld slurmd sbatch squeue scancel munged python3; do
  command -v "$p" >/dev/null || skip "$p not found: install slurm-wlm and munge (bash tools/setup.sh)"
done

# Every command below has a timeout taken from one budget, so that the teardown always
# runs before ctest's TIMEOUT (300 s), whose SIGKILL no trap could catch: daemons would
# be left running.
deadline=$((SECONDS + 200))
left() {
  local l=$((deadline - SECONDS))
  [ "$l" -gt 1 ] || l=1
  echo "$l"
}

T=$(mktemp -d)
S=$(mktemp -d) # single-node.sh makes it mode 755 (munged requires that)
started=0
bg=
# In the background and waited for, so that a TERM or INT is handled at once (bash runs a
# trap only after the foreground command has ended); teardown stops it.
run() {
  local rc=0
  "$@" &
  bg=$!
  wait "$bg" || rc=$?
  bg=
  return "$rc"
}
# shellcheck disable=SC2317 # called by the trap
teardown() {
  [ -z "$bg" ] || kill "$bg" 2>/dev/null || true
  if [ "$started" = 1 ]; then
    timeout -k 5 90 bash "$SN" stop "$S" || true
  fi
  rm -rf "$T" "$S"
}
trap teardown EXIT
# Ctrl-C, or a TERM from whoever runs the test: tear down (EXIT does it), then say so.
trap 'exit 130' INT
trap 'exit 143' TERM

cp "$EX/slab.lsqt" "$T/S.lsqt"
cp "$EX/slab.lsqt" "$T/one.lsqt"

started=1 # stop is safe after a half start
if ! out=$(timeout -k 5 "$(left)" bash "$SN" start "$S" 2>&1); then
  echo "$out"
  skip "could not start a single-node SLURM (log tails above)"
fi
echo "$out" | grep -v '^export ' || true
export SLURM_CONF=$S/slurm.conf
export LSQT_CL=$BIN LSQT_SLURM_POLL=0.5

F=(-p 20000 -wo 4 -wi 24 -s 7)
t0=$(date +%s.%N)
rc=0
run timeout -k 5 "$(left)" bash "$REPO/tools/slurm/submit.sh" --wait 4 "$T/S.lsqt" "${F[@]}" || rc=$?
t1=$(date +%s.%N)
fail=0
if [ "$rc" != 0 ]; then
  echo "FAIL: submit.sh --wait exited $rc" >&2
  for f in "$T"/S.lsqt.slurm/*.rc; do # the logs of the steps that failed
    if [ ! -f "$f" ] || [ "$(cat "$f")" = 0 ]; then continue; fi
    echo "---- ${f%.rc}.log" >&2
    tail -n 15 "${f%.rc}.log" >&2
  done
  exit 1
fi

run timeout -k 5 "$(left)" "$BIN" -q "${F[@]}" "$T/one.lsqt"
t2=$(date +%s.%N)
for ext in lss raw; do
  if ! cmp "$T/S.lsqt.$ext" "$T/one.lsqt.$ext"; then
    echo "FAIL: the SLURM round trip's .$ext differs from one process's" >&2
    fail=1
  fi
done
if compgen -G "$T/S.lsqt.shard-*" >/dev/null; then
  echo "FAIL: shard files left after the final merge:" "$T"/S.lsqt.shard-* >&2
  fail=1
fi
awk -v a="$t0" -v b="$t1" -v c="$t2" \
  'BEGIN { printf "test_slurm: round trip (4 shards, merge, 4 refinements, merge) %.1f s; one process %.1f s\n", b - a, c - b }'
[ "$fail" = 0 ] && echo "test_slurm: LSS and RAW equal one process's"
exit "$fail"
