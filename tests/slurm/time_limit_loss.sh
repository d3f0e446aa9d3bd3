#!/bin/bash
# Work lost at real time limits, before and after issue 15 (label long; about 10 minutes).
# long.toml (12 realizations of about 10 s) is submitted three times with --time 1 (one
# minute), --signal-lead 30 and --grace 1, on 2 tasks (2 workers, the master beside them):
#   before:   --no-checkpoints --deadline none: the behaviour before issue 15 (every realization
#             still running when the drain's grace ends starts over in the next allocation);
#   deadline: --no-checkpoints: time-aware dispatch alone;
#   after:    the defaults: time-aware dispatch and checkpoints.
# All chains must complete with identical results (a realization continued from checkpoints
# equals one computed in one go). From each store: per allocation the worker seconds thrown
# away and kept (/runs) and the worker time of the realizations it stored (/realizations);
# "after" must throw nothing away, "before" must have lost some (else the comparison says
# nothing and the test fails: the limit did not cut a realization).
# Slurm's clock is the subject here, so it has margins, not conditions: a chain takes about 3
# allocations of a minute (wait_chain's 900 s is a hang's bound, 15 of them); "before" loses
# worker time when a realization runs as its allocation's grace ends: 2 workers busy with 10 s
# realizations (60 s of wall time) against allocations that run about 30 s always have one.
source "$(dirname "$0")/lib.sh"
JOB_NAME=hopper-test-loss
LONG=$SRC/tests/slurm/data/long.toml
cluster_up

chain() {  # chain NAME OPTIONS...: submits, waits for the chain to end
    local name=$1
    shift
    "$EXE" submit "$LONG" --store "$WORK/$name.h5" --time 1 --signal-lead 30 --grace 1 \
        --max-resubmits 12 --ntasks 2 --job-name "$JOB_NAME" "$@" >"$name.submit" ||
        fail "campaign submit ($name) failed"
    wait_chain "$WORK/$name.h5.slurm.log" 900
    grep -q "campaign complete after" "$WORK/$name.h5.slurm.log" ||
        fail "the $name chain did not complete"
    grep "^hopper-slurm:" "$WORK/$name.h5.slurm.log"
}
chain before --no-checkpoints --deadline none
chain deadline --no-checkpoints
chain after

"$DIGEST" "$WORK/before.h5" >before.digest || fail "store_digest before.h5"
"$DIGEST" "$WORK/after.h5" >after.digest || fail "store_digest after.h5"
[ "$(wc -l <before.digest)" -eq 12 ] || fail "before.h5 has $(wc -l <before.digest) realizations"
cmp -s before.digest after.digest || { diff before.digest after.digest >&2; fail "digests differ"; }
"$DIGEST" "$WORK/deadline.h5" >deadline.digest || fail "store_digest deadline.h5"
cmp -s before.digest deadline.digest || fail "digests of deadline.h5 differ"

/usr/bin/python3 - "$WORK/before.h5" "$WORK/deadline.h5" "$WORK/after.h5" <<'PY' || fail "worker time lost"
import sys, h5py, calendar, time

def unix(t):
    return calendar.timegm(time.strptime(t, "%Y-%m-%dT%H:%M:%SZ")) if t else None

totals = {}
for path in sys.argv[1:]:
    name = path.rsplit("/", 1)[1]
    with h5py.File(path, "r") as f:
        runs, real = f["runs"], f["realizations"]
        fin, secs = real["finished_unix"][:], real["task_seconds"][:]
        print(f"{name}: allocation  end_reason                      stored  worker-s(wall x workers)"
              "  realizations' worker-s  thrown away  kept in checkpoints")
        lost = kept = 0.0
        for i in range(runs["start_time"].shape[0]):
            a = unix(runs["start_time"].asstr()[i])
            b = unix(runs["end_time"].asstr()[i]) or a
            done = secs[(fin >= a - 1) & (fin <= b + 1)].sum()
            w = runs["wall_seconds"][i] * runs["workers"][i]
            l, k = runs["lost_worker_seconds"][i], runs["saved_worker_seconds"][i]
            lost += l
            kept += k
            print(f"{name}: {i + 1:10d}  {runs['end_reason'].asstr()[i]:30s}  "
                  f"{runs['stored'][i]:6d}  {w:24.1f}  {done:23.1f}  {l:11.1f}  {k:19.1f}")
        interruptions = sum(1 for r in runs["end_reason"].asstr()[:] if r.startswith("interrupted"))
        print(f"{name}: {interruptions} interruption(s), {lost:.1f} worker-s thrown away "
              f"({lost / max(interruptions, 1):.1f} per interruption), {kept:.1f} kept; "
              f"realizations' worker time {secs.sum():.1f} s over {len(secs)} realizations")
        totals[name] = (lost, kept, interruptions)
assert totals["after.h5"][0] == 0.0, totals
assert totals["before.h5"][0] > 0.0, ("the limit cut no realization in the before chain", totals)
assert totals["before.h5"][1] == 0.0, totals
PY
echo "ok: test took $(elapsed) s"
