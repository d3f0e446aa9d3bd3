# Helpers of the Slurm tests (sourced). The caller sets EXE (campaign), DIGEST (store_digest),
# SRC (source tree), WORK (scratch directory, emptied here). Brings the single-node cluster up
# (installing slurm-wlm and munge if missing) and tears it down on exit, also on failure, unless
# it was already up before the test (then it is left as it was).
set -u
SLURM_DIR=$SRC/slurm
TINY=$SRC/tests/slurm/data/tiny.toml
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK" || exit 1
T0=$(date +%s.%N)

fail() {
    echo "FAIL: $*" >&2
    exit 1
}
elapsed() { awk -v a="$T0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }

cluster_up() {
    if [ "$(id -u)" -ne 0 ] && [ ! -f /tmp/slurm-local/slurmctld.pid ]; then
        echo "SKIP: the local Slurm cluster needs root (slurm/slurm-up.sh)"
        exit 77
    fi
    if [ -f /tmp/slurm-local/slurmctld.pid ] && [ -f /tmp/slurm-local/slurmd.pid ]; then
        OWN_CLUSTER=0
    else
        OWN_CLUSTER=1
    fi
    trap cleanup EXIT
    bash "$SLURM_DIR/slurm-up.sh" || fail "slurm-up.sh failed"
    CLUSTER_UP=1
    echo "cluster up at $(elapsed) s"
}
cleanup() {
    local rc=$?
    # Our jobs go first, whoever owns the cluster.
    [ -n "${JOB_NAME:-}" ] && [ "${CLUSTER_UP:-0}" = 1 ] && timeout 20 scancel -n "$JOB_NAME" 2>/dev/null
    if [ "$rc" -ne 0 ]; then
        for f in "$WORK"/*.slurm.log; do [ -f "$f" ] && { echo "--- $f" >&2; cat "$f" >&2; }; done
    fi
    [ "${OWN_CLUSTER:-0}" = 1 ] && bash "$SLURM_DIR/slurm-down.sh"
    exit "$rc"
}

# Waits are for conditions (a log line, realizations stored, a chain's end), each with a bound
# against a hang that a loaded machine does not reach; the bounds are seconds of the clock
# (SECONDS), not counts of polls whose length varies with the load.

# wait_chain LOG SECONDS [N]: waits until N (default 1) job chains logging to LOG have ended (a
# line saying the campaign is complete or that it does not resubmit) and no job of JOB_NAME is left.
wait_chain() {
    local n t_end=$((SECONDS + $2))
    while [ "$SECONDS" -lt "$t_end" ]; do
        n=$(grep -cE "campaign complete|not resubmitting|resubmission failed" "$1" 2>/dev/null)
        if [ "${n:-0}" -ge "${3:-1}" ] &&
            [ -z "$(squeue -h -n "$JOB_NAME" 2>/dev/null)" ]; then
            return 0
        fi
        sleep 0.1
    done
    fail "the job chain did not end within $2 s"
}

# wait_stored STORE N: waits (120 s; a few seconds on a quiet machine) until the store holds at
# least N realizations.
wait_stored() {
    local n t_end=$((SECONDS + 120))
    while [ "$SECONDS" -lt "$t_end" ]; do
        n=$("$EXE" status "$1" --json 2>/dev/null | sed -n 's/^  "done": \([0-9]*\).*/\1/p')
        [ -n "$n" ] && [ "$n" -ge "$2" ] && return 0
        sleep 0.1
    done
    fail "the store never held $2 realizations (120 s)"
}

# wait_log LOG PATTERN WHAT: waits (120 s) until LOG has a line matching the regular expression.
wait_log() {
    local t_end=$((SECONDS + 120))
    until grep -qE "$2" "$1" 2>/dev/null; do
        [ "$SECONDS" -lt "$t_end" ] || fail "$3: not within 120 s"
        sleep 0.02
    done
}

# submit_tiny OUT ARGS...: `campaign submit` of tiny.toml into $STORE as $JOB_NAME with ARGS, its
# output in OUT; prints the job id.
submit_tiny() {
    local out=$1 id
    shift
    "$EXE" submit "$TINY" --store "$STORE" --job-name "$JOB_NAME" "$@" >"$out" ||
        fail "campaign submit failed"
    cat "$out" >&2
    id=$(sed -n 's/^submitted job \([0-9]*\) .*/\1/p' "$out")
    [ -n "$id" ] || fail "no job id in: $(cat "$out")"
    echo "$id"
}

# job_of LOG ALLOCATION: the job id of an allocation, from the log's start line.
job_of() {
    sed -n "s/^hopper-slurm: [^ ]* job \([0-9]*\) allocation $2: start on.*/\1/p" "$1" | head -n 1
}

# intervals LOG: per interruption, seconds from the signal to the campaign's exit and from the
# exit to the next allocation's start (parsed from the log's timestamps).
intervals() {
    awk '
    function t(s,  a) { split(substr(s, 12, 12), a, ":"); return a[1] * 3600 + a[2] * 60 + a[3] }
    /^hopper-slurm: .* got SIG/ && !sig { sig = t($2); name = $8; sub(",", "", name) }
    /^hopper-slurm: .* campaign run exited/ {
        ex = t($2)
        if (sig) { printf "interruption by %s: signal -> exit %.2f s", name, ex - sig; open = 1 }
        sig = 0
    }
    /^hopper-slurm: .* resubmitted as job/ { resub = open }
    /^hopper-slurm: .* (not resubmitting|resubmission failed)/ { if (open) printf " (not resubmitted)\n"; open = 0 }
    /^hopper-slurm: .* start on/ {
        if (open && resub) printf ", exit -> next allocation started %.2f s\n", t($2) - ex
        open = resub = 0
    }
    END { if (open) printf "\n" }' "$1"
}

# Killing ranks of a job as a node loss does, and following its chain (node_lost.sh, dead_run.sh).
# rank_of PID: the process's MPI rank (Open MPI's variable under mpirun, PMIx's under srun).
rank_of() {
    tr '\0' '\n' <"/proc/$1/environ" 2>/dev/null |
        sed -n 's/^OMPI_COMM_WORLD_RANK=//p; s/^PMIX_RANK=//p' | head -n 1
}
# kill_ranks JOB RANK...: SIGKILL to the campaign processes of those ranks of the job, at once.
kill_ranks() {
    local job=$1 p r victims=""
    shift
    for p in $(scontrol listpids "$job" 2>/dev/null | awk 'NR > 1 { print $1 }'); do
        [ "$(cat /proc/"$p"/comm 2>/dev/null)" = campaign ] || continue
        r=$(rank_of "$p")
        for want in "$@"; do [ "$r" = "$want" ] && victims="$victims $p"; done
    done
    [ "$(echo $victims | wc -w)" -eq $# ] ||
        fail "job $job: ranks $* are processes '$victims' (expected one each)"
    kill -KILL $victims
    echo "killed ranks $* of job $job (pids$victims)" >&2
}
# next_job ALLOCATION (LOG: the chain's log): waits for that allocation's start line; prints its job id.
next_job() {
    local id t_end=$((SECONDS + 180))
    until id=$(job_of "$LOG" "$1") && [ -n "$id" ]; do
        [ "$SECONDS" -lt "$t_end" ] &&
            ! grep -qE "allocation $(($1 - 1)): (not resubmitting|resubmission failed)" "$LOG" ||
            { cat "$LOG" >&2; fail "allocation $1 never started: the chain ended"; }
        sleep 0.1
    done
    echo "$id"
}
