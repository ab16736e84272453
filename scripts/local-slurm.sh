#!/usr/bin/env bash
# Starts and stops a private single-node Slurm cluster on this machine, for the tests with the
# `cluster` label of make check and for users who want to try `overtake bench --slurm` on one
# machine (see docs/cluster.md).
#
#   scripts/local-slurm.sh start DIR [--owner PID]
#       DIR must be empty or not exist yet. Everything the cluster needs lives in it: its own
#       munged (munge/: key, socket, pid, log and seed files), slurm.conf, the controller's
#       state (state/), the node's spool (spool/), and the pid and log files of slurmctld and
#       slurmd. The two Slurm ports are picked free at start, so the cluster leaves alone any
#       Slurm or munge the machine already runs, and several can run at once in other folders.
#       On success it prints one line, `export SLURM_CONF=DIR/slurm.conf`, to be eval'ed; the
#       progress goes to stderr. With --owner PID, a guardian in the background stops the
#       cluster once process PID has ended, so a test that is killed leaves no daemons behind.
#   scripts/local-slurm.sh stop DIR
#       Cancels the cluster's jobs, then ends its daemons, its job steps and the guardian by
#       their pid files (SIGTERM, then SIGKILL after 10 seconds). Stopping a cluster that is
#       stopped or only half started succeeds quietly. DIR and its files are left in place.
#
# The daemons run as the user who starts the cluster. Started by root, the cluster runs the jobs
# of any user; started by another user, only that user's. A finished job stays known to
# `scontrol show job` for an hour (MinJobAge).
set -euo pipefail

self="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"

usage() {
  cat <<'EOF'
usage: scripts/local-slurm.sh start DIR [--owner PID]
       scripts/local-slurm.sh stop DIR
       scripts/local-slurm.sh --help

start  starts a single-node Slurm cluster (its own munged, slurmctld and slurmd, on free
       ports) whose files all live in DIR, which must be empty or not exist. Prints
       `export SLURM_CONF=DIR/slurm.conf` on success; progress goes to stderr. With
       --owner PID, the cluster is stopped by itself once process PID has ended.
stop   cancels the cluster's jobs and ends its processes; quiet and successful when
       nothing runs. DIR is left in place.
EOF
}

say() { echo "local-slurm: $*" >&2; }

# Whether process $1 runs (a zombie does not).
alive() {
  local stat
  stat="$(cat "/proc/$1/stat" 2>/dev/null)" || return 1
  stat="${stat##*) }"
  [ "${stat%% *}" != Z ]
}

# The start time of process $1 (field 22 of /proc/PID/stat, in clock ticks since boot), to
# tell it from a later process given the same pid.
start_time() {
  local stat fields
  stat="$(cat "/proc/$1/stat" 2>/dev/null)" || return 1
  read -r -a fields <<<"${stat##*) }"
  echo "${fields[19]}"
}

# Whether process $1 has the command name $2 and mentions $3 on its command line.
is_ours() {
  local pid="$1" name="$2" word="$3" comm args
  alive "$pid" || return 1
  comm="$(cat "/proc/$pid/comm" 2>/dev/null)" || return 1
  [ "$comm" = "$name" ] || return 1
  args="$(tr '\0' ' ' 2>/dev/null <"/proc/$pid/cmdline")" || return 1
  [[ "$args" == *"$word"* ]]
}

# The pid in file $1 when that process has the command name $2 and mentions $3 on its command
# line; nothing otherwise (no file, a process that has ended, a pid given to another process).
pid_from() {
  local file="$1" pid
  [ -f "$file" ] || return 0
  pid="$(tr -dc '0-9' 2>/dev/null <"$file")" || return 0
  [ -n "$pid" ] || return 0
  if is_ours "$pid" "$2" "$3"; then echo "$pid"; fi
}

# The descendants of the given processes, from one snapshot of the process table.
descendants() {
  ps -e -o pid= -o ppid= | awk -v roots="$*" '
    { parent[$1] = $2 }
    END {
      n = split(roots, list, " ")
      for (i = 1; i <= n; i++) { found[list[i]] = 1 }
      do {
        more = 0
        for (pid in parent) {
          if (!(pid in found) && (parent[pid] in found)) { found[pid] = 2; more = 1 }
        }
      } while (more)
      for (pid in found) { if (found[pid] == 2) print pid }
    }'
}

