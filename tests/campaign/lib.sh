# Helpers for the campaign's end-to-end tests (sourced). The caller sets:
#   EXE     the campaign executable        DIGEST  the store_digest tool
#   SRC     the source tree                WORK    a scratch directory (emptied here)
#   PY      a python3 with h5py            (mpirun is taken from PATH)
set -u
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1  # more ranks than cores (the master sleeps)
export HOPPER_PLOTS=0  # no figures at the end of every small run (analysis.store checks them)
MINI=$SRC/tests/campaign/data/mini.toml
DATA=$SRC/tests/campaign/data
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK" || exit 1

fail() {
    echo "FAIL: $*" >&2
    thaw_job  # a job frozen for a look (freeze_when) must not be left stopped
    exit 1
}

# run_expect CODE LOGNAME CMD...: runs CMD, stdout+stderr to LOGNAME.out/.err, checks the code.
run_expect() {
    local want=$1 log=$2
    shift 2
    "$@" >"$log.out" 2>"$log.err"
    local rc=$?
    if [ "$rc" -ne "$want" ]; then
        echo "--- stdout" >&2; cat "$log.out" >&2; echo "--- stderr" >&2; cat "$log.err" >&2
        fail "'$*' exited $rc, expected $want"
    fi
}

# expect_in FILE TEXT: FILE contains TEXT (fixed string).
expect_in() {
    grep -qF -- "$2" "$1" || { cat "$1" >&2; fail "'$1' lacks: $2"; }
}

# digest STORE OUT: the per-realization digests (fails on duplicates or journal/HDF5 mismatch).
digest() {
    "$DIGEST" "$1" >"$2" || fail "store_digest $1 failed"
}

# same_digests A B
same_digests() {
    cmp -s "$1" "$2" || { diff "$1" "$2" >&2; fail "digests differ: $1 $2"; }
}

# The reference: mini.toml run once, uninterrupted, in one process.
reference() {
    run_expect 0 ref "$EXE" run "$MINI" --store "$WORK/ref.h5" --progress-interval 0
    digest "$WORK/ref.h5" "$WORK/ref.digest"
    [ "$(wc -l <"$WORK/ref.digest")" -eq 12 ] || fail "reference has $(wc -l <"$WORK/ref.digest") realizations"
}

# big_point_sweep OUT: mini.toml's points plus one of 400 000 disks (its arrays alone need
# ~100 MB, where a worker rank of mini.toml needs about 40): the memory faults' sweep
# (cluster_faults.sh, oom_kill.sh).
big_point_sweep() {
    cat "$MINI" - >"$1" <<'EOF'

[[points]]
D_cm = 2.6
hopper.particles = 400000
hopper.width_cm = 400.0
EOF
}

# start_job CMD...: starts CMD in a new session (so that a kill reaches mpirun and every rank);
# sets JOB to the session leader's pid.
start_job() {
    setsid "$@" >>job.out 2>>job.err &
    JOB=$!
}

# kill_job SIGNAL: sends SIGNAL to every process of the job's session, then waits for it.
kill_job() {
    local pids
    pids=$(ps -o pid= -s "$JOB" 2>/dev/null)
    [ -n "$pids" ] && kill "-$1" $pids 2>/dev/null
    wait "$JOB" 2>/dev/null
    JOB_RC=$?
}

# random_sleep MIN_MS MAX_MS
random_sleep() {
    local ms=$(($1 + RANDOM % ($2 - $1 + 1)))
    sleep "$(printf '%d.%03d' $((ms / 1000)) $((ms % 1000)))"
}

# Waiting: tests wait for what their next assertion needs (a realization stored or running, a
# line in the run's log, a file), never for a fixed time. Each wait has a generous bound against a
# hang (120 s: a loaded machine only makes a condition take longer to come, and none of these
# takes more than a few seconds on a quiet one) and fails saying what never came.
WAIT_BOUND=120

# wait_until WHAT CMD...: runs CMD every 0.05 s until it succeeds; fails naming WHAT after
# WAIT_BOUND seconds.
wait_until() {
    local what=$1 t_end=$((SECONDS + WAIT_BOUND))
    shift
    until "$@"; do
        [ "$SECONDS" -lt "$t_end" ] || fail "$what: not within $WAIT_BOUND s"
        sleep 0.05
    done
}

# status_has STORE COND: the store's status --json, as s, satisfies the Python expression COND.
status_has() {
    [ -e "$1.journal" ] && "$EXE" status "$1" --json 2>/dev/null |
        "$PY" -c "import json, sys; s = json.load(sys.stdin); sys.exit(0 if ($2) else 1)" 2>/dev/null
}

# wait_stored STORE N: waits until the store holds at least N realizations.
wait_stored() {
    wait_until "the store $1 holding $2 realizations" status_has "$1" "s['done'] >= $2"
}

