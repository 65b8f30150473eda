# Shared by the shell tests (sourced): the preamble (set -u, the arguments, a temporary
# working folder removed at exit), pass/fail counters, `expect` and `finish`. A test starts
#   source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
#   cli_args BIN EX -- "$@"
#   cli_workdir
set -u

# cli_args NAME... -- ARG...: the test's arguments as the variables NAME, in order; fewer
# arguments than names is a usage error (exit 2).
cli_args() {
  local names=() n
  while [ $# -gt 0 ] && [ "$1" != -- ]; do names+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  if [ $# -lt ${#names[@]} ]; then
    echo "usage: $(basename "$0") ${names[*]}" >&2
    exit 2
  fi
  for n in "${names[@]}"; do printf -v "$n" '%s' "$1"; shift; done
}

pass=0
fail=0
ok() { pass=$((pass + 1)); }
# With LSQT_CHECK_FAIL_FAST=1 (the mutation check) the first failure ends the test.
bad() {
  fail=$((fail + 1))
  echo "FAIL: $*" >&2
  if [ -n "${LSQT_CHECK_FAIL_FAST:-}" ] && [ "${LSQT_CHECK_FAIL_FAST}" != 0 ]; then exit 1; fi
}

# expect STATUS SUBSTRING -- command...: exit status and a substring of stdout+stderr.
# A command that hangs fails after 120 s instead of stalling the suite.
expect() {
  local want=$1 text=$2
  shift 3
  local out rc
  out=$(timeout -k 5 120 "$@" 2>&1)
  rc=$?
  if [ "$rc" != "$want" ]; then bad "[$*] exit $rc, expected $want: $out"; return; fi
  if [ -n "$text" ] && ! grep -qF -- "$text" <<<"$out"; then bad "[$*] output lacks '$text': $out"; return; fi
  ok
}

# finish NAME: the summary line, and the exit status of the test.
finish() {
  echo "$1: $pass passed, $fail failed"
  [ "$fail" = 0 ]
}

# The temporary folder. cli_tmpdir makes a fresh one, $T, removed at exit with all in it;
# cli_workdir also makes it the working folder (a test writes only there). At exit the
# test's own cli_at_exit runs first, where it defines one (to stop what it started), then
# any tmpfs of cli_tmpfs is unmounted and $T removed; the test's exit status is kept.
T=
cli_mounts=()
cli_exit() {
  if declare -F cli_at_exit >/dev/null; then cli_at_exit; fi
  local m
  for m in "${cli_mounts[@]}"; do mountpoint -q "$m" 2>/dev/null && umount "$m"; done
  [ -n "$T" ] && rm -rf "$T"
}
cli_tmpdir() {
  T=$(mktemp -d) || exit 1
  trap cli_exit EXIT
}
cli_workdir() {
  cli_tmpdir
  cd "$T" || exit 1
}

# cli_tmpfs DIR SIZE: a tmpfs of SIZE (mount's size=, e.g. 8m) on DIR, made if missing and
# unmounted at exit; status 1 where it cannot be mounted (not root): skip what needs it.
cli_tmpfs() {
  mkdir -p "$1" && mount -t tmpfs -o "size=$2" tmpfs "$1" 2>/dev/null || return 1
  cli_mounts+=("$(cd "$1" && pwd -P)")
}
