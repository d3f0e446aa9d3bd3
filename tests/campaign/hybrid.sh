#!/bin/bash
# Hybrid runs (issue 15): under mpirun, --threads T makes every worker rank run T realizations
# at once. 2 ranks x 2 threads (1 worker rank) and 3 ranks x 2 threads give 2 and 4 workers, all
# of which run realizations; the results equal a one-process run's; a SIGTERM mid-run saves the
# running states and the rerun (again hybrid) ends identical.
source "$(dirname "$0")/lib.sh"
reference
run_expect 0 hy mpirun -np 2 "$EXE" run "$MINI" --store "$WORK/h.h5" --progress-interval 0 --threads 2
expect_in hy.err "1 worker rank(s) x 2 threads = 2 workers"
digest "$WORK/h.h5" h.digest
same_digests "$WORK/ref.digest" h.digest
"$PY" - "$WORK/h.h5" 2 <<'PY' || fail "workers of the hybrid run"
import h5py, sys
with h5py.File(sys.argv[1], "r") as f:
    n = int(sys.argv[2])
    assert f["runs/workers"][-1] == n, f["runs/workers"][:]
    ranks = set(int(r) for r in f["realizations/rank"][:])
    assert ranks == set(range(1, n + 1)), ranks
PY

STORE=$WORK/s.h5
# The run stops itself (SIGSTOP, lib.sh's freeze_at_stop) once 2 results are durable (with the
# batch they came in: 2 to 5 stored), and 4 workers have at most 4 more handed out, so at least
# 3 of the 12 are not, however loaded the machine. SIGTERM then reaches every process frozen in
# that state.
start_job env HOPPER_STORE_STOP=result:2 \
    mpirun -np 3 "$EXE" run "$MINI" --store "$STORE" --progress-interval 0 --threads 2
freeze_at_stop "$STORE" "s['done'] >= 2 and s['pending'] - len(s['running']) >= 2" \
    "2 realizations stored, 2 not handed out"
kill -TERM $FROZEN
thaw_job
wait "$JOB"
rc=$?
[ $rc -eq 4 ] || { cat job.err >&2; fail "SIGTERM: exit $rc, expected 4"; }
expect_in job.err "2 worker rank(s) x 2 threads = 4 workers"
run_expect 0 rerun mpirun -np 3 "$EXE" run "$MINI" --store "$STORE" --progress-interval 0 --threads 2
digest "$STORE" s.digest
same_digests "$WORK/ref.digest" s.digest
"$PY" - "$STORE" 4 <<'PY' || fail "workers of the 3-rank hybrid run"
import h5py, sys
with h5py.File(sys.argv[1], "r") as f:
    assert f["runs/workers"][-1] == int(sys.argv[2]), f["runs/workers"][:]
PY
echo "hybrid.sh: passed"
