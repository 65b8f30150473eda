# Sourced by tools/test.sh and .ci/run: `step NAME CMD...` runs CMD and records its wall
# time; `steps_done LABEL BUDGET_S` prints each step's time and the total against the
# budget, so the end of every log shows where the time went. A failing step prints its
# time too, then the script exits with that step's status.
_steps=()
_t0=$(date +%s)
step() {
  local name=$1 t rc=0
  shift
  t=$(date +%s)
  echo "== $name: $*"
  "$@" || rc=$?
  _steps+=("$name $(($(date +%s) - t))")
  if [ "$rc" != 0 ]; then
    echo "== $name failed (exit $rc) after $(($(date +%s) - t)) s"
    steps_done "${0##*/}" 0
    exit "$rc"
  fi
}
steps_done() {
  local label=$1 budget=$2 total=$(($(date +%s) - _t0)) s
  echo "== $label: time per step (wall seconds)"
  for s in "${_steps[@]}"; do printf '   %-12s %6d s\n' ${s}; done
  if [ "$budget" -gt 0 ]; then
    printf '   %-12s %6d s (budget %d s%s)\n' total "$total" "$budget" \
      "$([ "$total" -le "$budget" ] || echo ': OVER BUDGET')"
  else
    printf '   %-12s %6d s\n' total "$total"
  fi
}
