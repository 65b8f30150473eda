#!/usr/bin/env bash
# Shards and merge (docs/design.md section 4.2): the parts of a run, merged, are the run in one process byte
# for byte (tallies are integers, each path's random numbers depend only on its index);
# overlapping, missing, foreign or unmerged parts are refused; --partial keeps what there
# is and a continued partial state completes the run; RRSS progressive runs: the pilot
# is a share of the first run's -p only, so `-p 10000; -p 20000` = `-p 10000` three times.
# usage: test_shards.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
SH="$(cd "$(dirname "${BASH_SOURCE[0]}")/../tools/slurm" && pwd)/local-shards.sh"
cli_workdir
export LSQT_CL=$BIN

# same A B: both files exist and are byte-identical
same() {
  if [ -f "$1" ] && [ -f "$2" ] && cmp -s "$1" "$2"; then ok; else bad "$1 and $2 differ (or one is missing)"; fi
}
# fresh NAME: a copy of the slab example as NAME.lsqt, with no state
fresh() { rm -f "$1".lsqt*; cp "$EX/slab.lsqt" "$1.lsqt"; }
one() { "$BIN" -q "$@" >/dev/null; }

# 1. RRSS (default directions), 4 shards, -rp 0.3: the two-stage flow equals one process.
F=(-p 20000 -wo 4 -wi 24 -s 7 -rp 0.3)
fresh a; fresh b
bash "$SH" 4 a.lsqt "${F[@]}" -q -o a.out.raw --json a.json >/dev/null 2>shards.err ||
  bad "local-shards.sh failed: $(cat shards.err)"
one "${F[@]}" -o b.out.raw b.lsqt
same a.lsqt.lss b.lsqt.lss
same a.out.raw b.out.raw
python3 -c 'import json, sys; assert json.load(open(sys.argv[1]))["slices"][0]["paths"] == 20000' a.json && ok ||
  bad "the merged JSON is not of the whole run"
[ -e a.lsqt.raw ] && bad "a shard wrote the default RAW though -o names another" || ok
ls a.lsqt.shard-* >/dev/null 2>&1 && bad "shard files left behind after the merge" || ok
"$BIN" info a.lsqt.lss | grep -q "directions: RRSS (4 candidates per direction, pilot of 6000 paths)" && ok ||
  bad "merged LSS lacks the RRSS pilot: $("$BIN" info a.lsqt.lss | head -12)"

# 2. Even spread with -H, 3 shards (one stage: the refine shards have nothing to do), then
#    a sharded continuation equals a continuation in one process.
F=(-p 7000 -wo 4 -wi 16 --wi-spread -H -s 3)
fresh c; fresh d
bash "$SH" 3 c.lsqt "${F[@]}" -q >/dev/null 2>&1 || bad "local-shards.sh (spread) failed"
one "${F[@]}" d.lsqt
same c.lsqt.lss d.lsqt.lss
same c.lsqt.R.raw d.lsqt.R.raw
same c.lsqt.T.raw d.lsqt.T.raw
bash "$SH" 2 c.lsqt -p 3000 -H -q >/dev/null 2>&1 || bad "sharded continuation failed"
one -p 3000 -H d.lsqt
same c.lsqt.lss d.lsqt.lss
same c.lsqt.R.raw d.lsqt.R.raw

# 3. RRSS progressive identity: the pilot is rp of the first run's -p only.
fresh e; fresh g
one -p 10000 -wo 4 -wi 24 e.lsqt && one -p 20000 e.lsqt
one -p 10000 -wo 4 -wi 24 g.lsqt && one -p 10000 g.lsqt && one -p 10000 g.lsqt
same e.lsqt.lss g.lsqt.lss
same e.lsqt.raw g.lsqt.raw

# 4. Refusals. Shards of a spread run (one stage) as material.
F=(-p 4000 -wo 4 -wi 16 --wi-spread -s 5)
fresh m; fresh full
for k in 0 1 2 3; do one "${F[@]}" --shard $k/4 m.lsqt; done
one "${F[@]}" --shard 0/2 m.lsqt
one "${F[@]}" full.lsqt
cp m.lsqt.shard-0-of-4.lss copy0.lss
expect 2 "overlapping parts" -- "$BIN" merge x.lss m.lsqt.shard-0-of-4.lss copy0.lss
expect 2 "both hold paths [0, 1000)" -- "$BIN" merge x.lss m.lsqt.shard-0-of-4.lss m.lsqt.shard-0-of-2.lss
expect 2 "given twice" -- "$BIN" merge x.lss m.lsqt.shard-1-of-4.lss m.lsqt.shard-1-of-4.lss
mkfifo part.fifo # read as an LSS, a FIFO would block the merge
expect 2 "'part.fifo' is a FIFO, not an LSS file" -- "$BIN" merge x.lss m.lsqt.shard-1-of-4.lss part.fifo
[ -e x.lss ] && bad "a refused merge wrote x.lss" || ok
expect 2 "leave out paths [3000, 4000) of the run [0, 4000): missing shards" -- \
  "$BIN" merge x.lss m.lsqt.shard-0-of-4.lss m.lsqt.shard-1-of-4.lss m.lsqt.shard-2-of-4.lss
