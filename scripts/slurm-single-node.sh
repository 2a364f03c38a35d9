#!/bin/bash
# A single-node Slurm cluster on this machine (Debian's slurm-wlm and munge, as root), to try
# scripts/atlasmesh-array.sbatch for real; .ci/run starts one for the array-job test in
# tests/it/batch.rs and stops it when it ends, passed or failed.
#
#   scripts/slurm-single-node.sh start  [DIR]  a fresh cluster; prints the SLURM_CONF to export
#   scripts/slurm-single-node.sh stop   [DIR]  every job cancelled, every daemon of it ended
#   scripts/slurm-single-node.sh status [DIR]  what of it runs; exit 0 when it answers
#
# DIR (default /tmp/atlasmesh-slurm) holds the configuration, the state, the spool, the pid
# files and the logs. `start` stops whatever an earlier run of DIR left (a killed run too) and
# starts from an empty state folder (`slurmctld -c`): no job, node state or reservation of an
# earlier run comes back. `stop` cancels every job, shuts the controller and the node daemon
# down, ends their step daemons and the tasks under them, and the munged that `start` started
# (never one that was already running), each by pid; the logs stay in DIR/log.
set -euo pipefail
CMD=${1:-}
DIR=${2:-/tmp/atlasmesh-slurm}
case "$CMD" in
start | stop | status) ;;
*)
    echo "usage: $0 start|stop|status [DIR]" >&2
    exit 2
    ;;
esac
mkdir -p "$DIR"
DIR=$(cd "$DIR" && pwd)
export SLURM_CONF="$DIR/slurm.conf"

# Whether the process $1 runs (a zombie, ended but not yet reaped, does not).
alive() {
    [ -e "/proc/$1" ] && ! grep -q '^State:.*Z' "/proc/$1/status" 2>/dev/null
}

# The pid in the file $1 when that process runs and is the program $2.
pid_from() {
    local p
    p=$(cat "$1" 2>/dev/null) || return 1
    [ -n "$p" ] && alive "$p" && [ "$(cat "/proc/$p/comm" 2>/dev/null)" = "$2" ] && echo "$p"
}

# The step daemons of this cluster: slurmstepd processes holding a file of DIR open (the node
# daemon's log, which they write to, or its spool).
step_daemons() {
    local p
    for p in $(pgrep -x slurmstepd 2>/dev/null); do
        if alive "$p" && ls -l "/proc/$p/fd" 2>/dev/null | grep -qF -- "$DIR/"; then echo "$p"; fi
    done
}

# Every descendant of the processes $@ (children first found, then theirs).
descendants() {
    local table kids p
    table=$(ps -eo pid=,ppid=)
    kids="$*"
    while [ -n "$kids" ]; do
        local next=""
        for p in $kids; do
            next="$next $(awk -v pp="$p" '$2 == pp {print $1}' <<<"$table")"
        done
        next=$(echo $next)
        [ -n "$next" ] && echo "$next"
        kids=$next
    done
}

# Waits up to $1 seconds for the processes $2... to end.
wait_gone() {
    local t=$1 p running
    shift
    for _ in $(seq $((t * 10))); do
        running=""
        for p in "$@"; do
            if alive "$p"; then running=1; fi
        done
        [ -z "$running" ] && return 0
        sleep 0.1
    done
    return 1
}

ctld() { pid_from "$DIR/slurmctld.pid" slurmctld; }
slurmd_pid() { pid_from "$DIR/slurmd.pid" slurmd; }
munged_pid() { pid_from "$DIR/munged.pid" munged; }

stop() {
    local c d steps tree all
    c=$(ctld || true)
    d=$(slurmd_pid || true)
    if [ -n "$c" ]; then
        # Every job cancelled, then the controller and the node daemon shut down in order.
        local jobs
        jobs=$(timeout 20 squeue -h -o %A 2>/dev/null || true)
        if [ -n "$jobs" ]; then
            timeout 20 scancel --quiet $jobs 2>/dev/null || true
            for _ in $(seq 100); do
                [ -z "$(timeout 10 squeue -h -o %A 2>/dev/null || true)" ] && break
                sleep 0.2
            done
        fi
        timeout 20 scontrol shutdown >/dev/null 2>&1 || true
    fi
    steps=$(step_daemons)
    tree=""
    [ -n "$steps" ] && tree=$(descendants $steps)
    all=$(echo $c $d $steps $tree)
    if [ -n "$all" ]; then
        wait_gone 10 $all || {
            kill -TERM $all 2>/dev/null || true
            wait_gone 5 $all || kill -KILL $all 2>/dev/null || true
            wait_gone 5 $all || true
        }
    fi
    local m
    m=$(munged_pid || true)
    if [ -n "$m" ]; then
        kill -TERM "$m" 2>/dev/null || true
        wait_gone 5 "$m" || kill -KILL "$m" 2>/dev/null || true
    fi
    rm -f "$DIR/slurmctld.pid" "$DIR/slurmd.pid" "$DIR/munged.pid"
    [ -n "$all$m" ] && echo "stopped: $all${m:+ munged $m}" >&2
    return 0
}

status() {
    local c d m steps up=1
    c=$(ctld || true)
    d=$(slurmd_pid || true)
    m=$(munged_pid || true)
    steps=$(echo $(step_daemons))
    echo "slurmctld: ${c:-not running}"
    echo "slurmd: ${d:-not running}"
    echo "munged started here: ${m:-none}"
    echo "step daemons: ${steps:-none}"
    if [ -n "$c" ] && timeout 10 sinfo -h -o "%N %T" >/dev/null 2>&1; then
        echo "node: $(timeout 10 sinfo -h -o '%N %T')"
        echo "jobs: $(timeout 10 squeue -h -o '%A:%T' | tr '\n' ' ')"
        up=0
    fi
    return $up
}

start() {
    stop
    # Daemons of another cluster hold the ports: refused rather than killed.
    local other p
    other=""
    for p in $(pgrep -x slurmctld) $(pgrep -x slurmd); do
        if alive "$p"; then other="$other $p"; fi
    done
    if [ -n "$other" ]; then
        echo "Slurm daemons not started from $DIR run (pids $other): stop them first" >&2
        exit 1
    fi
    rm -rf "$DIR/state" "$DIR/spool"
    mkdir -p "$DIR"/{state,spool,log}
    local host node
    host=$(hostname -s)
    # The node line as slurmd sees this machine (CPUs, sockets, cores, RealMemory).
    node=$(slurmd -C | head -1)
    cat >"$SLURM_CONF" <<CONF
ClusterName=atlasmesh
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
$node State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=60 State=UP
CONF
    if ! timeout 10 munge -n >/dev/null 2>&1; then
        test -f /etc/munge/munge.key || mungekey --create
        chown munge:munge /etc/munge/munge.key
        chmod 400 /etc/munge/munge.key
        mkdir -p /run/munge && chown munge:munge /run/munge
        su -s /bin/sh munge -c munged
        cp /run/munge/munged.pid "$DIR/munged.pid"
    fi
    slurmctld -c -f "$SLURM_CONF"
    slurmd -c -f "$SLURM_CONF"
    for _ in $(seq 60); do
        if timeout 10 sinfo -h -o %T 2>/dev/null | grep -qx idle; then
            echo "$SLURM_CONF"
            return 0
        fi
        sleep 0.5
    done
    echo "slurm did not come up; see $DIR/log" >&2
    stop
    exit 1
}

"$CMD"
