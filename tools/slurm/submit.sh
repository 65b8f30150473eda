#!/usr/bin/env bash
# The job-array recipe for a SLURM cluster: N shards of a run, their merge, N shards of the
# refinement, and the final merge, all submitted at once and chained by dependencies.
#
#   bash tools/slurm/submit.sh [--wait] N FILE [lsqt-cl flags...]
#
#   A  --array=0-(N-1)        steps.sh shard  K N FILE FLAGS   (RRSS pilot and first paths)
#   B  afterok:A              steps.sh merge    N FILE FLAGS   (FILE.lss: directions fixed)
#   C  afterok:B, array 0..   steps.sh refine K N FILE FLAGS   (the remaining paths)
#   D  afterok:C              steps.sh merge    N FILE FLAGS   (FILE.lss and FILE.raw)
#
# --wait (first argument only) waits until D has ended and exits non-zero unless every step
# succeeded. Environment:
#   LSQT_CL       the lsqt-cl binary, at the same path on the compute nodes; jobs get the
#                 whole environment (--export=ALL). Default: the lsqt-cl beside this script
#                 (installed: PREFIX/bin), else in the source tree build/lsqt-cl, else
#                 lsqt-cl on PATH.
#   SBATCH_OPTS   extra sbatch options for all four jobs, split at blanks (no quoting), e.g.
#                 "-p short --time=02:00:00 --signal=B:USR1@300".
#   SBATCH_ARRAY_OPTS  extra options for the shard and refine arrays only, e.g. "--gres=gpu:1"
#                 (the merges need no GPU).
#   LSQT_SLURM_POLL  seconds between squeue polls with --wait (default 10).
#   LSQT_STEPS    the steps script (default: lsqt-slurm-steps next to this file, installed
#                 in PREFIX/bin; else steps.sh, the source tree). Symlinks to this file
#                 are followed.
# Logs and each step's exit status go to FILE.slurm/ (STEP-JOBID[_TASK].log and .rc).
set -euo pipefail

die() {
  echo "submit: $*" >&2
  exit 2
}
usage() { die "usage: $0 [--wait] N FILE [lsqt-cl flags...]"; }
if [ "${1:-}" = --version ]; then # the lsqt-cl the steps run: its version and commit
  s=$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/lsqt-slurm-steps
  [ -f "$s" ] || s=$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/steps.sh
  v=$(bash "$s" --version) && echo "${0##*/} ${v#* }"
  exit
fi

wait_end=0
if [ "${1:-}" = --wait ]; then
  wait_end=1
  shift
