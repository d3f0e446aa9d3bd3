#!/bin/bash
# Issue 14, item 4: a hung node. Under mpirun -np 3 (two workers), worker rank 1 is stopped with
# SIGSTOP while it runs a realization. With --worker-timeout 1 the master reports it silent
# after a second and hands its realization to the other worker; the campaign completes with
# every realization stored once and identical to an uninterrupted run.
#   1. the stopped worker is continued (SIGCONT) later: its late result is compared, not stored
#      again, and the job ends normally (exit 0);
#   2. the stopped worker never comes back: everything is stored and closed, and the master ends
#      the job with MPI_Abort instead of waiting for it in MPI_Finalize for ever (exit 0).
source "$(dirname "$0")/lib.sh"
SWEEP=$WORK/m36.toml
sed 's/^realizations = 4/realizations = 12/' "$MINI" >"$SWEEP"  # 36 tasks: the run outlasts the stop
run_expect 0 ref "$EXE" run "$SWEEP" --store "$WORK/ref.h5" --progress-interval 0
digest "$WORK/ref.h5" ref.digest
[ "$(wc -l <ref.digest)" -eq 36 ] || fail "reference has $(wc -l <ref.digest) realizations"

# rank_pid R: the pid of MPI rank R of the job.
rank_pid() {
    local p
    for p in $(pgrep -s "$JOB" -x campaign); do
        if tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$1"; then
            echo "$p"
            return
        fi
    done
}

for how in continued lost; do
    STORE=$WORK/$how.h5
    : >job.out
    : >job.err
    start_job mpirun -np 3 "$EXE" run "$SWEEP" --store "$STORE" --progress-interval 0 \
        --worker-timeout 1
    # Stopped with 34 of the 36 realizations still to store (the master cannot finish them in
    # the moment between the look and the stop). The other worker sends heartbeats every 0.25 s
    # against the limit of 1 s: only a process stopped for 4 heartbeats in a row is silent.
    wait_stored "$STORE" 2
    W=$(rank_pid 1)
    [ -n "$W" ] || fail "no rank 1 in the job"
    kill -STOP "$W"
    if [ $how = continued ]; then
        # Continued once the master has handed its realization to the other worker (the end of
        # the line that reports the silence), so that the late result meets a reassigned one.
        wait_until "the master reporting worker 1 silent and reassigning its realization" \
            grep -q "has been silent for .* handing it to another worker" job.err
        kill -CONT "$W"
    fi
    # The job must end by itself: a hang, not a slow machine, is what outlasts WAIT_BOUND.
    if ! (wait_until "the job ending" eval '! job_alive') 2>/dev/null; then
        kill -CONT "$W" 2>/dev/null
        kill_job KILL
        cat job.err >&2
        fail "$how: the job did not end within $WAIT_BOUND s"
    fi
    wait "$JOB"
    rc=$?
    cat job.err
    [ $rc -eq 0 ] || { cat job.err >&2; fail "$how: exit $rc, expected 0"; }
    expect_in job.err "worker 1 has been silent for"
    expect_in job.err "handing it to another worker"
    expect_in job.err "finished: all 36 realizations are in"
    [ $how = lost ] && expect_in job.err "worker(s) still silent; ending the MPI job without them"
    digest "$STORE" $how.digest
    same_digests ref.digest $how.digest
done
echo "ok"
