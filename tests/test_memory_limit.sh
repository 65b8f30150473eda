#!/usr/bin/env bash
# --max-memory: a run whose estimated peak memory (memory.h) exceeds it is refused with
# exit 2 before anything is simulated or written, naming the figure and the flags that
# need less; under it (and with 0, no limit) the run goes on; --plan shows the estimate.
# usage: test_memory_limit.sh LSQT_CL
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN -- "$@"
cli_workdir
printf 'Medium\nLayer z=0 LambertianBsdf fR=0.6 fT=0\nMedium\n' >L.lsqt
W=(--wavelengths 400:700:10 -p 300)
D=(--wavelengths 400:700:10 -p 100000) # every batch reached: the tallies' full size

# 31 bands of the default grid at 1e5 paths: 0.2 GB of tallies on the host, as much on
# the device, the RRSS pilot's more (nothing runs: it is refused before)
expect 2 "more than the 300 MB allowed (--max-memory)" -- "$BIN" "${D[@]}" --max-memory 300M -o A.raw --lss A.lss L.lsqt
expect 2 "Fewer bands per run (split --wavelengths" -- "$BIN" "${D[@]}" --max-memory 0.1G -o A.raw --lss A.lss L.lsqt
[ -z "$(ls -A | grep -v '^L.lsqt$')" ] && ok || bad "a refused run wrote: $(ls -A)"
# its figure: about 0.6 GB (the pilot's tallies twice, the runtime); at 300 paths a slice
# only the first 2 of the 32 batches are reached: about 0.2 GB
mb() { python3 -c "import re, sys; print(float(re.search(r'need about ([0-9.]+) MB', sys.argv[1]).group(1)))" "$1"; }
big=$(mb "$("$BIN" "${D[@]}" --max-memory 10M L.lsqt 2>&1)")
small=$(mb "$("$BIN" "${W[@]}" --max-memory 10M L.lsqt 2>&1)")
python3 -c "import sys; b, s = map(float, sys.argv[1:]); sys.exit(not (450 < b < 800 and 100 < s < 300))" "$big" "$small" &&
  ok || bad "the estimates of 31 bands: $big MB at 1e5 paths, $small MB at 300"
expect 0 "" -- "$BIN" -q "${W[@]}" --max-memory 1G -o B.raw --lss B.lss L.lsqt
[ -s B.lss ] && [ -s B.400nm.raw ] && ok || bad "the run under --max-memory wrote: $(ls -A)"
expect 0 "" -- "$BIN" -q -p 300 --max-memory 0 -o C.raw --lss C.lss L.lsqt
# one band: far below the default (80 % of the memory available)
expect 0 "" -- "$BIN" -q -p 300 -o D.raw --lss D.lss L.lsqt
expect 2 "--max-memory" -- "$BIN" -p 300 --max-memory 12Q L.lsqt
mkdir tmp
TMPDIR=$PWD/tmp "$BIN" --plan -wo 4 -wi 16 --wi-spread L.lsqt >plan.out 2>plan.err &&
  grep -q "^peak memory of a run of 8192 paths per slice or more: about [0-9.]* MB (tallies: [0-9.]* MB on the host" plan.out && ok ||
  bad "--plan's memory line: $(cat plan.out plan.err)"

finish test_memory_limit
