#!/bin/bash
# The drain path, fast: `scancel -b -s USR1` delivers the template's pre-limit signal at once.
# Allocation 1 drains (nothing interrupted, exit 4) and resubmits itself; allocation 2 is
# signalled the same way and stops at the cap (--max-resubmits 1). Checks the log and the store's
# record of both allocations. Then `campaign submit` again resumes, and a plain `scancel` (SIGTERM
# with time left) stops the chain instead of resubmitting.
source "$(dirname "$0")/lib.sh"
JOB_NAME=hopper-test-drain
cluster_up
STORE=$WORK/drain.h5
LOG=$STORE.slurm.log
# No race with the campaign's end: each allocation is signalled once it stored 5 more of
# tiny.toml's 405 realizations (70-80 s of work), so it always has pending ones to drain.
job1=$(submit_tiny submit.out --time 10 --signal-lead 60 --grace 20 --max-resubmits 1) || exit 1
wait_stored "$STORE" 5
scancel -b -s USR1 "$job1" || fail "scancel -b -s USR1 $job1"
wait_log "$LOG" "^hopper-slurm: .* job [0-9]+ allocation 2: start on" "allocation 2 starting"
job2=$(job_of "$LOG" 2)
[ -n "$job2" ] || fail "allocation 2 never started"
before=$("$EXE" status "$STORE" --json | sed -n 's/^  "done": \([0-9]*\).*/\1/p')
wait_stored "$STORE" $((before + 5))
scancel -b -s USR1 "$job2" || fail "scancel -b -s USR1 $job2"
wait_chain "$LOG" 120

grep -q "allocation 1: got SIGUSR1" "$LOG" || fail "allocation 1 got no SIGUSR1"
grep -q "allocation 2: got SIGUSR1" "$LOG" || fail "allocation 2 got no SIGUSR1"
[ "$(grep -c "stopped by SIGUSR1" "$LOG")" -eq 2 ] || fail "expected two drains"
[ "$(grep "stopped by SIGUSR1" "$LOG" | grep -cvF "(0 interrupted)")" -eq 0 ] ||
    fail "a drain interrupted a running realization"
grep -q "allocation 1: resubmitted as job $job2 (allocation 2 of at most 2)" "$LOG" ||
    fail "allocation 1 did not resubmit"
grep -q "allocation 2: not resubmitting: the cap of 1 resubmission(s) is reached" "$LOG" ||
    fail "allocation 2 did not stop at the cap"

# `campaign submit` again resumes; a plain scancel (SIGTERM, time left) stops without resubmitting.
job3=$(submit_tiny submit3.out --time 10 --signal-lead 60 --grace 20 --max-resubmits 5) || exit 1
before=$("$EXE" status "$STORE" --json | sed -n 's/^  "done": \([0-9]*\).*/\1/p')
wait_stored "$STORE" $((before + 5))
scancel "$job3" || fail "scancel $job3"
wait_chain "$LOG" 120 2
grep -q "job $job3 allocation 1: not resubmitting: cancelled (SIGTERM with" "$LOG" ||
    fail "a cancelled job went on"

[ "$(grep -c "campaign run exited 4 after" "$LOG")" -eq 3 ] || fail "expected three runs ending with exit 4"
"$EXE" status "$STORE" --json >status.json || fail "campaign status"
/usr/bin/python3 - status.json <<'PY' || fail "the store's record of the allocations"
import json, sys
s = json.load(open(sys.argv[1]))
assert not s["active"] and s["hdf5_in_step"], s
assert [r["end_reason"] for r in s["runs"]] == ["interrupted by SIGUSR1"] * 2 + ["interrupted by SIGTERM"], s["runs"]
assert 0 < s["done"] < s["total"] and s["failed"] == 0, s
assert s["done"] == sum(r["stored"] for r in s["runs"]), s
PY
intervals "$LOG"
echo "ok: drain test took $(elapsed) s"
