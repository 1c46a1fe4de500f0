#!/usr/bin/env bash
# A real one-node Slurm cluster on this machine for the length of one command: Debian's
# `slurmctld`, `slurmd` and `munged` (packages installed when missing), all their state in one
# temporary directory.
#
#   bash scripts/slurm-local.sh COMMAND [ARGS...]
#   e.g. bash scripts/slurm-local.sh sinfo
#        bash scripts/slurm-local.sh bash scripts/slurm-ci-crosscheck.sh target/cluster ../shared/meshes/*.obj
#
# Writes a slurm.conf for one node with this machine's CPUs and memory (as `slurmd -C` reports
# them), `select/cons_tres` with CPUs and memory consumable, one default partition `local`, and
# starts munged (a key and socket of its own), slurmctld and slurmd in the foreground as children
# of this script. Waits until the node is `idle` (at most SLURM_START_TIMEOUT seconds, default
# 60), then runs COMMAND with SLURM_CONF exported, so sbatch, squeue, scontrol and scancel talk
# to this cluster, and SLURM_LOCAL_DIR (the temporary directory; the daemons' logs are in
# $SLURM_LOCAL_DIR/log/). The exit status is COMMAND's.
#
# On exit (success, failure, or SIGINT/SIGTERM/SIGHUP) every job is cancelled, the job
# processes get SLURM_STOP_TIMEOUT seconds (default 20) to end, the daemons are stopped, any
# process still carrying this cluster's marker variable is killed by its PID, and the directory
# is removed. When the cluster fails to start, or COMMAND fails, the last lines of the daemons'
# logs are printed first. Nothing is written outside the temporary directory (TMPDIR, else
# /tmp) except by apt-get. Needs root: the packages, and slurmd runs jobs as their user.
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 COMMAND [ARGS...]" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "slurm-local: needs root (slurmd, munged, apt-get)" >&2; exit 2; }
start_timeout=${SLURM_START_TIMEOUT:-60}
stop_timeout=${SLURM_STOP_TIMEOUT:-20}

