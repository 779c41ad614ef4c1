#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for tests/batch_slurm.rs and the README's timing.
#
#   tools/slurm_local.sh start DIR   install slurm-wlm and munge (apt, when missing), write DIR/slurm.conf
#                                    (one node: this host, its cores and memory; proctrack/linuxproc,
#                                    task/none, select/cons_tres; every state and log file in DIR),
#                                    start munged (--force, its own key and socket in DIR), slurmctld
#                                    and slurmd, and wait until `sinfo` shows the node idle.
#   tools/slurm_local.sh stop DIR    stop the three daemons started for DIR (by their pid files).
#
# Use the cluster with SLURM_CONF=DIR/slurm.conf. Slurm's ports are fixed (6817, 6818): one such
# cluster runs at a time on a machine, so `start` holds an exclusive lock (/tmp/drapekit-slurm.lock,
# flock) from start to stop (or until the caller dies); a second `start` waits for it (up to 20 minutes)
# and first stops any daemon an earlier, killed caller left running.
# Needs root (it installs packages and runs slurmd, which starts jobs as their users).
set -euo pipefail

cmd=${1:-}
dir=${2:-}
if [[ -z "$cmd" || -z "$dir" ]]; then
    echo "usage: $0 start|stop DIR" >&2
    exit 2
fi
LOCK=/tmp/drapekit-slurm.lock

stop_daemons() {
    local d=$1
    for name in slurmd slurmctld munged; do
        local pidf="$d/$name.pid"
        if [[ -s "$pidf" ]]; then
            local pid
            pid=$(cat "$pidf")
            if kill -0 "$pid" 2>/dev/null; then
                kill "$pid" 2>/dev/null || true
                for _ in $(seq 1 50); do
                    kill -0 "$pid" 2>/dev/null || break
                    sleep 0.1
                done
                kill -9 "$pid" 2>/dev/null || true
            fi
            rm -f "$pidf"
        fi
    done
}

if [[ "$cmd" == stop ]]; then
    dir=$(realpath "$dir")
    stop_daemons "$dir"
    # Release the lock: the holder is the waiting process recorded at start.
    if [[ -s "$dir/lock.pid" ]]; then
        kill "$(cat "$dir/lock.pid")" 2>/dev/null || true
        rm -f "$dir/lock.pid"
    fi
    exit 0
fi
[[ "$cmd" == start ]] || { echo "unknown command $cmd" >&2; exit 2; }

if [[ $(id -u) -ne 0 ]]; then
    echo "slurm_local.sh: needs root (installs packages, runs slurmd)" >&2
    exit 3
fi
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    echo "installing slurm-wlm and munge (apt-get)..." >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q >&2
    apt-get install -y -q slurm-wlm munge >&2
fi

mkdir -p "$dir"
dir=$(realpath "$dir")
mkdir -p "$dir/spool/ctld" "$dir/spool/d" "$dir/munge"

# The lock: a background holder keeps the file locked until `stop` kills it.
exec 9>>"$LOCK"
if ! flock -w 1200 9; then
    echo "slurm_local.sh: another local cluster holds $LOCK" >&2
    exit 4
fi
# (every process left running has its output away from the caller's pipes, so a caller reading
# this script's output to the end is not kept waiting by the daemons)
# The holder lives as long as the caller (this script's parent) at most: a caller killed before
# `stop` blocks the next one for a second, not for ever.
caller=$PPID
( while kill -0 "$caller" 2>/dev/null; do sleep 1; done ) 9>&9 </dev/null >/dev/null 2>&1 &
echo $! > "$dir/lock.pid"
exec 9>&-
# Daemons of an earlier cluster whose caller was killed before `stop` hold Slurm's ports: stop
# them (their folder is recorded in OWNER).
OWNER=/tmp/drapekit-slurm.owner
if [[ -s "$OWNER" ]]; then
    old=$(cat "$OWNER")
    [[ "$old" != "$dir" && -d "$old" ]] && stop_daemons "$old"
fi
echo "$dir" > "$OWNER"

host=$(hostname -s)
cpus=$(nproc)
mem_mb=$(awk '/MemTotal/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)

# munge: our own key and socket, so a system munged (if any) is left alone.
key="$dir/munge/munge.key"
[[ -s "$key" ]] || dd if=/dev/urandom of="$key" bs=1024 count=1 status=none
chmod 700 "$dir/munge"
chmod 600 "$key"
sock="$dir/munge/munge.socket"
munged --force --key-file="$key" --socket="$sock" --pid-file="$dir/munged.pid" \
    --log-file="$dir/munged.log" --seed-file="$dir/munge/seed" </dev/null >>"$dir/daemons.out" 2>&1

cat > "$dir/slurm.conf" <<EOF
ClusterName=drapekit-local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$sock
CredType=cred/munge
StateSaveLocation=$dir/spool/ctld
SlurmdSpoolDir=$dir/spool/d
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1,bf_interval=1,sched_min_interval=100000
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
KillWait=5
Waittime=0
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MaxArraySize=100001
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$dir/slurm.conf"

cleanup_on_fail() {
    echo "slurm_local.sh: the cluster did not come up; logs in $dir:" >&2
    tail -n 20 "$dir"/slurmctld.log "$dir"/slurmd.log "$dir"/munged.log >&2 2>/dev/null || true
    "$0" stop "$dir" || true
}
trap cleanup_on_fail ERR

slurmctld -i </dev/null >>"$dir/daemons.out" 2>&1
slurmd </dev/null >>"$dir/daemons.out" 2>&1

for _ in $(seq 1 120); do
    state=$(sinfo -h -N -o '%T' 2>/dev/null | head -n 1 || true)
    if [[ "$state" == idle ]]; then
        trap - ERR
        echo "slurm up: node $host ($cpus cpus, $mem_mb MB), SLURM_CONF=$dir/slurm.conf" >&2
        exit 0
    fi
    sleep 0.5
done
echo "slurm_local.sh: node state '${state:-none}' after 60 s" >&2
false
