#!/bin/bash
# Starts a single-node Slurm cluster on this machine (Debian's slurm-wlm and munge, as root),
# to try scripts/atlasmesh-array.sbatch for real; .ci/run uses it for the array-job test in tests/batch.rs.
# Prints the SLURM_CONF to export. State, spool and logs under $1 (default /tmp/atlasmesh-slurm).
set -euo pipefail
DIR=${1:-/tmp/atlasmesh-slurm}
mkdir -p "$DIR"/{state,spool,log}
HOST=$(hostname -s)
# The node line as slurmd sees this machine (CPUs, sockets, cores, RealMemory).
NODE=$(slurmd -C | head -1)
cat > "$DIR/slurm.conf" <<CONF
ClusterName=atlasmesh
SlurmctldHost=$HOST
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
$NODE State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
if ! munge -n >/dev/null 2>&1; then
    test -f /etc/munge/munge.key || mungekey --create
    chown munge:munge /etc/munge/munge.key
    chmod 400 /etc/munge/munge.key
    mkdir -p /run/munge && chown munge:munge /run/munge
    su -s /bin/sh munge -c munged
fi
export SLURM_CONF="$DIR/slurm.conf"
pkill -x slurmctld 2>/dev/null || true
pkill -x slurmd 2>/dev/null || true
sleep 1
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 30); do
    if sinfo -h -o %T 2>/dev/null | grep -qx idle; then
        echo "$SLURM_CONF"
        exit 0
    fi
    sleep 1
done
echo "slurm did not come up; see $DIR/log" >&2
exit 1
