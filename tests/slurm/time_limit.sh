#!/bin/bash
# The whole path on a real time limit: tiny.toml (70-80 s of work for one worker) is submitted
# with --time 1 (one minute) and --signal-lead 30, so that the first allocation must be stopped by
# Slurm (the pre-limit SIGUSR1, or the SIGTERM at the limit) or by its own deadline (submit's
# default --deadline slurm-(LEAD-GRACE) stops running realizations exactly when the SIGUSR1 is
# due, so either may come first) and resubmit itself, until the
# campaign is complete. The store must then equal an uninterrupted run's, realization by
# realization (the reference runs meanwhile, outside Slurm, on the other core).
# This test runs against Slurm's clock by design, so it has margins rather than conditions: an
# allocation runs realizations for about 35 s (60 s less the 25 s the deadline keeps, less the
# start), so the 70-80 s of work take 3 allocations here; a machine over twice as fast would
# finish in one and fail the "at least 2" check below (then raise tiny.toml's realizations). A
# slower or loaded machine takes more allocations (up to 16): the chain's bound, 540 s, is 9 of
# them, and the test's limit (600 s) is above it.
source "$(dirname "$0")/lib.sh"
JOB_NAME=hopper-test-limit
cluster_up
STORE=$WORK/limit.h5
LOG=$STORE.slurm.log

"$EXE" run "$TINY" --store "$WORK/ref.h5" --progress-interval 0 >ref.out 2>ref.err &
REF=$!
"$EXE" submit "$TINY" --store "$STORE" --time 1 --signal-lead 30 --grace 5 --max-resubmits 15 \
    --ntasks 2 --job-name "$JOB_NAME" >submit.out || fail "campaign submit failed"
cat submit.out
submitted=$(elapsed)
wait_chain "$LOG" 540
done_at=$(elapsed)
wait "$REF" || { cat ref.err >&2; fail "the reference run failed"; }

grep -q "campaign complete after" "$LOG" || fail "the campaign did not complete"
allocations=$(grep -c "start on" "$LOG")
resubmits=$(grep -c "resubmitted as job" "$LOG")
[ "$allocations" -ge 2 ] && [ "$resubmits" -eq $((allocations - 1)) ] ||
    fail "$allocations allocation(s), $resubmits resubmission(s): expected at least one of each (one allocation: the work fit in it, a machine too fast for tiny.toml's 70-80 s)"
"$DIGEST" "$WORK/ref.h5" >ref.digest || fail "store_digest ref.h5"
"$DIGEST" "$STORE" >limit.digest || fail "store_digest limit.h5"
[ "$(wc -l <ref.digest)" -eq 405 ] || fail "the reference has $(wc -l <ref.digest) realizations"
cmp -s ref.digest limit.digest || { diff ref.digest limit.digest | head >&2; fail "digests differ"; }
"$EXE" status "$STORE" --json >status.json || fail "campaign status"
/usr/bin/python3 - status.json "$allocations" <<'PY' || fail "the store's record of the allocations"
import json, sys
s = json.load(open(sys.argv[1]))
n = int(sys.argv[2])
assert s["done"] == s["total"] == 405 and s["pending"] == 0, s
runs = s["runs"]
assert len(runs) == n, (len(runs), n)
# Every allocation but the last was stopped: by Slurm's signal, by its own deadline, or killed at
# the limit (no end recorded: None). Which one depends on when Slurm delivers its signal (it may
# come up to a minute early, even as an allocation starts); the chain must go on either way.
stops = ("interrupted by SIGUSR1", "interrupted by SIGTERM", "interrupted by the deadline", None)
assert all(r["end_reason"] in stops for r in runs[:-1]), runs
assert runs[-1]["end_reason"] == "complete" or "interrupted" not in runs[-1]["end_reason"], runs[-1]
print("runs:", [(r["end_reason"], r["stored"]) for r in runs])
PY
grep "^hopper-slurm:" "$LOG"
intervals "$LOG"
echo "ok: $allocations allocations, $resubmits resubmission(s); chain ended $(awk -v a="$submitted" -v b="$done_at" 'BEGIN{printf "%.1f", b-a}') s after submission; test took $(elapsed) s"
