#!/usr/bin/env bash
# Where lsqt-cl's outputs go (util.h's rules, through the CLI): FIFO with a reader, symlink,
# -o - in a pipe, a private null device, a directory, a full file system, unwritable
# paths found before any work, a write that fails at the end, and an LSS that is not a
# regular file. Device nodes are made here with mknod, never the system's.
# usage: test_outputs.sh LSQT_CL EXAMPLES_DIR
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
cli_args BIN EX -- "$@"
cli_workdir
no_temporaries() { ! find "$T" -name '*.tmp.*' | grep -q . && ok || bad "temporaries left: $(find "$T" -name '*.tmp.*')"; }

cp "$EX/tutorial/Lambertian.lsqt" L.lsqt
RUN=(-p 500 -wo 4 -wi 16)
"$BIN" -q -R "${RUN[@]}" -o ref.raw --lss ref.lss L.lsqt && ok || bad "reference run"

# -o -: the RAW alone on stdout, byte for byte; the summary on stderr.
"$BIN" -R "${RUN[@]}" -o - --lss p.lss L.lsqt 2>piped.err | cat >piped.raw
cmp -s piped.raw ref.raw && ok || bad "-o - differs from the file RAW: $(head -3 piped.raw)"
grep -q "R +- 1 s.e." piped.err && ok || bad "-o -: no summary on stderr: $(cat piped.err)"
expect 2 "two outputs would be written to '-'" -- "$BIN" "${RUN[@]}" -o - --json - L.lsqt
expect 2 "-H writes two files" -- "$BIN" -H "${RUN[@]}" -o - L.lsqt

# A FIFO is written in place for its reader and stays a FIFO.
mkfifo fifo
(timeout 120 cat fifo >from_fifo.raw) &
reader=$!
expect 0 "" -- "$BIN" -q -R "${RUN[@]}" -o fifo --lss f.lss L.lsqt
wait $reader
cmp -s from_fifo.raw ref.raw && ok || bad "the FIFO's reader got another RAW"
[ -p fifo ] && ok || bad "fifo is no longer a FIFO"
# Temporaries that a killed run of this machine left beside an output go when the next
# run writes there; a live process's, and another machine's (a shared folder), stay.
host=$(hostname | tr './' '__')
true &
dead=$!
wait $dead
touch "st.raw.tmp.$host.$dead.0" "st.raw.tmp.$host.$$.0" "st.raw.tmp.elsewhere.$dead.0"
expect 0 "" -- "$BIN" -q -R "${RUN[@]}" -o st.raw --lss st.lss L.lsqt
[ ! -e "st.raw.tmp.$host.$dead.0" ] && [ -e "st.raw.tmp.$host.$$.0" ] && [ -e "st.raw.tmp.elsewhere.$dead.0" ] && ok ||
  bad "stale temporaries: $(ls st.raw.tmp.* 2>&1)"
rm -f st.raw.tmp.*
# A FIFO nobody reads: the LSS is written first (the state is safe), the run says it is
# waiting, and SIGTERM ends the wait: exit 1 naming the FIFO, well within seconds.
"$BIN" -R "${RUN[@]}" -o fifo --lss nf.lss L.lsqt >nf.log 2>&1 &
pid=$!
for _ in $(seq 300); do [ -s nf.lss ] && break; sleep 0.1; done # 30 s: build and run take a few
[ -s nf.lss ] && "$BIN" info nf.lss >/dev/null 2>&1 && ok || bad "no LSS while the RAW waits for a reader"
sleep 1.5 # past the note's second
kill -TERM $pid 2>/dev/null
for _ in $(seq 100); do kill -0 $pid 2>/dev/null || break; sleep 0.1; done
if kill -0 $pid 2>/dev/null; then
  kill -9 $pid
  bad "SIGTERM did not end the wait for the FIFO's reader"
fi
wait $pid
rc=$?
[ "$rc" = 1 ] && grep -q "cannot write 'fifo': no process read the FIFO before the interrupt" nf.log &&
  grep -q "waiting for a process to read the FIFO 'fifo'" nf.log && ok || bad "FIFO without a reader: exit $rc, $(cat nf.log)"