one -s 6 -p 4000 -wo 4 -wi 16 --wi-spread --shard 3/4 --lss other.lss m.lsqt
expect 2 "differ in their seed" -- "$BIN" merge x.lss m.lsqt.shard-0-of-4.lss other.shard-3-of-4.lss
for t in 10 20 30 40 50 60 70 80; do echo "$t 0"; echo "$t 90"; done >wa.txt
for t in 12 22 32 42 52 62 72 82; do echo "$t 0"; echo "$t 90"; done >wb.txt
one -p 2000 -wo 4 --wi-file wa.txt --shard 0/2 --lss wa.lss m.lsqt
one -p 2000 -wo 4 --wi-file wb.txt --shard 1/2 --lss wb.lss m.lsqt
expect 2 "differ in their incident directions" -- "$BIN" merge x.lss wa.shard-0-of-2.lss wb.shard-1-of-2.lss
expect 2 "not an LSS file" -- "$BIN" merge x.lss m.lsqt.shard-0-of-4.lss m.lsqt
expect 2 "" -- "$BIN" merge x.lss
# --partial: the state says what it holds; continuing it runs the missing tail, and then
# it is the whole run. A gap in the middle cannot be continued.
expect 0 "(the run owes 1000 more)" -- "$BIN" merge --partial p.lss m.lsqt.shard-0-of-4.lss m.lsqt.shard-1-of-4.lss m.lsqt.shard-2-of-4.lss
"$BIN" info p.lss | grep -qF "ranges: [0, 3000) on every slice; part of a run of [0, 4000)" && ok ||
  bad "info of a partial merge: $("$BIN" info p.lss | grep ranges)"
cp m.lsqt p.lsqt
one --lss p.lss -o p.raw p.lsqt
cmp -s p.lss full.lsqt.lss && ok || bad "a continued partial merge is not the whole run"
cmp -s p.raw full.lsqt.raw && ok || bad "a continued partial merge's RAW is not the whole run's"
"$BIN" merge -q --partial gap.lss m.lsqt.shard-0-of-4.lss m.lsqt.shard-3-of-4.lss
expect 2 "gaps between them" -- "$BIN" -p 100 --lss gap.lss -o gap.raw m.lsqt
# the four, merged, are the run
expect 0 "merged 4 files" -- "$BIN" merge all.lss m.lsqt.shard-{0,1,2,3}-of-4.lss
same all.lss full.lsqt.lss
same all.raw full.lsqt.raw
# lssmerge is the same program (beside lsqt-cl), with -H and -o
expect 0 "merged 4 files" -- "$(dirname "$BIN")/lssmerge" all2.lss m.lsqt.shard-{0,1,2,3}-of-4.lss -H -o all2.raw
one "${F[@]}" -H -o fullH.raw --lss fullH.lss full.lsqt
same all2.R.raw fullH.R.raw
same all2.T.raw fullH.T.raw
expect 2 "unknown option '--bogus'" -- "$BIN" merge --bogus x.lss all.lss

# 4b. A shard stopped early (a job's time limit) and run again continues its own file;
#     the same for a pilot shard. The merged result is still the one-process run.
for mode in spread rrss; do
  fresh t; fresh u
  X=(-p 300000 -wo 4 -wi 16 -s 8)
  [ $mode = spread ] && X=(-p 2000000 -wo 4 -wi 16 -s 8 --wi-spread)
  "$BIN" -q "${X[@]}" --shard 1/2 --time-limit 0.2 t.lsqt >/dev/null 2>&1
  n1=$("$BIN" info t.lsqt.shard-1-of-2.lss --json - 2>/dev/null | python3 -c 'import json,sys; print(json.load(sys.stdin)["paths"])')
  expect 0 "continuing t.lsqt.shard-1-of-2.lss" -- "$BIN" "${X[@]}" --shard 1/2 t.lsqt
  one "${X[@]}" --shard 0/2 t.lsqt
  "$BIN" merge -q t.lsqt.lss t.lsqt.shard-{0,1}-of-2.lss
  if [ $mode = rrss ]; then
    for k in 0 1; do one "${X[@]}" --shard $k/2 --refine t.lsqt; done
    "$BIN" merge -q t.lsqt.lss t.lsqt.lss t.lsqt.shard-{0,1}-of-2.lss
  fi
  one "${X[@]}" u.lsqt
  [ "$n1" -gt 0 ] && [ "$n1" -lt $(( ${X[1]} / 2 )) ] 2>/dev/null && ok || bad "$mode: the time-limited shard held $n1 paths"
  same t.lsqt.lss u.lsqt.lss
  same t.lsqt.raw u.lsqt.raw
done

