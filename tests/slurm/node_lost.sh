#!/bin/bash
# Issue 44, part 3: a node lost under Slurm. Every rank of one "node" dies at once (SIGKILL, as a
# node's power or its kernel takes them): in allocation 1 the two worker ranks of a 3-rank job
# (a node of workers), in allocation 2 the master and a worker together (the master's node).
# The chain must go on after each loss (the launcher ends the job's other ranks, the batch
# script resubmits), and the completed store must equal an uninterrupted run's, realization by
# realization: nothing lost, nothing duplicated, every realization bit-identical.
# LAUNCHER (environment): srun (the default of campaign submit) or mpirun.
source "$(dirname "$0")/lib.sh"
JOB_NAME=hopper-test-node
LAUNCHER=${LAUNCHER:-srun}
cluster_up
STORE=$WORK/node.h5
LOG=$STORE.slurm.log

"$EXE" run "$TINY" --store "$WORK/ref.h5" --progress-interval 0 >ref.out 2>ref.err &
REF=$!
# A long limit (10 minutes): only the test's kills interrupt the allocations. Two tasks with the
# master's rank beside them (--master-slot shared, the default; the local cluster has 2 CPUs):
# rank 0 the master, ranks 1 and 2 the workers.
job1=$(submit_tiny submit.out --time 10 --ntasks 2 --launcher "$LAUNCHER" \
    --grace 5 --max-resubmits 4) || exit 1
wait_stored "$STORE" 5
kill_ranks "$job1" 1 2  # the workers' node
job2=$(next_job 2)
grep -q "allocation 1: campaign run was killed by signal 9 (exit 137)" "$LOG" ||
    { cat "$LOG" >&2; fail "allocation 1 did not say why it goes on"; }
before=$("$EXE" status "$STORE" --json | sed -n 's/^  "done": \([0-9]*\).*/\1/p')
wait_stored "$STORE" $((before + 5))
kill_ranks "$job2" 0 1  # the master's node
job3=$(next_job 3)
echo "allocations: $job1 $job2 $job3" >&2
wait_chain "$LOG" 480
wait "$REF" || { cat ref.err >&2; fail "the reference run failed"; }
grep -q "campaign complete after 3 allocation(s)" "$LOG" || { cat "$LOG" >&2; fail "the campaign did not complete in 3 allocations"; }
"$DIGEST" "$WORK/ref.h5" >ref.digest || fail "store_digest ref.h5"
"$DIGEST" "$STORE" >node.digest || fail "store_digest node.h5 (duplicates or journal/HDF5 mismatch)"
[ "$(wc -l <ref.digest)" -eq 405 ] || fail "the reference has $(wc -l <ref.digest) realizations"
cmp -s ref.digest node.digest || { diff ref.digest node.digest | head >&2; fail "digests differ"; }
grep "^hopper-slurm:" "$LOG"
echo "ok: two nodes lost (the workers', the master's), 3 allocations, store identical to the uninterrupted run; test took $(elapsed) s"
