#!/bin/bash
# Issue 44: a run that dies with realizations running and nothing stored yet (a worker killed
# by the kernel for memory takes the job with it, often before anything is stored) is progress
# for the chain: each realization it was running counts a death, and one that is running every
# time the job dies is set aside after --max-deaths of them. Before, such an allocation ended
# the chain ("killed ... stored nothing"), and a realization that kills its job was never set
# aside under Slurm. long.toml's realizations take 10-20 s: the workers' ranks are killed while
# the first two run (nothing stored); with --max-deaths 1, allocation 2 sets those two aside,
# runs the other 10 and ends with exit 3 naming them (the chain stops there: a person decides).
source "$(dirname "$0")/lib.sh"
JOB_NAME=hopper-test-dead-run
cluster_up
STORE=$WORK/dead.h5
LOG=$STORE.slurm.log
LONG=$SRC/tests/slurm/data/long.toml
"$EXE" submit "$LONG" --store "$STORE" --job-name "$JOB_NAME" --time 10 --ntasks 2 \
    --grace 5 --max-resubmits 3 --max-deaths 1 >submit.out || fail "campaign submit failed"
cat submit.out >&2
job1=$(sed -n 's/^submitted job \([0-9]*\) .*/\1/p' submit.out)
[ -n "$job1" ] || fail "no job id in: $(cat submit.out)"
grep -q -- "--max-deaths 1" "$STORE.sbatch" || fail "the batch script does not pass --max-deaths 1"
# Both workers running their first realization (the dispatch records say so), none stored.
t_end=$((SECONDS + 120))
until [ "$("$EXE" status "$STORE" --json 2>/dev/null | grep -oE '"running_when_died": [0-9]+' | tail -n 1 | grep -oE '[0-9]+$')" = 2 ]; do
    [ "$SECONDS" -lt "$t_end" ] || fail "the first allocation never ran two realizations"
    sleep 0.1
done
sleep 1
kill_ranks "$job1" 1 2 # the workers' node
done1=$("$EXE" status "$STORE" --json | sed -n 's/^  "done": \([0-9]*\).*/\1/p')
[ "$done1" = 0 ] || fail "allocation 1 stored $done1 realization(s) before the kill: the test needs none"
next_job 2 >/dev/null
grep -q "allocation 1: campaign run was killed by signal 9 (exit 137) with 2 realization(s) running, each counted as a death" "$LOG" ||
    { cat "$LOG" >&2; fail "allocation 1 did not go on for its deaths"; }
wait_chain "$LOG" 400
grep "^hopper-slurm:" "$LOG"
grep -q "allocation 2: not resubmitting: campaign run failed (exit 3" "$LOG" ||
    { cat "$LOG" >&2; fail "allocation 2 did not end with the two set aside (exit 3)"; }
"$EXE" status "$STORE" --json >status.json || fail "campaign status"
for want in '"done": 10' '"failed": 2' '"died": 2' '"pending": 0'; do
    grep -q "$want" status.json || { cat status.json >&2; fail "status lacks $want"; }
done
[ "$(grep -c '"reason": "set aside: the job died each of the 1 times' status.json)" -eq 2 ] ||
    { cat status.json >&2; fail "the two realizations are not set aside with the reason"; }
echo "ok: a run killed before storing anything went on for its 2 deaths; the 2 set aside, the 10 others stored; test took $(elapsed) s"
