# Shared by the shell tests (sourced): pass/fail counters and `expect`.
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