fi
[ $# -ge 2 ] || usage
n=$1
file=$2
shift 2
[[ $n =~ ^[1-9][0-9]*$ ]] || die "N must be a positive integer, not '$n'"
[ -f "$file" ] || die "no such file: $file"
# What this needs of SLURM, checked before anything is submitted; without it the same
# shards run on this machine with local-shards.sh (installed: lsqt-local-shards).
local_cmd=lsqt-local-shards
[ "${BASH_SOURCE[0]##*/}" = submit.sh ] && local_cmd="bash $(dirname "${BASH_SOURCE[0]}")/local-shards.sh"
need=(sbatch scancel)
[ "$wait_end" = 0 ] || need+=(squeue)
missing=()
for c in "${need[@]}"; do command -v "$c" >/dev/null || missing+=("$c"); done
[ ${#missing[@]} -eq 0 ] || die "${missing[*]} not found: this needs a SLURM cluster's client commands (Debian: \
slurm-client, with SLURM_CONF or /etc/slurm/slurm.conf naming the cluster). Without SLURM, the same shards run \
one after another on this machine, with the same result: $local_cmd $n $file $*"
# The client commands without a cluster that answers them (no controller configured or
# reachable): asked once, before anything is made. --test-only submits nothing.
read -r -a opts <<<"${SBATCH_OPTS:-}"
if ! probe=$(printf '#!/bin/sh\ntrue\n' | sbatch --test-only "${opts[@]}" 2>&1); then
  die "no SLURM cluster answers here (sbatch --test-only: $(head -1 <<<"$probe")). On a cluster, run this \
where its controller is reachable (a login node). Without SLURM, the same shards run one after another on this \
machine, with the same result: $local_cmd $n $file $*"
fi

# Absolute paths: a job may start in another folder, on another machine with the same mounts.
abspath() { echo "$(cd "$(dirname "$1")" && pwd -P)/$(basename "$1")"; }
file=$(abspath "$file")
self=$(readlink -f "${BASH_SOURCE[0]}")
here=$(dirname "$self")
if [ -z "${LSQT_STEPS:-}" ]; then
  steps=$here/lsqt-slurm-steps
  [ -f "$steps" ] || steps=$here/steps.sh
  [ -f "$steps" ] || die "no steps script (lsqt-slurm-steps or steps.sh) beside $self"
else
  steps=$LSQT_STEPS
fi
[ -f "$steps" ] || die "no steps script: $steps"
steps=$(abspath "$steps")
# Resolved here, so that a missing binary fails now and not in N queued jobs.
if [ -z "${LSQT_CL:-}" ]; then
  if [ -x "$here/lsqt-cl" ]; then
    LSQT_CL=$here/lsqt-cl
  elif [ "${self##*/}" = submit.sh ] && [ -x "$here/../../build/lsqt-cl" ]; then
    LSQT_CL=$here/../../build/lsqt-cl
  fi
fi
if [[ ${LSQT_CL:-lsqt-cl} == */* ]]; then
  LSQT_CL=$(abspath "$LSQT_CL")
else
  LSQT_CL=$(command -v "${LSQT_CL:-lsqt-cl}") || die "lsqt-cl not found on PATH; set LSQT_CL"
fi
[ -x "$LSQT_CL" ] || die "not executable: $LSQT_CL"
export LSQT_CL

logdir=$file.slurm
mkdir -p "$logdir"
read -r -a array_opts <<<"${SBATCH_ARRAY_OPTS:-}"

# The batch script of one step, fed to sbatch on stdin. It records the step's exit status in
# a marker (the only record once SLURM forgets the job: there is no accounting to ask). The
# step runs in a process group of its own so that a signal meant for the batch shell
# (--signal=B:USR1@T, scancel --batch -s USR1) can be passed on to lsqt-cl inside steps.sh.
# SIGTERM is not passed on: at the time limit or on scancel SLURM sends it to every process
# of the job itself, and a second signal makes lsqt-cl exit without writing its LSS.
job_script() { # step array(0|1) args-after-the-task-id...
  local step=$1 array=$2
  shift 2
  echo '#!/bin/bash'
  printf 'step=%q array=%q logdir=%q\n' "$step" "$array" "$logdir"
  printf 'pre=(bash %q %q)\n' "$steps" "$step"
  printf 'post=(%s)\n' "$(printf '%q ' "$@")"
  cat <<'EOF'
set -u
if [ "$array" = 1 ]; then
  tag=${SLURM_ARRAY_JOB_ID}_${SLURM_ARRAY_TASK_ID}
  task=("$SLURM_ARRAY_TASK_ID")
else
  tag=$SLURM_JOB_ID
  task=()
fi
child=
forward() { [ -z "$child" ] || kill -s "$1" -- "-$child" 2>/dev/null || true; }
trap 'forward USR1' USR1
trap 'forward USR2' USR2
trap 'echo "step: SIGTERM (time limit or scancel)" >&2' TERM
trap '' HUP
cmd=("${pre[@]}" "${task[@]}" "${post[@]}")
echo "step: ${cmd[*]} (job $tag on $(hostname), $(date))"
setsid "${cmd[@]}" &
child=$!
while :; do
  rc=0
  wait "$child" || rc=$?
  kill -0 "$child" 2>/dev/null || break
done
# lsqt-cl may outlive a steps.sh killed by a forwarded signal: let it write its LSS.
while kill -0 -- "-$child" 2>/dev/null; do sleep 1; done
echo "step: exit status $rc ($(date))"
echo "$rc" >"$logdir/$step-$tag.rc"
exit "$rc"
EOF
}

submitted=()
# A half-submitted chain would leave shards without their merge: cancel what went in.
# shellcheck disable=SC2317 # called by the trap
cleanup_submit() {
  if [ ${#submitted[@]} -gt 0 ]; then
    echo "submit: cancelling ${submitted[*]}" >&2
    scancel "${submitted[@]}" || true
  fi
}
trap cleanup_submit EXIT

id=
submit() { # step array(0|1) dependency args... -> sets id (not $(...): submitted must grow here)
  local step=$1 array=$2 dep=$3 out
  shift 3
  local args=(--parsable --export=ALL --chdir="$PWD" -J "lsqt-$step")
  if [ "$array" = 1 ]; then
    args+=(--array="0-$((n - 1))" -o "$logdir/$step-%A_%a.log" "${array_opts[@]}")
  else
    args+=(-o "$logdir/$step-%j.log")
  fi
  # kill-on-invalid-dep: a failed step cancels what depends on it instead of leaving it
  # pending forever (DependencyNeverSatisfied), so the chain always ends.
  [ -z "$dep" ] || args+=(--dependency="afterok:$dep" --kill-on-invalid-dep=yes)
  out=$(job_script "$step" "$array" "$@" | sbatch "${args[@]}" "${opts[@]}") || exit 1
  id=${out%%;*} # --parsable prints "id" or "id;cluster"
  submitted+=("$id")
}

# shard and merge; then, with the directions of the merged pilot, refine and merge again.
submit shard 1 "" "$n" "$file" "$@"
ja=$id
submit merge 0 "$ja" "$n" "$file" "$@"
jb=$id
# merge runs twice; the second's logs and markers are told apart by their job ids.
submit refine 1 "$jb" "$n" "$file" "$@"
jc=$id
submit merge 0 "$jc" "$n" "$file" "$@"
jd=$id
submitted=()
echo "submit: shard ${ja} (array 0-$((n - 1))), merge ${jb}, refine ${jc} (array 0-$((n - 1))), merge ${jd}; logs in $logdir"
echo "${ja} ${jb} ${jc} ${jd}"
[ "$wait_end" = 1 ] || exit 0

# No accounting (sacct) is assumed: poll squeue until D has left the queue, then read the
# markers. A failure cancels the rest of the chain, so D always ends.
poll=${LSQT_SLURM_POLL:-10}
while [ -n "$(squeue -h -j "$jd" -o %i 2>/dev/null)" ]; do
  sleep "$poll"
done
bad=0
check() { # step tag
  local f=$logdir/$1-$2.rc rc
  if [ -f "$f" ]; then
    rc=$(cat "$f")
    [ "$rc" = 0 ] && return 0
    echo "submit: $1 $2 failed (exit status $rc); see $logdir/$1-$2.log" >&2
  else
    echo "submit: $1 $2 did not finish (cancelled, killed or never ran; a failed step cancels the ones after it)" >&2
  fi
  bad=1
}
for ((k = 0; k < n; k++)); do check shard "${ja}_$k"; done
check merge "$jb"
for ((k = 0; k < n; k++)); do check refine "${jc}_$k"; done
check merge "$jd"
if [ "$bad" = 0 ]; then
  echo "submit: all steps succeeded"
fi
exit "$bad"
