#!/usr/bin/env bash
# usage: tools/slurm/local-shards.sh N FILE [lsqt-cl flags]
# Runs the SLURM recipe's steps (steps.sh) one after another on this machine: N shards,
# merge, N refine shards, merge. Leaves FILE.lss and FILE.raw, byte-identical to
# `lsqt-cl [flags] FILE` in one process. LSQT_CL names the binary (default lsqt-cl).
set -euo pipefail
n=${1:?usage: local-shards.sh N FILE [lsqt-cl flags]}
file=${2:?usage: local-shards.sh N FILE [lsqt-cl flags]}
shift 2
steps="$(dirname "$0")/steps.sh"
for ((k = 0; k < n; k++)); do bash "$steps" shard "$k" "$n" "$file" "$@"; done
bash "$steps" merge "$n" "$file" "$@"
for ((k = 0; k < n; k++)); do bash "$steps" refine "$k" "$n" "$file" "$@"; done
bash "$steps" merge "$n" "$file" "$@"
