# Shared by the shell tests (sourced): pass/fail counters and `expect`.
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*" >&2; }

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
