#!/usr/bin/env bash
# Tears down the single-node cluster of slurm-up.sh: cancels every job, waits for them, kills
# job processes Slurm still lists, then stops slurmd, slurmctld and munged — each only if
# slurm-up.sh started it (its record in /tmp/slurm-local). Safe to run twice or on failure.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/slurm-lib.sh"

if ours_alive slurmctld; then
    jobs=$(squeue -h -o %A 2>/dev/null | tr '\n' ' ')
    if [ -n "${jobs// /}" ]; then
        # shellcheck disable=SC2086
        scancel $jobs 2>/dev/null
        for _ in $(seq 1 150); do  # KillWait (10 s) + margin
            [ -z "$(squeue -h -o %A 2>/dev/null)" ] && break
            sleep 0.1
        done
    fi
fi
if ours_alive slurmd; then
    # slurmstepd and its job processes are detached from slurmd: kill what is left.
    left=$(scontrol listpids 2>/dev/null | awk 'NR > 1 && $1 ~ /^[0-9]+$/ {print $1}')
    [ -n "$left" ] && kill -KILL $left 2>/dev/null
fi
stop_ours slurmd /run/slurmd.pid
stop_ours slurmctld /run/slurmctld.pid
stop_ours munged /run/munge/munged.pid
log "down"
exit 0
