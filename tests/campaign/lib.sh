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

# wait_stored STORE N: waits (up to 30 s) until the store holds at least N realizations.
wait_stored() {
    local i
    for i in $(seq 1 600); do
        if [ -e "$1.journal" ] && "$EXE" status "$1" --json 2>/dev/null |
            "$PY" -c "import json,sys; sys.exit(0 if json.load(sys.stdin)['done'] >= $2 else 1)"; then
            return 0
        fi
        sleep 0.05
    done
    fail "the store never held $2 realizations"
}
