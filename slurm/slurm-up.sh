#!/usr/bin/env bash
# Brings up a real single-node Slurm cluster on localhost (munged + slurmctld + slurmd) for the
# project's tests and for trying `campaign submit`. Debian 12, as root, without systemd.
# Idempotent: installs what is missing (apt-get update first), starts what is not running, and
# returns at once when the cluster it started is healthy. Stop it with slurm/slurm-down.sh, which
# stops only the daemons recorded here as started by this script.
#
# Environment (all optional):
#   SLURM_LOCAL_CPUS=N         advertise N CPUs instead of what `slurmd -C` detects
#   SLURM_LOCAL_CRED_EXPIRE=S  credential lifetime = requeue delay (default 10; minimum 5)
#   SLURM_LOCAL_KEEP_STATE=1   keep jobs across a restart (default: clean start, slurmctld -c)
#   SLURM_LOCAL_NO_INSTALL=1   fail instead of installing missing packages
#
# Writes /etc/slurm/slurm.conf (old copy: slurm.conf.bak), /run/munge, /run/slurm*.pid, logs in
# /var/log/slurm, and its records of what it started in /tmp/slurm-local/*.pid.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/slurm-lib.sh"
t0=$(date +%s.%N)

[ "$(id -u)" -eq 0 ] || die "must run as root (it starts munged, slurmctld and slurmd)"

# 1. Packages.
need=()
for b in /usr/sbin/slurmctld /usr/sbin/slurmd /usr/sbin/munged /usr/bin/sbatch; do
    [ -x "$b" ] || need=(slurm-wlm munge)
done
if [ ${#need[@]} -gt 0 ]; then
    [ "${SLURM_LOCAL_NO_INSTALL:-0}" = 1 ] && die "slurm-wlm/munge are not installed"
    log "installing ${need[*]} (apt-get)"
    for i in 1 2 3; do
        apt-get -o DPkg::Lock::Timeout=600 update >/dev/null && break
        [ "$i" -eq 3 ] && die "apt-get update failed"
        sleep 5
    done
    DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600 install -y \
        --no-install-recommends slurm-wlm munge >/dev/null || die "apt-get install failed"
fi
mkdir -p "$STATE" /var/log/slurm /var/lib/slurm/slurmctld /var/lib/slurm/slurmd
chown slurm:slurm /var/log/slurm /var/lib/slurm/slurmctld 2>/dev/null || true

# 2. munge: a key, its runtime directory (systemd would make it), the daemon.
if [ ! -s /etc/munge/munge.key ]; then
    mungekey --create --keyfile=/etc/munge/munge.key
    chown munge:munge /etc/munge/munge.key
    chmod 0400 /etc/munge/munge.key
fi
install -d -o munge -g munge -m 0755 /run/munge
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    runuser -u munge -- /usr/sbin/munged
    record_started munged /run/munge/munged.pid
    munge -n | unmunge >/dev/null || die "munge does not work (see /var/log/munge/munged.log)"
fi

# 3. slurm.conf from the template and this machine's hardware.
host=$(hostname -s)
node=$(/usr/sbin/slurmd -C | head -n 1)  # NodeName=<host> CPUs=2 Boards=1 ... RealMemory=...
[[ $node == NodeName=* ]] || die "slurmd -C printed no node line: $node"
extra=""
if [ -n "${SLURM_LOCAL_CPUS:-}" ]; then
    [[ $SLURM_LOCAL_CPUS =~ ^[1-9][0-9]*$ ]] || die "SLURM_LOCAL_CPUS must be a positive integer"
    mem=$(sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p' <<<"$node")
    node="NodeName=$host CPUs=$SLURM_LOCAL_CPUS RealMemory=$mem"
    extra="SlurmdParameters=config_overrides"
fi
node=$(sed "s/^NodeName=[^ ]*/NodeName=$host/" <<<"$node")
cred=${SLURM_LOCAL_CRED_EXPIRE:-10}
[[ $cred =~ ^[0-9]+$ ]] && [ "$cred" -ge 5 ] || die "SLURM_LOCAL_CRED_EXPIRE must be >= 5"
conf=$(sed -e "s/@HOST@/$host/g" -e "s/@CRED_EXPIRE@/$cred/" -e "s/@EXTRA@/$extra/" \
    -e "s/@NODELINE@/$node/" "$here/slurm.conf.in")
mkdir -p /etc/slurm
changed=0
if [ ! -f /etc/slurm/slurm.conf ] || [ "$conf" != "$(cat /etc/slurm/slurm.conf)" ]; then
    [ -f /etc/slurm/slurm.conf ] && cp /etc/slurm/slurm.conf /etc/slurm/slurm.conf.bak
    printf '%s\n' "$conf" >/etc/slurm/slurm.conf
    changed=1
fi

# 4. The daemons. Ones this script did not start are never touched.
for d in slurmctld slurmd; do
    if ours_alive "$d"; then
        if [ "$changed" = 1 ]; then
            log "slurm.conf changed: restarting $d"
            stop_ours "$d"
        fi
    else
        for pid in $(pgrep -x "$d"); do  # zombies of daemons stopped earlier do not count
            alive "$pid" "$d" && die "a $d (pid $pid) runs that slurm-up.sh did not start; stop it first"
        done
    fi
done
if ! ours_alive slurmctld; then
    rm -f /run/slurmctld.pid
    if [ "${SLURM_LOCAL_KEEP_STATE:-0}" = 1 ]; then /usr/sbin/slurmctld; else /usr/sbin/slurmctld -c; fi
    record_started slurmctld /run/slurmctld.pid
fi
if ! ours_alive slurmd; then
    rm -f /run/slurmd.pid
    /usr/sbin/slurmd -N "$host"
    record_started slurmd /run/slurmd.pid
fi

# 5. Wait for the node, then run a real job step end to end.
state=""
for _ in $(seq 1 300); do
    state=$(sinfo -h -N -n "$host" -o %t 2>/dev/null | head -n 1 || true)
    case $state in
    idle | mix | alloc) break ;;
    down* | drain* | drng*) scontrol update NodeName="$host" State=RESUME 2>/dev/null || true ;;
    esac
    sleep 0.1
done
case $state in idle | mix | alloc) ;; *) die "node $host is '$state', not idle (see /var/log/slurm)" ;; esac
ok=0
for _ in 1 2 3; do
    if timeout 60 srun -n1 true 2>/dev/null; then ok=1 && break; fi
    sleep 1  # e.g. "Job credential revoked" right after a crash and a clean restart
done
[ "$ok" = 1 ] || die "srun -n1 true failed (see /var/log/slurm/slurmd.log)"
log "cluster up on $host ($(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.1f", b-a}') s)"