# SIGTERM to the given processes, then SIGKILL to those still running after 10 seconds.
end_processes() {
  local pid left i
  [ "$#" -gt 0 ] || return 0
  kill -TERM "$@" 2>/dev/null || true
  for ((i = 0; i < 50; i++)); do
    left=()
    for pid in "$@"; do
      if alive "$pid"; then left+=("$pid"); fi
    done
    [ "${#left[@]}" -gt 0 ] || return 0
    sleep 0.2
  done
  say "killing ${left[*]}, still running 10 s after SIGTERM"
  kill -KILL "${left[@]}" 2>/dev/null || true
}

# The job steps of the cluster in $1: slurmstepd processes whose environment names the
# cluster's slurm.conf (they inherit slurmd's, which starts with SLURM_CONF set).
step_daemons() {
  local dir="$1" proc pid
  for proc in /proc/[0-9]*; do
    pid="${proc#/proc/}"
    [ "$(cat "$proc/comm" 2>/dev/null)" = slurmstepd ] || continue
    if tr '\0' '\n' 2>/dev/null <"$proc/environ" | grep -qxF "SLURM_CONF=$dir/slurm.conf"; then
      echo "$pid"
    fi
  done
}

stop_cluster() {
  local dir="$1" conf ctld slurmd munged guardian ids i steps jobs daemons
  [ -d "$dir" ] || return 0
  dir="$(realpath -- "$dir")"
  conf="$dir/slurm.conf"
  guardian="$(pid_from "$dir/guardian.pid" bash " guard $dir ")"
  ctld="$(pid_from "$dir/slurmctld.pid" slurmctld "$conf")"
  slurmd="$(pid_from "$dir/slurmd.pid" slurmd "$conf")"
  munged="$(pid_from "$dir/munge/munged.pid" munged "$dir/munge/")"

  # The guardian first (unless this is the guardian, stopping the cluster): it would run this
  # again once its owner has ended.
  if [ -n "$guardian" ] && [ "$guardian" != $$ ]; then end_processes "$guardian"; fi

  # Cancel every job while the controller runs, and give the steps a few seconds to end.
  if [ -n "$ctld" ]; then
    ids="$(SLURM_CONF="$conf" timeout 10 squeue -h -o %F 2>/dev/null | sort -u)" || true
    if [ -n "$ids" ]; then
      # shellcheck disable=SC2086 # one job id a word
      SLURM_CONF="$conf" timeout 10 scancel --full $ids >/dev/null 2>&1 || true
      for ((i = 0; i < 25; i++)); do
        [ -n "$(step_daemons "$dir")" ] || break
        sleep 0.2
      done
    fi
  fi

  # Steps left over, with the processes of their jobs; then the daemons, munged last since
  # the others use it until they end.
  mapfile -t steps < <(step_daemons "$dir")
  if [ "${#steps[@]}" -gt 0 ]; then
    mapfile -t jobs < <(descendants "${steps[@]}")
    end_processes "${steps[@]}" "${jobs[@]}"
  fi
  daemons=()
  if [ -n "$slurmd" ]; then daemons+=("$slurmd"); fi
  if [ -n "$ctld" ]; then daemons+=("$ctld"); fi
  end_processes "${daemons[@]}"
  if [ -n "$munged" ]; then end_processes "$munged"; fi
}

# Runs a command (in a subshell, this replaces it) without the file descriptors above 2 the
# caller gave: a daemon holding the end of a pipe would keep a reader of that pipe waiting.
# munged keeps what it inherits.
without_inherited_fds() {
  local fd
  for fd in "/proc/$BASHPID/fd/"*; do
    fd="${fd##*/}"
    case "$fd" in
      0 | 1 | 2 | 255) ;;  # 255: bash's own, closed on exec
      *) eval "exec $fd>&-" 2>/dev/null || true ;;
    esac
  done
  exec "$@"
}

