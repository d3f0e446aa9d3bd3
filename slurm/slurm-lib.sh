# Helpers of slurm-up.sh and slurm-down.sh (sourced). A daemon counts as "ours" when
# $STATE/<name>.pid holds a PID that is alive (not a zombie) and whose /proc comm is <name>; that
# also guards against PID reuse.
STATE=${SLURM_LOCAL_STATE:-/tmp/slurm-local}

log() { echo "slurm-local: $*" >&2; }
die() {
    log "error: $*"
    exit 1
}

# alive PID NAME: PID runs (state not Z) and its comm is NAME.
alive() {
    local stat
    [ -n "$1" ] && [ -r "/proc/$1/stat" ] || return 1
    [ "$(cat "/proc/$1/comm" 2>/dev/null)" = "$2" ] || return 1
    stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 1
    stat=${stat##*) }
    [ "${stat%% *}" != Z ]
}

ours_alive() {
    [ -f "$STATE/$1.pid" ] && alive "$(cat "$STATE/$1.pid")" "$1"
}

# record_started NAME PIDFILE: waits (10 s) for the daemon's pidfile, checks it, records it.
record_started() {
    local pid=""
    for _ in $(seq 1 100); do
        pid=$(cat "$2" 2>/dev/null || true)
        alive "$pid" "$1" && break
        sleep 0.1
    done
    if ! alive "$pid" "$1"; then
        tail -n 20 "/var/log/slurm/$1.log" "/var/log/munge/$1.log" 2>/dev/null >&2 || true
        die "$1 did not start"
    fi
    mkdir -p "$STATE"
    echo "$pid" >"$STATE/$1.pid"
}

# stop_ours NAME [PIDFILE]: SIGTERM, 10 s, SIGKILL; then forgets it (and its pidfile if stale).
stop_ours() {
    local pid
    pid=$(cat "$STATE/$1.pid" 2>/dev/null || true)
    if alive "$pid" "$1"; then
        kill -TERM "$pid" 2>/dev/null || true
        for _ in $(seq 1 100); do
            alive "$pid" "$1" || break
            sleep 0.1
        done
        alive "$pid" "$1" && kill -KILL "$pid" 2>/dev/null || true
    fi
    # slurmctld runs as user slurm and cannot delete its own /run pidfile; a stale one makes
    # `apt-get purge slurmctld` fail. Remove it when it still names the PID we stopped.
    if [ -n "${2:-}" ] && [ -n "$pid" ] && [ "$(cat "$2" 2>/dev/null)" = "$pid" ]; then rm -f "$2"; fi
    rm -f "$STATE/$1.pid"
}
