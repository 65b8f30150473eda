#!/usr/bin/env bash
# Install: `cmake --install BUILD --prefix` into a scratch folder, then, from
# another folder with PREFIX/bin on PATH and LSQT_CL unset, the seed guide's tutorial (§1.2,
# §2.1) as written, with its names: layered-sqt, layered-sqt-lssview, layered-sqt-lssinfo.
# The scripts must find lsqt-cl and their siblings in the prefix: lssplot,
# lsqt-local-shards and lsqt-slurm-submit run through symlinks from another folder, with a
# PATH whose first lsqt-cl is a decoy that fails, so a script that falls back to PATH
# fails here. lsqt-slurm-submit goes to a stand-in sbatch that keeps the batch scripts,
# which are then run as SLURM would (task ids, in dependency order): the bytes must be one
# process's. The man page must render and name the flags.
# usage: test_install.sh CMAKE BUILD_DIR
# (-e is left out: a failed check is counted and the next one runs; see cli_lib.sh.)
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
[ $# -eq 2 ] || { echo "usage: $0 CMAKE BUILD_DIR" >&2; exit 2; }
CMAKE=$1
BUILD=$2
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)
cli_tmpdir
P=$T/prefix
W=$T/work
mkdir -p "$W" "$T/decoy" "$T/links" "$T/slurm"
unset LSQT_CL LSQT_STEPS
export MANPAGER=cat PAGER=cat

if ! out=$("$CMAKE" --install "$BUILD" --prefix "$P" 2>&1); then
  echo "$out" >&2
  echo "FAIL: cmake --install $BUILD --prefix $P failed" >&2
  exit 1
fi

# 1. The layout.
for f in $(find "$P/bin" "$P/share/lsqt-cl" -type f -name '*.sh' -o -type f -name '*.py'); do
  [ -x "$f" ] && ok || bad "installed script without its run bit: $f"