# As an LSS, a FIFO is never read (that hung): an error, or with -R a sink for the state.
expect 2 "cannot continue from 'fifo': it is a FIFO" -- "$BIN" "${RUN[@]}" -o x.raw --lss fifo L.lsqt
[ ! -e x.raw ] && ok || bad "the refused run wrote x.raw"
(timeout 120 cat fifo >from_fifo.lss) &
reader=$!
expect 0 "" -- "$BIN" -q -R "${RUN[@]}" -o x.raw --lss fifo L.lsqt
wait $reader
[ "$(head -c 7 from_fifo.lss)" = "LSQTLSS" ] && ok || bad "the FIFO's reader got no LSS"

# A symlink into another folder keeps the link; its target is replaced, no temporaries.
mkdir -p other links
echo old >other/real.raw
ln -s ../other/real.raw links/r.raw
expect 0 "" -- "$BIN" -q -R "${RUN[@]}" -o links/r.raw --lss s.lss L.lsqt
[ -L links/r.raw ] && ok || bad "the symlink was replaced by a file"
cmp -s other/real.raw ref.raw && ok || bad "the link's target does not hold the RAW"
no_temporaries

# A private null device (made here): written in place, still a character device.
if mknod null c 1 3 2>/dev/null && mknod full c 1 7 2>/dev/null; then
  expect 0 "" -- "$BIN" -q -R "${RUN[@]}" -o null --lss null --json null L.lsqt
  [ "$(stat -c %F null)" = "character special file" ] && ok || bad "null is now a $(stat -c %F null)"
  # A write that fails at the end (ENOSPC) is reported; the other outputs are written.
  expect 1 "cannot write 'full': No space left on device" -- "$BIN" -R "${RUN[@]}" -o full --lss end.lss --json end.json L.lsqt
  [ -s end.lss ] && [ -s end.json ] && ok || bad "the other outputs were not written after a failed one"
  [ "$(stat -c %F full)" = "character special file" ] && ok || bad "full is now a $(stat -c %F full)"
else
  echo "skip: cannot mknod here (not root?): null-device checks skipped"
fi

# A directory as the target: a clear error, exit 1, nothing simulated.
mkdir -p adir
expect 1 "cannot write 'adir': it is a directory (nothing simulated)" -- "$BIN" -R "${RUN[@]}" -o adir --lss d.lss L.lsqt
[ ! -e d.lss ] && ok || bad "an LSS was written although the RAW cannot be"
# Every output location is checked before any work.
expect 1 "cannot write 'nodir/x.lss'" -- "$BIN" -R "${RUN[@]}" -o n.raw --lss nodir/x.lss L.lsqt
expect 1 "cannot write 'nodir/x.json'" -- "$BIN" -R "${RUN[@]}" -o n.raw --json nodir/x.json L.lsqt
[ ! -e n.raw ] && ok || bad "RAW written although the LSS/JSON path is unwritable"
# Two outputs on one file, or an output over the input.
expect 2 "two outputs would be written to 'same'" -- "$BIN" "${RUN[@]}" -o same --lss same L.lsqt
expect 2 "would replace the input" -- "$BIN" "${RUN[@]}" -o L.lsqt L.lsqt
cmp -s L.lsqt "$EX/tutorial/Lambertian.lsqt" && ok || bad "the input was changed"

# A full file system (a small tmpfs, as root): the write fails with ENOSPC, exit 1, the
# previous files stay whole and no temporary is left.
if cli_tmpfs small 8m; then
  expect 0 "" -- "$BIN" -q -R "${RUN[@]}" -o small/old.raw --lss small/old.lss L.lsqt
  cp small/old.raw keep.raw
  cp small/old.lss keep.lss
  dd if=/dev/zero of=small/filler bs=4k 2>/dev/null
  expect 1 "No space left on device" -- "$BIN" "${RUN[@]}" -o small/old.raw --lss small/old.lss L.lsqt
  cmp -s small/old.raw keep.raw && cmp -s small/old.lss keep.lss && ok || bad "a full disk damaged the old files"
  expect 1 "cannot write 'small/new.raw': No space left on device" -- "$BIN" -R "${RUN[@]}" -o small/new.raw --lss n2.lss L.lsqt
  [ ! -e small/new.raw ] && ok || bad "a half-written small/new.raw exists"
  [ -s n2.lss ] && ok || bad "the LSS on the other file system was not written"
  no_temporaries
  umount small
else
  echo "skip: cannot mount a tmpfs here (not root?): full file system checks skipped"
fi

finish test_outputs
