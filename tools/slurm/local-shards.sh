#!/usr/bin/env bash
# usage: tools/slurm/local-shards.sh N FILE [lsqt-cl flags]
# Runs the SLURM recipe's steps (steps.sh) one after another on this machine: N shards,
# merge, N refine shards, merge. Leaves FILE.lss and FILE.raw, byte-identical to
# `lsqt-cl [flags] FILE` in one process. Installed, this is PREFIX/bin/lsqt-local-shards
# and runs lsqt-slurm-steps beside it (symlinks to it are followed), else steps.sh (the
# source tree). LSQT_CL names the binary; unset, steps.sh chooses (see there).
set -euo pipefail
if [ "${1:-}" = --version ]; then # the lsqt-cl the steps run: its version and commit
  here=$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")
  s=$here/lsqt-slurm-steps
  [ -f "$s" ] || s=$here/steps.sh
  v=$(bash "$s" --version) && echo "${0##*/} ${v#* }"
  exit
fi
n=${1:?usage: ${0##*/} N FILE [lsqt-cl flags]}
file=${2:?usage: ${0##*/} N FILE [lsqt-cl flags]}
shift 2
here=$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")
steps=$here/lsqt-slurm-steps
[ -f "$steps" ] || steps=$here/steps.sh
[ -f "$steps" ] || { echo "${0##*/}: no lsqt-slurm-steps or steps.sh beside $here" >&2; exit 2; }
for ((k = 0; k < n; k++)); do bash "$steps" shard "$k" "$n" "$file" "$@"; done
bash "$steps" merge "$n" "$file" "$@"
for ((k = 0; k < n; k++)); do bash "$steps" refine "$k" "$n" "$file" "$@"; done
bash "$steps" merge "$n" "$file" "$@"