done
for f in "$REPO"/tools/*.py "$REPO"/tools/lssplot; do
  [ "$(head -c 2 "$f")" != "#!" ] || [ -x "$f" ] || bad "$f has a #! line but no run bit"
done
for f in lsqt-cl lssview lssinfo lssmerge lssplot lsqt-slurm-submit lsqt-slurm-steps lsqt-local-shards; do
  [ -f "$P/bin/$f" ] && [ -x "$P/bin/$f" ] && ok || bad "not installed as a program: bin/$f"
done
for a in layered-sqt=lsqt-cl layered-sqt-lssview=lssview layered-sqt-lssinfo=lssinfo; do
  [ -L "$P/bin/${a%%=*}" ] && [ "$(readlink "$P/bin/${a%%=*}")" = "${a#*=}" ] && ok ||
    bad "bin/${a%%=*} is not a relative symlink to ${a#*=}"
done
[ -x "$P/share/lsqt-cl/slurm/single-node.sh" ] && ok || bad "not installed: share/lsqt-cl/slurm/single-node.sh"
expect 2 "usage:" -- "$P/share/lsqt-cl/slurm/single-node.sh"
# The example inputs, as in the source, and nothing else: a run in the source tree leaves
# outputs beside them (.raw, .lss, .json), which must not be installed.
want=$(cd "$REPO/examples" && find . -type f \( -name '*.lsqt' -o -path './tables/*.txt' \) | sort)
have=$(cd "$P/share/lsqt-cl/examples" && find . -type f | sort)
[ -n "$want" ] && [ "$want" = "$have" ] && ok ||
  bad "share/lsqt-cl/examples holds other files than the source's example inputs: $(diff <(echo "$want") <(echo "$have") | tr '\n' ' ')"
for f in $want; do cmp -s "$REPO/examples/$f" "$P/share/lsqt-cl/examples/$f" || bad "installed example $f differs"; done
MAN=$P/share/man/man1/lsqt-cl.1
[ -s "$MAN" ] && ok || bad "not installed: share/man/man1/lsqt-cl.1"

# 2. The tutorial, from another folder, by name through PATH.
export PATH=$P/bin:$PATH
[ "$(command -v layered-sqt)" = "$P/bin/layered-sqt" ] && ok || bad "layered-sqt on PATH is $(command -v layered-sqt)"
cd "$W" || exit 1
# §1.2: the help, with -h or with no file; the same text through the alias as by lsqt-cl.
expect 0 "--path-count" -- layered-sqt
expect 0 "--path-count" -- layered-sqt -h
# --version on every installed program, through PATH (the scripts report the lsqt-cl they run)
for prog in lsqt-cl lssview lssinfo lssmerge lssplot lsqt-slurm-submit lsqt-slurm-steps lsqt-local-shards; do
  expect 0 "$prog 0.1.0 (git " -- "$prog" --version
done
expect 0 "lsqt-cl 0.1.0 (git " -- layered-sqt --version # the seed guide's name for it
[ "$(layered-sqt --help)" = "$(lsqt-cl --help)" ] && ok || bad "layered-sqt --help differs from lsqt-cl --help"
mkdir tutorial1 && cd tutorial1 || exit 1
cp "$P/share/lsqt-cl/examples/tutorial/Lambertian.lsqt" .
# §2.1 (-p 4000 to be quick)
expect 0 "wrote Lambertian.lsqt.raw, Lambertian.lsqt.lss" -- layered-sqt -p 4000 Lambertian.lsqt
[ -s Lambertian.lsqt.raw ] && [ -s Lambertian.lsqt.lss ] && ok || bad "no Lambertian.lsqt.raw and .lss"
expect 0 "wrote Lambertian.lsqt.lss.png (512x512)" -- layered-sqt-lssview Lambertian.lsqt.lss
[ "$(head -c 8 Lambertian.lsqt.lss.png | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] && ok ||
  bad "Lambertian.lsqt.lss.png is not a PNG"
# R of every slice is fR = 0.6 (within 4 standard errors; this estimator's error is 0, so
# within float rounding), T is 0, 4000 paths in each of the 12 default slices.
check_info() { # PATHS
  layered-sqt-lssinfo --json - Lambertian.lsqt.lss 2>/dev/null | python3 -c '
import json, sys
paths = int(sys.argv[1])
d = json.load(sys.stdin)
s = d["slices"]
assert len(s) == 12, "%d slices" % len(s)
for x in s:
    assert x["paths"] == paths, x["paths"]
    assert abs(x["R"] - 0.6) <= max(4 * x["R_err"], 1e-6), (x["R"], x["R_err"])
    assert x["T"] == 0, x["T"]
' "$1"
}
check_info 4000 && ok || bad "layered-sqt-lssinfo: not R = 0.6, T = 0 and 4000 paths in 12 slices"
# Running again adds paths to the LSS (§2.1: progressive).
expect 0 "8000 per slice in all" -- layered-sqt -p 4000 Lambertian.lsqt
check_info 8000 && ok || bad "the second run did not continue the LSS to 8000 paths"
# §1.2: - reads stdin.
# shellcheck disable=SC2002 # the guide's command, as written
cat Lambertian.lsqt | layered-sqt -q -p 4000 -o example.raw - && [ -s example.raw ] && ok ||
  bad "cat Lambertian.lsqt | layered-sqt -p 4000 -o example.raw - wrote no example.raw"

# 3. The scripts through symlinks in another folder, LSQT_CL unset, a decoy first on PATH.
printf '#!/bin/sh\necho "decoy lsqt-cl on PATH ran" >&2\nexit 99\n' >"$T/decoy/lsqt-cl"
chmod +x "$T/decoy/lsqt-cl"
for f in lssplot lsqt-local-shards; do ln -s "$P/bin/$f" "$T/links/$f"; done
DPATH=$T/decoy:/usr/local/bin:/usr/bin:/bin
if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  expect 0 "lssplot: wrote Lambertian.lsqt.lss.plot.png" -- env PATH="$DPATH" "$T/links/lssplot" Lambertian.lsqt.lss
  [ -s Lambertian.lsqt.lss.plot.png ] && ok || bad "lssplot wrote no Lambertian.lsqt.lss.plot.png"
else
  echo "SKIP (this part only): lssplot, python3-matplotlib is not installed (bash tools/setup.sh)"
fi
cd "$W" || exit 1
F=(-p 3000 -wo 4 -wi 16 -s 5 -q)
cp "$P/share/lsqt-cl/examples/slab.lsqt" sh.lsqt
cp "$P/share/lsqt-cl/examples/slab.lsqt" one.lsqt
cp "$P/share/lsqt-cl/examples/slab.lsqt" sb.lsqt
lsqt-cl "${F[@]}" one.lsqt || bad "lsqt-cl ${F[*]} one.lsqt failed"
expect 0 "" -- env PATH="$DPATH" "$T/links/lsqt-local-shards" 2 sh.lsqt "${F[@]}"
for e in lss raw; do cmp -s sh.lsqt.$e one.lsqt.$e && ok || bad "lsqt-local-shards 2: sh.lsqt.$e is not one process's"; done

# lsqt-slurm-submit with a stand-in sbatch: it keeps each batch script and its LSQT_CL.
cat >"$T/slurm/sbatch" <<'EOF'
#!/bin/bash
case " $* " in *" --test-only "*) cat >/dev/null; echo "sbatch: Job 1 to start at now" >&2; exit 0 ;; esac
n=$(find "$SB_DIR" -name 'job*.sh' | wc -l)
cat >"$SB_DIR/job$n.sh"
printf '%s\n' "$LSQT_CL" >"$SB_DIR/job$n.lsqt_cl"
printf '%s\n' "$@" >"$SB_DIR/job$n.args"
echo $((100 + n))
EOF
chmod +x "$T/slurm/sbatch"
export SB_DIR=$T/slurm
expect 0 "merge 103" -- env PATH="$T/slurm:$T/decoy:$P/bin:/usr/bin:/bin" lsqt-slurm-submit 2 sb.lsqt "${F[@]}"
# As SLURM would: the arrays' tasks 0 and 1, the merges, in the dependency order.
job() { # N [TASK]
  local log=$T/slurm/run-$1-${2:-}.log
  env PATH="$DPATH" LSQT_CL="$(cat "$T/slurm/job$1.lsqt_cl")" SLURM_JOB_ID=$((100 + $1)) \
    SLURM_ARRAY_JOB_ID=$((100 + $1)) SLURM_ARRAY_TASK_ID="${2:-}" bash "$T/slurm/job$1.sh" >"$log" 2>&1 ||
    bad "batch script $1 (task ${2:-none}) failed: $(tail -5 "$log")"
}
if [ -f "$T/slurm/job3.sh" ]; then
  for j in 0 1 2 3; do
    [ "$(cat "$T/slurm/job$j.lsqt_cl" 2>/dev/null)" = "$P/bin/lsqt-cl" ] && ok ||
      bad "job $j: LSQT_CL is '$(cat "$T/slurm/job$j.lsqt_cl" 2>/dev/null)', not $P/bin/lsqt-cl"
    grep -qF "$P/bin/lsqt-slurm-steps" "$T/slurm/job$j.sh" 2>/dev/null && ok || bad "job $j does not run $P/bin/lsqt-slurm-steps"
  done
  job 0 0; job 0 1; job 1; job 2 0; job 2 1; job 3
  for e in lss raw; do cmp -s sb.lsqt.$e one.lsqt.$e && ok || bad "lsqt-slurm-submit's batch scripts: sb.lsqt.$e is not one process's"; done
else
  bad "lsqt-slurm-submit did not submit its 4 jobs: their batch scripts are not run"
fi

# 4. The man page: renders without warnings, at its place under MANPATH, and names the flags.
if command -v groff >/dev/null; then
  w=$(groff -man -Tutf8 -ww -z "$MAN" 2>&1)
  [ -z "$w" ] && ok || bad "groff warns about lsqt-cl.1: $w"
fi
if command -v man >/dev/null; then
  page=$(MANWIDTH=80 man -l "$MAN" 2>&1) && ok || bad "man -l lsqt-cl.1 failed: $page"
  for s in "lsqt-cl - " SYNOPSIS DESCRIPTION OPTIONS "EXIT STATUS" "SEE ALSO" "-p, --path-count N" \
           "--wi-file FILE" "lssview(1), lssinfo(1), lssmerge(1), lssplot(1)"; do
    grep -qF -- "$s" <<<"$page" && ok || bad "the rendered man page lacks '$s'"
  done
  MANWIDTH=80 man -M "$P/share/man" lsqt-cl 2>/dev/null | grep -qF -- "--path-count" && ok ||
    bad "man -M PREFIX/share/man lsqt-cl does not find the page"
  # Every installed program has a page (the seed guide's names too), and SEE ALSO names
  # only pages that are installed.
  for pg in lsqt-cl:--path-count layered-sqt:--path-count lssview:--image-dim layered-sqt-lssview:--image-dim \
            lssinfo:--bsdf layered-sqt-lssinfo:--bsdf lssmerge:--partial lssplot:--channel; do
    MANWIDTH=80 man -M "$P/share/man" "${pg%%:*}" 2>/dev/null | grep -qF -- "${pg#*:}" && ok ||
      bad "man -M PREFIX/share/man ${pg%%:*} does not show its page (${pg#*:})"
  done
  for f in "$P"/share/man/man1/*.1; do
    for ref in $(sed -n '/^\.SH SEE ALSO/,$p' "$f" | sed -n 's/^\.BR \([^ ]*\) (1).*/\1/p' | sed 's/\\-/-/g'); do
      [ -f "$P/share/man/man1/$ref.1" ] || bad "$(basename "$f") names $ref(1), which is not installed"
    done
  done
  ok
else
  echo "SKIP (this part only): man is not installed (man-db)"
  grep -qF -- '\-\-path\-count' "$MAN" && ok || bad "lsqt-cl.1 lacks --path-count"
fi
finish test_install
