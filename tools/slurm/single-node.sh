#!/usr/bin/env bash
# A single-node SLURM on this machine, entirely under one folder, to try tools/slurm/submit.sh
# (and to test it) without a cluster:
#   bash tools/slurm/single-node.sh start DIR   # then: export SLURM_CONF=DIR/slurm.conf
#   (or: eval "$(bash tools/slurm/single-node.sh start DIR)")
#   bash tools/slurm/single-node.sh stop DIR    # cancels the jobs, stops the daemons
# Needs root (slurmd starts jobs as their user) and the Debian packages slurm-wlm and munge
# (tools/setup.sh). Nothing outside DIR is written or read as configuration: its own munge
# key and socket, free TCP ports, no accounting, no systemd. stop leaves DIR for the caller
# to delete (it holds the logs).
set -euo pipefail

usage() {
  echo "usage: $0 start|stop DIR" >&2
  exit 2
}
[ $# -eq 2 ] || usage
cmd=$1
[ -n "$2" ] || usage
# Absolute: the paths go into slurm.conf and the daemons' command lines (stop matches them).
case $2 in /*) dir=$2 ;; *) dir=$PWD/$2 ;; esac
dir=${dir%/}

conf=$dir/slurm.conf
piddir=$dir/pids

log() { echo "single-node: $*" >&2; }

# Our own PID files, written by this script from $!, and checked against the command line
# before a kill: a stale file after a reboot must never make us kill someone else's process.
our_pid() { # name -> prints the PID if that process is still ours
  local f=$piddir/$1 pid
  [ -f "$f" ] || return 1
  pid=$(cat "$f")
  [[ $pid =~ ^[0-9]+$ ]] || return 1
  [ -r "/proc/$pid/cmdline" ] || return 1
  tr '\0' ' ' <"/proc/$pid/cmdline" | grep -qF -- "$dir/" || return 1
  echo "$pid"
}

any_alive() {
  local p
  for p in "$@"; do kill -0 "$p" 2>/dev/null && return 0; done
  return 1
}

stop_daemons() { # names...: TERM together, up to 10 s, then KILL
  local name pid pids=() i
  for name in "$@"; do
    if pid=$(our_pid "$name"); then
      kill -TERM "$pid" 2>/dev/null || true
      pids+=("$pid")
    fi
    rm -f "$piddir/$name"
  done
  [ ${#pids[@]} -gt 0 ] || return 0
  for ((i = 0; i < 100; i++)); do
    any_alive "${pids[@]}" || break
    sleep 0.1
  done
  for pid in "${pids[@]}"; do
    if kill -0 "$pid" 2>/dev/null; then
      log "PID $pid ignored SIGTERM for 10 s; killing it"
      kill -KILL "$pid" 2>/dev/null || true
    fi
  done
}

stop() {
  [ -d "$dir" ] || { log "nothing to stop: $dir does not exist"; return 0; }
  # Jobs first: slurmstepd outlives slurmd and would keep running the job's processes.
  if our_pid slurmctld >/dev/null && [ -f "$conf" ]; then
    local ids i
    ids=$(SLURM_CONF=$conf timeout 10 squeue -h -o %A 2>/dev/null | sort -u | tr '\n' ' ') || ids=
    if [ -n "${ids// /}" ]; then
      log "cancelling jobs $ids"
      # shellcheck disable=SC2086 # a list of job ids
      SLURM_CONF=$conf timeout 10 scancel $ids 2>/dev/null || true
    fi
    for ((i = 0; i < 300; i++)); do
      [ -z "$(SLURM_CONF=$conf timeout 10 squeue -h -o %A 2>/dev/null)" ] && break
      sleep 0.1
    done
  fi
  # Each running step has a socket (HOST_JOB.STEP) in the spool folder until its slurmstepd
  # exits.
  local i socks=""
  for ((i = 0; i < 300; i++)); do
    socks=$(find "$dir/spool" -maxdepth 1 -type s 2>/dev/null)
    [ -n "$socks" ] || break
    sleep 0.1
  done
  [ -z "$socks" ] || log "warning: job steps still running after 30 s:" "$socks"
  stop_daemons slurmd slurmctld
  stop_daemons munged # last: the SLURM daemons authenticate through it until they end
  log "stopped (logs in $dir/log; remove $dir when done)"
}

fail() { # message: show the logs, undo the half start
  log "error: $*"
  local f
  for f in "$dir"/log/*.log "$dir"/log/*.out; do
    [ -s "$f" ] || continue
    echo "---- tail of $f" >&2
    tail -n 20 "$f" >&2
  done
  stop
  exit 1
}

# Two free TCP ports on 127.0.0.1 (the kernel's choice, held together so they differ).
free_ports() {
  python3 - <<'EOF'
import socket
ss = [socket.socket() for _ in range(2)]
for s in ss:
    s.bind(("127.0.0.1", 0))
print(" ".join(str(s.getsockname()[1]) for s in ss))
EOF
}

# Starts "$@" as a daemon of its own session (a Ctrl-C to the caller must not kill it before
# stop cancels the jobs), its output in a log, no inherited descriptors (a caller reading our
# output through a pipe, such as ctest, would otherwise wait for the daemons to end).
spawn() { # name cmd...
  local name=$1
  shift
  setsid "$@" </dev/null >>"$dir/log/$name.out" 2>&1 &
  local pid=$! i
  echo "$pid" >"$piddir/$name"
  # Until the exec, /proc/PID/cmdline is still this script's, and our_pid would take the
  # daemon for dead (seen on a loaded machine): wait for it, or for the end of the process.
  for ((i = 0; i < 100; i++)); do
    our_pid "$name" >/dev/null && return 0
    kill -0 "$pid" 2>/dev/null || return 0
    sleep 0.05
  done
}

start() {
  [ "$(id -u)" = 0 ] || { log "error: needs root (slurmd starts jobs as their user)"; exit 1; }
  local p
  for p in munged mungekey slurmctld slurmd sinfo scontrol squeue scancel python3 setsid; do
    command -v "$p" >/dev/null || { log "error: $p not found (apt-get install slurm-wlm munge, or bash tools/setup.sh)"; exit 1; }
  done
  if our_pid slurmctld >/dev/null || our_pid slurmd >/dev/null || our_pid munged >/dev/null; then
    log "error: a SLURM of $dir is already running (stop it first)"
    exit 1
  fi
  local t0
  t0=$(date +%s.%N)
  mkdir -p "$dir"
  # munged refuses a socket folder that others cannot search, or one they can write.
  chmod 755 "$dir"
  mkdir -p "$piddir" "$dir/log" "$dir/state" "$dir/spool" "$dir/munge"
  chmod 755 "$dir/munge"
  chmod 700 "$dir/state"

  # munge: its own key, socket, PID, log and seed files, so the machine's munge (if any) is
  # neither needed nor touched.
  local msock=$dir/munge/munge.socket
  if [ ! -s "$dir/munge/munge.key" ]; then
    mungekey --create --keyfile="$dir/munge/munge.key" 2>>"$dir/log/munged.log" ||
      dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  fi
  chmod 600 "$dir/munge/munge.key"
  spawn munged munged --foreground --socket="$msock" --key-file="$dir/munge/munge.key" \
    --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" \
    --seed-file="$dir/munge/munged.seed"
  local i
  for ((i = 0; i < 100; i++)); do
    [ -S "$msock" ] && break
    our_pid munged >/dev/null || fail "munged exited"
    sleep 0.1
  done
  [ -S "$msock" ] || fail "munged did not create $msock within 10 s"

  local host cpus ports cport dport
  host=$(hostname -s)
  cpus=$(nproc)
  ports=$(free_ports)
  cport=${ports% *}
  dport=${ports#* }
  touch "$dir/plugstack.conf" # empty: keep /etc/slurm's SPANK plugins out
  # linuxproc/none: no cgroups needed (containers often lack them); no accounting: no
  # slurmdbd; batch_sched_delay=0: jobs start at once instead of in the next cycle.
  cat >"$conf" <<EOF
# Written by tools/slurm/single-node.sh: a single-node SLURM under $dir.
ClusterName=lsqt
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$cport
SlurmdPort=$dport
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$msock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
PlugStackConfig=$dir/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
# Keep finished jobs visible to scontrol show job for 5 minutes.
MinJobAge=300
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF=$conf
  # -D: in the foreground, so $! is the daemon (stop kills it by that PID); -i: ignore state
  # a previous start left in DIR; -f names the configuration (also how stop recognises it).
  spawn slurmctld slurmctld -D -i -f "$conf"
  spawn slurmd slurmd -D -f "$conf"

  # Up when the controller answers and the node is idle.
  local state=""
  for ((i = 0; i < 300; i++)); do
    our_pid slurmctld >/dev/null || fail "slurmctld exited"
    our_pid slurmd >/dev/null || fail "slurmd exited"
    if timeout 5 scontrol ping >/dev/null 2>&1; then
      state=$(timeout 5 sinfo -h -n "$host" -o %T 2>/dev/null || true)
      [ "$state" = idle ] && break
    fi
    sleep 0.1
  done
  [ "$state" = idle ] || fail "node $host not idle within 30 s (state: ${state:-no answer})"
  log "up in $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }') s: node $host, $cpus CPUs, partition debug, ports $cport/$dport"
  # stdout is only the line to run, so that eval "$(bash single-node.sh start DIR)" works.
  log "use it with the line below (sbatch, squeue, bash tools/slurm/submit.sh ...); stop with"
  log "  bash $0 stop $dir   # then rm -rf $dir"
  echo "export SLURM_CONF=$conf"
}

case $cmd in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
