#!/usr/bin/env bash
# Starts (start) or stops (stop) a single-node Slurm on this machine, for tests and trials: munged,
# slurmctld and slurmd on localhost with a generated slurm.conf (Debian's slurm-wlm and munge,
# run as root without systemd). `start` installs the packages if they are missing and waits until
# the node is idle; the daemons' process ids go to $STATE/pids so that `stop` ends exactly them.
set -euo pipefail
STATE=${SLURM_LOCAL_STATE:-/tmp/neumann-slurm}
case "${1:-}" in
start)
    if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
        DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm munge >/dev/null ||
            { apt-get update -q >/dev/null && DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm munge >/dev/null; }
    fi
    mkdir -p "$STATE"
    [ -f /etc/munge/munge.key ] || mungekey --create
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge /etc/munge/munge.key
    if ! pgrep -x munged >/dev/null; then
        su -s /bin/sh munge -c munged
    fi
    pgrep -x munged > "$STATE/pids"
    host=$(hostname -s)
    mkdir -p /var/spool/slurmctld /var/spool/slurmd /var/log/slurm /etc/slurm
    cat > /etc/slurm/slurm.conf <<CONF
ClusterName=local
SlurmctldHost=$host
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
ReturnToService=2
JobRequeue=1
MinJobAge=3600
SchedulerParameters=defer_batch=0
NodeName=$host CPUs=$(nproc) RealMemory=2000 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
    slurmctld -c # a fresh state: no jobs left from an earlier run
    slurmd
    for _ in $(seq 60); do
        if sinfo -h -o %t 2>/dev/null | grep -qx idle; then
            cat "$STATE/slurmctld.pid" "$STATE/slurmd.pid" >> "$STATE/pids"
            sinfo
            exit 0
        fi
        sleep 1
    done
    echo "error: the local Slurm node did not become idle; see /var/log/slurm/" >&2
    exit 1
    ;;
stop)
    if [ -f "$STATE/pids" ]; then
        # Slurm's daemons first, munged last.
        tac "$STATE/pids" | while read -r pid; do kill "$pid" 2>/dev/null || true; done
        rm -f "$STATE/pids"
    fi
    ;;
*)
    echo "usage: $0 start|stop" >&2
    exit 2
    ;;
esac
