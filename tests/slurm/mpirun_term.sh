#!/bin/bash
# A SIGTERM under `campaign submit --launcher mpirun` (found by bench/soak.sh, issue 44): mpirun
# exits 1 when it is sent SIGTERM, although the campaign stops cleanly (exit 4, states saved).
# The batch script must go by how the store says the run ended, not by the launcher's code: a
# plain `scancel -b` (SIGTERM to the batch script, forwarded to mpirun, with time left) is a
# cancellation ("not resubmitting: cancelled"), not "campaign run failed (exit 1)".
source "$(dirname "$0")/lib.sh"
JOB_NAME=hopper-test-mpirun-term
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # mpirun as root (the job inherits it)
cluster_up
STORE=$WORK/term.h5
LOG=$STORE.slurm.log
job1=$(submit_tiny submit.out --time 10 --launcher mpirun --grace 5 --max-resubmits 2) || exit 1
wait_stored "$STORE" 5
scancel -b -s TERM "$job1" || fail "scancel -b -s TERM $job1"
wait_chain "$LOG" 180
grep "^hopper-slurm:" "$LOG"
grep -q "allocation 1: got SIGTERM" "$LOG" || fail "allocation 1 got no SIGTERM"
grep -q "campaign run failed" "$LOG" && fail "a clean stop by SIGTERM was taken for a failed run"
grep -q "allocation 1: the launcher exited 1, the campaign's run ended \"interrupted by SIGTERM\"" "$LOG" ||
    fail "the batch script did not read the store's end of the run"
grep -q "allocation 1: not resubmitting: cancelled (SIGTERM with" "$LOG" ||
    fail "the cancellation was not said"
"$EXE" status "$STORE" --json | grep -q '"end_reason": "interrupted by SIGTERM"' ||
    fail "the store does not record the run as interrupted by SIGTERM"
echo "ok: mpirun's exit 1 after a clean SIGTERM stop read as a cancellation; test took $(elapsed) s"
