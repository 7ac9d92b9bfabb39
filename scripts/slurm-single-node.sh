#!/usr/bin/env bash
# A one-node Slurm (Debian bookworm's slurm-wlm + munge) on this machine, to try `beslam bench --emit slurm`
# scripts for real (docs/benchmarks.md). Needs root; writes /etc/slurm/slurm.conf only if it is absent.
#   scripts/slurm-single-node.sh start    # installs slurm-wlm munge if missing, starts munged, slurmctld, slurmd
#   scripts/slurm-single-node.sh stop     # stops the three daemons this script started (by their pid files)
# No systemd needed: proctrack/linuxproc and task/none, so no cgroups either. One node named after
# `hostname -s`, with this machine's CPU count, in partition "local".
set -euo pipefail
case "${1:-}" in
  start)
    for p in slurm-wlm munge; do
      dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [ -n "${missing[*]:-}" ]; then
      apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
    fi
    host="$(hostname -s)"
    if [ ! -f /etc/slurm/slurm.conf ]; then
      cat > /etc/slurm/slurm.conf <<CONF
# Written by BE-SLAM scripts/slurm-single-node.sh: one node, for trying bench job arrays.
ClusterName=beslam
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
    fi
    mkdir -p /run/munge /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
    chown munge:munge /run/munge
    [ -f /etc/munge/munge.key ] || { mungekey --create && chown munge:munge /etc/munge/munge.key; }
    pgrep -x munged > /dev/null || runuser -u munge -- /usr/sbin/munged
    pgrep -x slurmctld > /dev/null || /usr/sbin/slurmctld
    sleep 2
    pgrep -x slurmd > /dev/null || /usr/sbin/slurmd
    sleep 2
    sinfo
    ;;
  stop)
    for f in /run/slurmd.pid /run/slurmctld.pid /run/munge/munged.pid; do
      [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null || true
    done
    ;;
  *) echo "usage: scripts/slurm-single-node.sh start|stop" >&2; exit 2 ;;
esac
