#!/usr/bin/env bash
# -t N: PoCL's CPU device runs N worker threads. Counted from /proc while a run goes on:
# the process has one thread more with -t 2 than with -t 1 (main, signal and PoCL's
# workers). Debian 12's PoCL 3.1 reads POCL_MAX_PTHREAD_COUNT, not POCL_CPU_MAX_CU_NUM, so
# setting only the latter left -t 1 on every core. Needs 2 CPUs and /proc (skips, 77).
# usage: test_threads.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
if [ "$(nproc)" -lt 2 ] || [ ! -d /proc/self/task ]; then
  echo "test_threads: SKIPPED: needs 2 CPUs and /proc"
  exit 77
fi
cli_workdir
cp "$EX/slab.lsqt" slab.lsqt
"$BIN" -q -R slab.lsqt -p 1000 -o /dev/null --lss warm.lss # fills the kernel cache

# most_threads N: the most threads seen in a 3-second run with -t N.
most_threads() {
  "$BIN" -q -R slab.lsqt -p 1000000000 --time-limit 3 -o /dev/null --lss "t$1.lss" -t "$1" &
  local pid=$! most=0 c
  for _ in $(seq 1 20); do
    sleep 0.1
    c=$(find "/proc/$pid/task" -mindepth 1 -maxdepth 1 2>/dev/null | wc -l)
    [ "$c" -gt "$most" ] && most=$c
  done
  wait "$pid"
  echo "$most"
}
one=$(most_threads 1)
two=$(most_threads 2)
echo "threads with -t 1: $one, with -t 2: $two"
if [ "$one" -ge 2 ] && [ "$two" = $((one + 1)) ]; then ok; else bad "-t 1 ran $one threads and -t 2 $two: expected one more with -t 2"; fi
expect 0 "other" -- "$BIN" --help
finish test_threads