# Freezing the job for a look. A condition read from status --json while the run goes on can be
# stale by the time the test acts on it (a realization seen running ends, the last one is handed
# out): on a fast machine, or one where the test's polls are slow, the signal that follows then
# meets another state than the one seen. freeze_when stops every campaign process of the job
# (SIGSTOP) and reads the status again: what it reads then holds until thaw_job, and a signal
# sent meanwhile is pending when the processes continue, before they run another step.
FROZEN=""
freeze_job() {  # SIGSTOP to every campaign process of the job (every rank under mpirun)
    FROZEN=$(pgrep -s "$JOB" -x campaign | tr '\n' ' ')
    [ -n "$FROZEN" ] || return 0
    kill -STOP $FROZEN 2>/dev/null
    wait_until "the job's processes stopping on SIGSTOP" all_stopped  # kill returns before
}
all_stopped() {  # every thread of the processes in FROZEN is stopped (or gone)
    local p f line st
    for p in $FROZEN; do
        for f in /proc/"$p"/task/*/stat; do
            line=$(cat "$f" 2>/dev/null) || continue
            st=${line##*) }
            case ${st%% *} in T | t | Z | X | "") ;; *) return 1 ;; esac
        done
    done
}
job_alive() {  # the job's process runs (a zombie, ended but not yet waited for, does not)
    local st
    st=$(ps -o stat= -p "$JOB" 2>/dev/null)
    [ -n "$st" ] && [ "${st#Z}" = "$st" ]
}
thaw_job() {  # SIGCONT to what freeze_job stopped
    [ -n "${FROZEN:-}" ] && kill -CONT $FROZEN 2>/dev/null
    FROZEN=""
}
# freeze_when STORE COND WHAT: returns with the job frozen in a state whose status satisfies
# COND (see status_has). Fails naming WHAT if the job ends first or after WAIT_BOUND seconds.
# The job advances in slices: it runs for SLICE seconds of the clock, then is frozen while the
# status is read, and so on. A state that lasts longer than one slice of the job's progress
# cannot pass unseen, however slow the looks are (a loaded machine makes `campaign status` and
# Python take longer than a whole mini.toml run: campaign.mpi_hybrid once saw the run end
# between two looks, issue 45). The job's share of the clock falls accordingly (a slice in every
# look), so what it does before the state comes takes longer, never less.
SLICE=0.05
freeze_when() {
    local t_end=$((SECONDS + WAIT_BOUND))
    while :; do
        freeze_job
        status_has "$1" "$2" && return 0
        thaw_job
        job_alive || fail "$3: the run ended first"
        [ "$SECONDS" -lt "$t_end" ] || fail "$3: not within $WAIT_BOUND s"
        sleep "$SLICE"
    done
}
# freeze_at_stop STORE COND WHAT: for a job whose run stops itself in a known state (started with
# `env HOPPER_STORE_STOP=result:<n>`: the store raises SIGSTOP once the run's n-th result is
# durable, after the batch that brought it: with several workers a batch can hold more than one
# result, so COND asks for done >= n, never == n, unless one worker runs), waits until it has, freezes the rest of the job as freeze_job does, and fails naming
# WHAT unless the status then satisfies COND. Where the state to act on is "so many stored, the
# rest not yet handed out", this is the way: that state is the run's own, not one that a look
# happened to catch, so no load can make the run end before it (freeze_when's slices bound the
# job's progress per look only as well as the loaded test shell keeps to its sleeps: on a
# 0.6 s mini.toml run under the full suite at -j2, campaign.mpi_hybrid once missed it).
freeze_at_stop() {
    wait_until "$3: the run stopping itself (HOPPER_STORE_STOP)" self_stopped
    freeze_job
    status_has "$1" "$2" || { "$EXE" status "$1" --json >&2; fail "$3: not so where the run stopped itself"; }
}
self_stopped() {  # a campaign process of the job is stopped; fails the test if the job ended
    job_alive || fail "the run ended before it stopped itself (HOPPER_STORE_STOP)"
    local p line st
    for p in $(pgrep -s "$JOB" -x campaign); do
        line=$(cat /proc/"$p"/stat 2>/dev/null) || continue
        st=${line##*) }
        [ "${st%% *}" = T ] && return 0
    done
    return 1
}
# pending_signal PID SIG: PID has SIG (a number) pending (stopped processes keep it so).
pending_signal() {
    local mask
    mask=$(awk '$1 == "ShdPnd:" || $1 == "SigPnd:" { print $2 }' "/proc/$1/status" 2>/dev/null | tr '\n' ' ')
    for m in $mask; do
        (( (16#$m >> ($2 - 1)) & 1 )) && return 0
    done
    return 1
}
