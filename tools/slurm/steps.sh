#!/usr/bin/env bash
# The steps of a sharded lsqt-cl run, one per call; the SLURM recipe (submit.sh) and
# local-shards.sh run exactly these, so both give the same bytes:
#   steps.sh shard  K N FILE [flags]  lsqt-cl FLAGS --shard K/N FILE   (FILE.shard-K-of-N.lss)
#   steps.sh merge    N FILE [flags]  lsqt-cl merge FILE.lss [FILE.lss] FILE.shard-*-of-N.lss
#   steps.sh refine K N FILE [flags]  lsqt-cl FLAGS --shard K/N --refine FILE
#   steps.sh merge    N FILE [flags]  (again)
# Why two stages: a fresh RRSS run's shards run only the pilot (each its part of it, on
# the same candidates); merging the whole pilot chooses the directions once, whatever the
# split; the refine shards then run the rest. Without RRSS (or when continuing a run) the
# first stage does all the paths and the refine shards have nothing to do.
# The LSS is FILE.lss, or --lss PATH among the flags.
# Installed, this is PREFIX/bin/lsqt-slurm-steps. The binary: $LSQT_CL if set; else the
# lsqt-cl beside this script (the installed layout; symlinks to the script are followed);
# else, in the source tree (tools/slurm/steps.sh), build/lsqt-cl; else lsqt-cl on PATH.
set -euo pipefail
self=$(readlink -f "${BASH_SOURCE[0]}")
here=$(dirname "$self")
if [ -z "${LSQT_CL:-}" ]; then
  if [ -x "$here/lsqt-cl" ]; then
    LSQT_CL=$here/lsqt-cl
  elif [ "${self##*/}" = steps.sh ] && [ -x "$here/../../build/lsqt-cl" ]; then
    LSQT_CL=$(readlink -f "$here/../../build/lsqt-cl")
  else
    LSQT_CL=lsqt-cl
  fi
fi
me=${0##*/}
if [ "${1:-}" = --version ]; then # the lsqt-cl it runs: its version and commit
  v=$("$LSQT_CL" info --version) && echo "$me ${v#lsqt-cl info }"
  exit
fi
step=${1:?usage: $me shard|refine K N FILE [flags] | $me merge N FILE [flags]}
shift
if [ "$step" = merge ]; then
  n=$1 file=$2
  shift 2
else
  k=$1 n=$2 file=$3
  shift 3
fi
# The run's LSS, and the flags merge takes (the RAW's name and form, JSON, quiet).
# The shards get the rest: a RAW of a part (-o) or its JSON would only be overwritten.
lss="$file.lss"
merge_flags=()
shard_flags=()
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
  a=${args[i]}
  case "$a" in
    --lss) lss=${args[i + 1]}; shard_flags+=("$a" "$lss"); i=$((i + 1)) ;;
    --lss=*) lss=${a#--lss=}; shard_flags+=("$a") ;;
    -o|--output|--json) merge_flags+=("$a" "${args[i + 1]}"); i=$((i + 1)) ;;
    -o=*|--output=*|--json=*) merge_flags+=("$a") ;;
    -H|--only-hemispherical|-q|--quiet) merge_flags+=("$a"); shard_flags+=("$a") ;;
    *) shard_flags+=("$a") ;;
  esac
done
command -v "$LSQT_CL" >/dev/null || {
  echo "$me: lsqt-cl not found ('$LSQT_CL'): set LSQT_CL or put lsqt-cl on PATH" >&2
  exit 2
}
base=${lss%.lss}
case "$step" in
  shard) exec "$LSQT_CL" "${shard_flags[@]}" --shard "$k/$n" "$file" ;;
  refine) exec "$LSQT_CL" "${shard_flags[@]}" --shard "$k/$n" --refine "$file" ;;
  merge)
    parts=()
    for ((j = 0; j < n; j++)); do parts+=("$base.shard-$j-of-$n.lss"); done
    inputs=()
    [ -f "$lss" ] && inputs+=("$lss")
    "$LSQT_CL" merge "$lss" "${inputs[@]}" "${parts[@]}" "${merge_flags[@]}"
    rm -f "${parts[@]}" # merged into the LSS: keeping them would invite a double count
    ;;
  *) echo "$me: unknown step '$step'" >&2; exit 2 ;;
esac