# The tails of the logs in $1, to stderr.
show_logs() {
  local dir="$1" log
  for log in "$dir/munge/munged.log" "$dir/munge/munged.out" "$dir/slurmctld.log" \
    "$dir/slurmctld.out" "$dir/slurmd.log" "$dir/slurmd.out" "$dir/guardian.log"; do
    if [ -s "$log" ]; then
      echo "--- last lines of $log" >&2
      tail -n 20 "$log" >&2
    fi
  done
}

start_cluster() {
  local dir="$1" owner="$2" owner_start="" user host ports port_ctld port_slurmd node conf
  local i state pid name cmd since socket memory

  if [ -n "$owner" ]; then
    if [[ ! "$owner" =~ ^[0-9]+$ ]] || ! alive "$owner"; then
      say "--owner $owner: no such process"
      exit 2
    fi
    owner_start="$(start_time "$owner")"
  fi
  for cmd in munged munge slurmctld slurmd sinfo python3; do
    if ! command -v "$cmd" >/dev/null; then
      say "$cmd is missing (Debian: apt-get install slurmctld slurmd slurm-client munge python3)"
      exit 1
    fi
  done

  if [ -e "$dir" ] && [ ! -d "$dir" ]; then
    say "$dir exists and is not a folder"
    exit 1
  fi
  # slurm.conf takes paths without quoting, and Unix sockets have paths of at most 107 bytes:
  # munged's socket, and slurmd's for each job step (spool/HOST_JOBID.STEPID).
  dir="$(realpath -m -- "$dir")"
  host="$(hostname -s)"
  if [[ ! "$dir" =~ ^[A-Za-z0-9._/+@-]+$ ]]; then
    say "$dir: the path may hold only letters, digits and . _ / + @ -"
    exit 1
  fi
  if [ $((${#dir} + ${#host} + 29)) -gt 107 ]; then
    say "$dir: the path is too long for the cluster's sockets (at most $((78 - ${#host})) bytes)"
    exit 1
  fi
  mkdir -p "$dir"
  if [ -n "$(ls -A "$dir")" ]; then
    say "$dir holds files already; start needs an empty or new folder"
    exit 1
  fi

  # From here on, a failure (or being interrupted) stops whatever has been started.
  starting="$dir"
  trap 'say "start failed"; show_logs "$starting"; stop_cluster "$starting"' EXIT
  trap 'exit 1' INT TERM HUP

  mkdir -m 700 "$dir/munge"
  mkdir "$dir/state" "$dir/spool"
  (umask 077 && head -c 1024 /dev/urandom >"$dir/munge/munge.key")
  chmod 400 "$dir/munge/munge.key"

  # --force: munged wants everyone to be able to reach its socket, which a folder of mode 700
  # does not allow; only this user's daemons and jobs use it.
  say "starting munged"
  socket="$dir/munge/munge.socket"
  if ! (without_inherited_fds munged --force --socket="$socket" \
    --key-file="$dir/munge/munge.key" --pid-file="$dir/munge/munged.pid" \
    --log-file="$dir/munge/munged.log" --seed-file="$dir/munge/munged.seed") \
    </dev/null >"$dir/munge/munged.out" 2>&1; then
    say "munged did not start"
    exit 1
  fi
  if ! munge -n -S "$socket" | unmunge -S "$socket" >/dev/null 2>&1; then
    say "munged does not answer on $socket"
    exit 1
  fi

  # Two distinct free ports, held at the same time so that they differ.
  ports="$(python3 -c '
import socket
held = [socket.socket() for _ in range(2)]
for s in held:
    s.bind(("0.0.0.0", 0))
print(*[s.getsockname()[1] for s in held])
for s in held:
    s.close()
')"
  read -r port_ctld port_slurmd <<<"$ports"

  # The node as slurmd sees it (SLURM_CONF=/dev/null: no other cluster's slurm.conf is read),
  # with at most 1000 MB of memory so that it is never drained for having less than that.
  node="$(SLURM_CONF=/dev/null slurmd -C | head -n 1)"
  if [[ ! "$node" =~ ^NodeName= ]]; then
    say "slurmd -C did not describe the node: $node"
    exit 1
  fi
  memory="$(sed -nE 's/.* RealMemory=([0-9]+).*/\1/p' <<<"$node")"
  if [ -z "$memory" ] || [ "$memory" -gt 1000 ]; then memory=1000; fi
  node="$(sed -E 's/ RealMemory=[0-9]+//' <<<"$node")"
  node="$node RealMemory=$memory NodeAddr=127.0.0.1 State=UNKNOWN"

  # slurmd runs as this user too: root can start the jobs of everyone, another user only
  # their own.
  user="$(id -un)"
  conf="$dir/slurm.conf"
  cat >"$conf" <<EOF
# A single-node cluster started by scripts/local-slurm.sh; stop it with
# scripts/local-slurm.sh stop $dir
ClusterName=overtake-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port_ctld
SlurmdPort=$port_slurmd
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
MailProg=/bin/true
MinJobAge=3600
KillWait=5
$node
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF

  export SLURM_CONF="$conf"
  say "starting slurmctld (port $port_ctld) and slurmd (port $port_slurmd)"
  if ! (without_inherited_fds slurmctld -c -f "$conf") </dev/null >"$dir/slurmctld.out" 2>&1; then
    say "slurmctld did not start"
    exit 1
  fi
  if ! (without_inherited_fds slurmd -c -f "$conf") </dev/null >"$dir/slurmd.out" 2>&1; then
    say "slurmd did not start"
    exit 1
  fi

  # Up to 30 seconds for the node to be idle; each daemon must have written its pid file
  # within 5. sinfo waits long for a controller that does not answer, hence the timeout.
  since=$SECONDS
  while :; do
    for name in slurmctld slurmd; do
      if [ -f "$dir/$name.pid" ]; then
        pid="$(tr -dc '0-9' <"$dir/$name.pid")"
        if [ -z "$pid" ] || ! alive "$pid"; then
          say "$name has ended"
          exit 1
        fi
      elif [ $((SECONDS - since)) -ge 5 ]; then
        say "$name has written no pid file"
        exit 1
      fi
    done
    state="$(timeout 5 sinfo -h -o %t 2>/dev/null)" || true
    [ "$state" != idle ] || break
    if [ $((SECONDS - since)) -ge 30 ]; then
      say "the node is not idle after 30 s (sinfo: ${state:-no answer})"
      exit 1
    fi
    sleep 0.2
  done

  if [ -n "$owner" ]; then
    # Detached from the caller: its own session, no inherited output, out of DIR.
    (cd / && without_inherited_fds setsid "$BASH" "$self" guard "$dir" "$owner" "$owner_start" \
      </dev/null >>"$dir/guardian.log" 2>&1) &
    for ((i = 0; i < 25; i++)); do
      [ -s "$dir/guardian.pid" ] && break
      sleep 0.2
    done
    if [ -z "$(pid_from "$dir/guardian.pid" bash " guard $dir ")" ]; then
      say "the guardian did not start"
      exit 1
    fi
    say "the cluster stops by itself once process $owner has ended"
  fi

  trap - EXIT INT TERM HUP
  say "up in $SECONDS s; stop it with: scripts/local-slurm.sh stop $dir"
  echo "export SLURM_CONF=$conf"
}

# The guardian: waits until the owner has ended (or its pid belongs to a newer process), then
# becomes `stop DIR` (which knows its own pid and leaves it alone).
guard() {
  local dir="$1" owner="$2" owner_start="$3"
  echo $$ >"$dir/guardian.pid"
  while alive "$owner" && [ "$(start_time "$owner" || true)" = "$owner_start" ]; do
    sleep 1
  done
  echo "$(date '+%F %T') process $owner has ended; stopping the cluster"
  exec "$BASH" "$self" stop "$dir"
}

command="${1:-}"
case "$command" in
  start)
    if [ "$#" -eq 2 ]; then
      start_cluster "$2" ""
    elif [ "$#" -eq 4 ] && [ "$3" = --owner ]; then
      start_cluster "$2" "$4"
    else
      usage >&2
      exit 2
    fi
    ;;
  stop)
    if [ "$#" -ne 2 ]; then
      usage >&2
      exit 2
    fi
    stop_cluster "$2"
    ;;
  guard)  # internal: started by `start --owner`
    [ "$#" -eq 4 ] || exit 2
    guard "$2" "$3" "$4"
    ;;
  -h | --help | help)
    usage
    ;;
  *)
    usage >&2
    exit 2
    ;;
esac
