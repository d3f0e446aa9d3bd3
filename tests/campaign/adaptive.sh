#!/bin/bash
# Issue 13: a campaign that stops when good enough (data/mini_adaptive.toml) runs the same set of
# realizations, bit for bit, with 1 or 3 worker threads, under mpirun at 3 ranks (argument "mpi")
# and after being stopped mid-way and resumed (argument "resume"); it reports per point why it
# stopped.
source "$(dirname "$0")/lib.sh"
SWEEP=$DATA/mini_adaptive.toml
run_expect 0 one "$EXE" run "$SWEEP" --store "$WORK/one.h5" --progress-interval 0
expect_in one.err "campaign: target tau: no point needs more after round"
expect_in one.err "target met: relative 95 % half-width"
digest "$WORK/one.h5" one.digest
n=$(wc -l <one.digest)
[ "$n" -gt 6 ] && [ "$n" -le 12 ] || fail "$n realizations: the rounds should stop between 7 and 12"
expect_in one.err "max_realizations = 4 reached"
# status counts what the rounds still need, not max_realizations per point: a finished target
# campaign has nothing pending (the batch script resubmits while something is).
run_expect 0 status "$EXE" status "$WORK/one.h5" --json
grep -q '"pending": 0' status.out || fail "status of a finished target campaign shows pending realizations: $(grep -o '"pending": [0-9]*' status.out | head -1)"
run_expect 0 status_text "$EXE" status "$WORK/one.h5"
expect_in status_text.out "target met: no point needs more after round"

if [ "${1:-}" = mpi ]; then
    run_expect 0 mpi mpirun -np 3 "$EXE" run "$SWEEP" --store "$WORK/mpi.h5" --progress-interval 0
    digest "$WORK/mpi.h5" mpi.digest
    same_digests one.digest mpi.digest
    echo "ok: the same $n realizations under mpirun -np 3"
    exit 0
fi

if [ "${1:-}" != resume ]; then
    run_expect 0 three "$EXE" run "$SWEEP" --store "$WORK/three.h5" --threads 3 --progress-interval 0
    digest "$WORK/three.h5" three.digest
    same_digests one.digest three.digest
    echo "ok: the same $n realizations with 1 and 3 workers"
    exit 0
fi

# Stopped after a few realizations (SIGINT: drain), then resumed, twice.
for cut in 3 7; do
    rm -f "$WORK/cut.h5"*
    start_job "$EXE" run "$SWEEP" --store "$WORK/cut.h5" --threads 2 --progress-interval 0
    # No race to lose: the drain may come at any later moment (even after the run's end on a
    # very fast machine, 12 realizations of about 0.15 s); the resumed store must equal anyway.
    wait_stored "$WORK/cut.h5" "$cut"
    kill_job INT
    run_expect 0 resume$cut "$EXE" run "$SWEEP" --store "$WORK/cut.h5" --progress-interval 0
    digest "$WORK/cut.h5" cut$cut.digest
    same_digests one.digest cut$cut.digest
done
echo "ok: the same $n realizations after interruptions"