need=()
command -v munged >/dev/null 2>&1 || need+=(munge)
command -v slurmctld >/dev/null 2>&1 || need+=(slurmctld)
command -v slurmd >/dev/null 2>&1 || need+=(slurmd)
command -v sbatch >/dev/null 2>&1 || need+=(slurm-client)
if [ ${#need[@]} -gt 0 ]; then
    echo "slurm-local: installing ${need[*]}" >&2
    # Docker's policy-rc.d (when present) keeps the packages' own services from starting; ours
    # are started below with their own configuration.
    DEBIAN_FRONTEND=noninteractive apt-get update -q </dev/null >&2
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${need[@]}" \
        </dev/null >&2
fi

dir=$(mktemp -d "${TMPDIR:-/tmp}/halfray-slurm.XXXXXX")
chmod 755 "$dir" # slurmd runs a job's steps as the job's user, who needs the spool
mkdir -p "$dir"/{munge,state,spool,run,log}
chmod 700 "$dir/munge"
# Every daemon and job of this cluster inherits this variable: teardown finds leftovers by it.
marker="HALFRAY_SLURM_CLUSTER=$dir"
pids=() # munged slurmctld slurmd, in start order
cmd=""   # COMMAND

show_logs() {
    local f
    for f in "$dir"/log/*; do
        # A daemon's stderr matters when it stopped before opening its log.
        case $f in *.stderr) [ ! -s "${f%.stderr}.log" ] || continue ;; esac
        [ -s "$f" ] || continue
        echo "---- slurm-local: last lines of $f" >&2
        tail -n 40 "$f" >&2
    done
}

# The PIDs of this cluster's processes (never this script): those whose environment holds the
# marker (daemons, jobs, COMMAND) or that hold a file under the directory open (slurmstepd,
# which slurmd starts with an environment of its own, writes to the slurmd log).
cluster_pids() {
    local p f
    for p in /proc/[0-9]*; do
        p=${p#/proc/}
        [ "$p" != $$ ] || continue
        if grep -qzxF "$marker" "/proc/$p/environ" 2>/dev/null; then echo "$p"; continue; fi
        for f in /proc/"$p"/fd/*; do
            case $(readlink "$f" 2>/dev/null) in "$dir"/*) echo "$p"; break ;; esac
        done
    done
}

# Sends TERM to the PIDs after $1, waits up to $1 seconds for them to end, then sends KILL and
# waits up to 5 s more.
stop_pids() {
    local timeout=$1
    shift
    [ $# -gt 0 ] || return 0
    kill -TERM "$@" 2>/dev/null || true
    wait_gone "$timeout" "$@" && return 0
    echo "slurm-local: killing $* (still running after $timeout s)" >&2
    kill -KILL "$@" 2>/dev/null || true
    wait_gone 5 "$@" || echo "slurm-local: $* still running after SIGKILL" >&2
}

# Waits up to $1 seconds until none of the PIDs after it runs; fails if one still does.
wait_gone() {
    local deadline=$((SECONDS + $1)) p
    shift
    while :; do
        for p in "$@"; do
            # A zombie has ended: only its parent's wait is missing.
            if kill -0 "$p" 2>/dev/null && [ "$(ps -o stat= -p "$p")" != Z ]; then break; fi
            p=""
        done
        [ -n "$p" ] || return 0
        [ "$SECONDS" -lt "$deadline" ] || return 1
        sleep 0.2
    done
}

teardown() {
    local rc=$?
    trap - EXIT INT TERM HUP
    set +e
    if [ -n "$cmd" ] && kill -0 "$cmd" 2>/dev/null; then stop_pids "$stop_timeout" "$cmd"; fi
    if [ "$rc" -ne 0 ]; then show_logs; fi
    if [ ${#pids[@]} -ge 2 ] && kill -0 "${pids[1]}" 2>/dev/null; then
        # Cancel every job and give their processes time to end through slurmd.
        squeue -h -o %A 2>/dev/null | sort -u | xargs -r scancel 2>/dev/null
        local deadline=$((SECONDS + stop_timeout))
        while [ -n "$(squeue -h -o %A 2>/dev/null)" ] && [ "$SECONDS" -lt "$deadline" ]; do
            sleep 0.5
        done
    fi
    # slurmd, slurmctld, munged: the reverse of the start order.
    local i
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
        stop_pids "$stop_timeout" "${pids[i]}"
        wait "${pids[i]}" 2>/dev/null
    done
    local left
    mapfile -t left < <(cluster_pids)
    if [ ${#left[@]} -gt 0 ]; then
        # slurmstepd outlives a slurmd that died; it ignores TERM while its job runs.
        echo "slurm-local: stopping leftover processes ${left[*]}" >&2
        stop_pids 5 "${left[@]}"
    fi
    rm -rf "$dir"
    exit "$rc"
}
trap teardown EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
trap 'exit 129' HUP

# Two free TCP ports for slurmctld and slurmd (another Slurm may run here on 6817/6818).
read -r ctld_port slurmd_port < <(python3 -c '
import socket
socks = [socket.socket() for _ in range(2)]
for s in socks: s.bind(("127.0.0.1", 0))
print(*(s.getsockname()[1] for s in socks))')
host=$(hostname -s)
# `slurmd -C` prints this machine as a NodeName line (CPUs, sockets, cores, threads,
# RealMemory); keep its hardware fields under our node name.
hardware=$(slurmd -C | sed -n 's/^NodeName=[^ ]* //p')
[ -n "$hardware" ] || { echo "slurm-local: slurmd -C printed no node line" >&2; exit 1; }
cpus=$(sed -n 's/.*CPUs=\([0-9]*\).*/\1/p' <<<"$hardware")
memory=$(sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p' <<<"$hardware")
conf=$dir/slurm.conf
cat >"$conf" <<EOF
# Written by scripts/slurm-local.sh for one run; removed with $dir.
ClusterName=halfray-local
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
# cred_expire also delays a requeued job's restart (default 120 s).
AuthInfo=socket=$dir/munge/munge.socket,cred_expire=10
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/log/jobcomp.log
MpiDefault=none
MailProg=/bin/true
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
# A job that asks for no memory gets its CPUs' share, not the whole node.
DefMemPerCPU=$((memory / cpus))
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=2,bf_interval=2
ReturnToService=2
MinJobAge=3600
KillWait=5
NodeName=$host NodeAddr=127.0.0.1 $hardware State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
: >"$dir/plugstack.conf"

# munged: a fresh key (the package's /etc/munge key is not ours to read or change).
head -c 1024 /dev/urandom >"$dir/munge/munge.key"
chmod 400 "$dir/munge/munge.key"
env "$marker" munged --foreground --force --key-file="$dir/munge/munge.key" \
    --socket="$dir/munge/munge.socket" --pid-file="$dir/run/munged.pid" \
    --seed-file="$dir/munge/munged.seed" \
    >"$dir/log/munged.log" 2>&1 &
pids+=($!)
env "$marker" SLURM_CONF="$conf" slurmctld -D -i -f "$conf" >"$dir/log/slurmctld.stderr" 2>&1 &
pids+=($!)
env "$marker" SLURM_CONF="$conf" slurmd -D -f "$conf" >"$dir/log/slurmd.stderr" 2>&1 &
pids+=($!)
export SLURM_CONF=$conf SLURM_LOCAL_DIR=$dir

started=$SECONDS
deadline=$((SECONDS + start_timeout))
until [ "$(sinfo -h -n "$host" -o %T 2>/dev/null)" = idle ]; do
    for p in "${pids[@]}"; do
        kill -0 "$p" 2>/dev/null || { echo "slurm-local: a daemon exited during start-up" >&2; exit 1; }
    done
    if [ "$SECONDS" -ge "$deadline" ]; then
        echo "slurm-local: node $host not idle after ${start_timeout} s:" >&2
        sinfo -N -l >&2 || true
        scontrol show node "$host" >&2 || true
        exit 1
    fi
    sleep 0.5
done
echo "slurm-local: $(sinfo -V), node $host idle ($(sinfo -h -n "$host" -o '%c CPUs, %m MB')) after $((SECONDS - started)) s" >&2

# In the background, so that a signal reaches the trap at once rather than after COMMAND.
env "$marker" "$@" &
cmd=$!
wait "$cmd"