# 5. RRSS pilot shards: unmerged, incomplete or mixed with run parts, they are refused.
fresh r
for k in 0 1 2; do one -p 3000 -wo 4 -wi 16 -s 5 --shard $k/3 r.lsqt; done
expect 2 "one shard of an RRSS pilot" -- "$BIN" -p 100 --lss r.lsqt.shard-1-of-3.lss r.lsqt
expect 2 "holds (part of) an RRSS pilot" -- "$BIN" --shard 1/2 --lss r.lsqt.shard-0-of-3.lss r.lsqt
expect 2 "an RRSS pilot must be whole" -- "$BIN" merge --partial x.lss r.lsqt.shard-0-of-3.lss r.lsqt.shard-1-of-3.lss
expect 2 "differ in their stage" -- "$BIN" merge x.lss r.lsqt.shard-0-of-3.lss m.lsqt.shard-1-of-4.lss
expect 2 "holds no merged run yet" -- "$BIN" -p 3000 -wo 4 -wi 16 --shard 0/3 --refine --lss none.lss r.lsqt

# Two-sided states (--from-below): shards of a spread run, and of a continued RRSS run,
# merge into one process's LSS and both RAWs, the two-sided RRSS pilot too.
fresh w1; fresh w2
F2=(-p 3000 -wo 4 -wi 16 --wi-spread --from-below -s 4)
bash "$SH" 2 w1.lsqt "${F2[@]}" -q >/dev/null 2>&1 || bad "local-shards.sh (two-sided) failed"
one "${F2[@]}" w2.lsqt
same w1.lsqt.lss w2.lsqt.lss
same w1.lsqt.raw w2.lsqt.raw
same w1.lsqt.below.raw w2.lsqt.below.raw
fresh w3; fresh w4
one -p 2000 -wo 4 -wi 16 --from-below w3.lsqt && one -p 2000 -wo 4 -wi 16 --from-below w4.lsqt
bash "$SH" 3 w3.lsqt -p 2500 -H -q >/dev/null 2>&1 || bad "local-shards.sh (two-sided RRSS, continued) failed"
one -p 2500 -H w4.lsqt
same w3.lsqt.lss w4.lsqt.lss
same w3.lsqt.below.R.raw w4.lsqt.below.R.raw
same w3.lsqt.T.raw w4.lsqt.T.raw
fresh w5; fresh w6
bash "$SH" 2 w5.lsqt -p 3000 -wo 4 -wi 16 --from-below -q >/dev/null 2>&1 || bad "local-shards.sh (two-sided RRSS) failed"
one -p 3000 -wo 4 -wi 16 --from-below w6.lsqt
same w5.lsqt.lss w6.lsqt.lss
same w5.lsqt.below.raw w6.lsqt.below.raw

# 6. Bad flags.
for v in 4/4 1 a/b 0/0 -1/2 1/70000; do expect 2 "bad value '$v' for --shard" -- "$BIN" --shard "$v" r.lsqt; done
expect 2 "give --shard K/N too" -- "$BIN" --refine r.lsqt
expect 2 "cannot stop a shard" -- "$BIN" --shard 0/2 --target-error 0.1 r.lsqt
expect 2 "give a file" -- "$BIN" --shard 0/2 --lss - r.lsqt
# submit.sh without SLURM's commands says which are missing and the command that runs the
# same shards here (exit 2, nothing written: no FILE.slurm folder).
fresh z
mkdir -p nobin && ln -sf "$(command -v dirname)" nobin/dirname
SUB="$(dirname "$SH")/submit.sh"
PATH="$PWD/nobin" "$(command -v bash)" "$SUB" --wait 3 z.lsqt -p 100 >z.out 2>&1
rc=$?
[ "$rc" = 2 ] && grep -q "sbatch scancel squeue not found: this needs a SLURM cluster's client commands" z.out &&
  grep -q "the same shards run one after another on this machine, with the same result: bash .*local-shards.sh 3 z.lsqt -p 100" z.out &&
  [ ! -e z.lsqt.slurm ] && ok || bad "submit.sh without SLURM: exit $rc, $(cat z.out)"
# SLURM's client commands with no cluster behind them: sbatch's own error is one line of
# the message, which says that no cluster answers and gives the same local command.
mkdir -p nocl
for c in dirname head cat readlink; do ln -sf "$(command -v $c)" nocl/$c; done
printf '#!/bin/sh\ncat >/dev/null\necho "sbatch: error: resolve_ctls_from_dns_srv: res_nsearch error: Unknown host" >&2\necho "sbatch: error: fetch_config: DNS SRV lookup failed" >&2\nexit 1\n' >nocl/sbatch
printf '#!/bin/sh\nexit 0\n' >nocl/scancel
cp nocl/scancel nocl/squeue
chmod +x nocl/sbatch nocl/scancel nocl/squeue
PATH="$PWD/nocl" "$(command -v bash)" "$SUB" --wait 3 z.lsqt -p 100 >z.out 2>&1
rc=$?
[ "$rc" = 2 ] && grep -q "no SLURM cluster answers here (sbatch --test-only: sbatch: error: resolve_ctls_from_dns_srv" z.out &&
  ! grep -q "fetch_config" z.out &&
  grep -q "the same shards run one after another on this machine, with the same result: bash .*local-shards.sh 3 z.lsqt -p 100" z.out &&
  [ ! -e z.lsqt.slurm ] && ok || bad "submit.sh without a SLURM cluster: exit $rc, $(cat z.out)"
finish test_shards
