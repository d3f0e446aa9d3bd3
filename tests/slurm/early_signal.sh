#!/bin/bash
# Issue 29, item 9: Slurm's warning SIGUSR1 may come as an allocation starts (up to a minute
# early), before the campaign is up to catch it; and a run killed at the time limit exits 137 or
# 143. Neither may end the chain while realizations are pending and the allocation stored or
# checkpointed something. Deterministic: the signals are delivered by the test at chosen moments
# (`scancel -b -s USR1` the moment the batch script starts; a SIGKILL of the campaign process once
# it stored something, as the limit's SIGKILL would), not by Slurm's clock.
source "$(dirname "$0")/lib.sh"
JOB_NAME=hopper-test-early
cluster_up
STORE=$WORK/early.h5
LOG=$STORE.slurm.log
# A long limit (10 minutes): only the test's own signals interrupt the allocations.
# The first allocation's campaign creates the store and pauses 10 s before it links the journal
# (the test hook HOPPER_STORE_PAUSE, passed on by sbatch --export=ALL; later allocations open the
# store and do not pause): the campaign is not up (the store not active) for 10 s after the
# batch script's first line, so the SIGUSR1 sent once that line is seen comes before it is up
# however slowly scancel delivers it (well under a second) on a loaded machine.
job1=$(HOPPER_STORE_PAUSE=journal_link:10000 \
    submit_tiny submit.out --time 10 --signal-lead 60 --grace 5 --max-resubmits 2) || exit 1
# 1. SIGUSR1 the moment the batch script runs (its first log line), before `campaign run` is up.
wait_log "$LOG" "job $job1 allocation 1: start on" "allocation 1 starting"
scancel -b -s USR1 "$job1" || fail "scancel -b -s USR1 $job1"
wait_log "$LOG" "allocation 1: got SIGUSR1" "allocation 1 getting the SIGUSR1"
grep -q "allocation 1: got SIGUSR1 before the campaign was up: not forwarded" "$LOG" ||
    { cat "$LOG" >&2; fail "allocation 1 forwarded a SIGUSR1 that came before the campaign was up"; }
# The allocation goes on: it stores realizations (nothing drains it).
wait_stored "$STORE" 5
# 2. The launcher and the campaign killed as at the limit (SIGKILL after the SIGTERM): the chain
# goes on.
before=$("$EXE" status "$STORE" --json | sed -n 's/^  "done": \([0-9]*\).*/\1/p')
wait_stored "$STORE" $((before + 3))
pids=$(scontrol listpids "$job1" 2>/dev/null | awk 'NR > 1 { print $1 }')
victims=""
for p in $pids; do
    case $(cat /proc/"$p"/comm 2>/dev/null) in
    campaign | srun | mpirun) victims="$victims $p" ;;  # the ranks and the launcher, not the shell
    esac
done
[ -n "$victims" ] || fail "no campaign process in job $job1"
kill -KILL $victims
t_end=$((SECONDS + 120))
until job2=$(job_of "$LOG" 2) && [ -n "$job2" ]; do
    [ "$SECONDS" -lt "$t_end" ] && ! grep -qE "allocation 1: (not resubmitting|resubmission failed)" "$LOG" ||
        { cat "$LOG" >&2; fail "allocation 2 never started: the chain ended"; }
    sleep 0.1
done
grep -q "allocation 1: campaign run was killed by signal 9 (exit 137)" "$LOG" ||
    fail "allocation 1 did not say why it goes on"
grep -q "allocation 1: resubmitted as job $job2" "$LOG" || fail "allocation 1 did not resubmit"
# Allocation 2 is left to finish the campaign (tiny.toml: about a minute of work; the bound, a
# hang's, leaves the test's 600 s room for a machine loaded several times over).
wait_chain "$LOG" 480
grep -q "campaign complete after 2 allocation(s)" "$LOG" || fail "the campaign did not complete"
grep "^hopper-slurm:" "$LOG"
echo "ok: test took $(elapsed) s"
