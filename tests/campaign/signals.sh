#!/bin/bash
# Signals: SIGTERM mid-run stops at once, stores what finished, says how to resume and exits 4;
# SIGUSR1 drains; the rerun completes to the same results as an uninterrupted run. The resume
# line repeats the command's arguments.
# Usage: signals.sh NP (0 = without mpirun; under mpirun SIGUSR1 goes to mpirun, which forwards
# it to every rank, and SIGTERM to every rank directly).
NP=$1
source "$(dirname "$0")/lib.sh"
reference
STORE=$WORK/sig.h5
if [ "$NP" -eq 0 ]; then
    CMD=("$EXE" run "$MINI" --store "$STORE" --progress-interval 0 --grace 30 --threads 2)
else
    CMD=(mpirun -np "$NP" "$EXE" run "$MINI" --store "$STORE" --progress-interval 0 --grace 30)
fi

# Each signal is sent with the job frozen in the state the assertions need: something stored,
# and at least 2 realizations not yet handed out (more than the one dispatch a worker's result
# could still get before the master sees the signal), so that the run cannot end complete before
# the signal, however fast the machine or slow the test's polls. The run stops itself there
# (HOPPER_STORE_STOP=result:1: SIGSTOP once its first result is durable; lib.sh's freeze_at_stop).
NOT_HANDED_OUT="s['pending'] - len(s['running']) >= 2"

# 1. SIGTERM: stop now, once the run is under way.
start_job env HOPPER_STORE_STOP=result:1 "${CMD[@]}"
freeze_at_stop "$STORE" "s['done'] >= 1 and $NOT_HANDED_OUT" "a realization stored, 2 not handed out"
kill -TERM $FROZEN  # every rank, as Slurm does at the time limit
thaw_job
wait "$JOB"
rc=$?
[ $rc -eq 4 ] || { cat job.err >&2; fail "SIGTERM: exit $rc, expected 4"; }
expect_in job.err "SIGTERM: handing out no more tasks"
expect_in job.err "stopped by SIGTERM"
expect_in job.err "Resume with:"
# The resume line repeats the arguments given (issue 27: it dropped --threads).
if [ "$NP" -eq 0 ]; then
    expect_in job.err "  campaign run $MINI --store $STORE --progress-interval 0 --grace 30 --threads 2"
else
    expect_in job.err "  campaign run $MINI --store $STORE --progress-interval 0 --grace 30"
fi
"$EXE" status "$STORE" --json >term.json || fail "status after SIGTERM"
"$PY" - term.json <<'PY' || fail "store after SIGTERM"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["hdf5_in_step"] and not s["active"], s          # closed cleanly
assert s["runs"][-1]["end_reason"] == "interrupted by SIGTERM", s["runs"]
assert 0 < s["done"] < 12 and s["failed"] == 0, s
PY

# 2. SIGUSR1: drain (running realizations finish within the grace time).
: >job.err
before=$("$EXE" status "$STORE" --json | "$PY" -c 'import json,sys; print(json.load(sys.stdin)["done"])')
start_job env HOPPER_STORE_STOP=result:1 "${CMD[@]}"
freeze_at_stop "$STORE" "s['done'] >= $((before + 1)) and $NOT_HANDED_OUT" \
    "one more realization stored, 2 not handed out"
if [ "$NP" -eq 0 ]; then kill -USR1 "$JOB"; else kill -USR1 $(pgrep -s "$JOB" -x mpirun); fi
# mpirun forwards the signal to the (frozen) ranks: they continue once every one has it pending.
for p in $FROZEN; do wait_until "SIGUSR1 forwarded to rank process $p" pending_signal "$p" 10; done
thaw_job
wait "$JOB"
rc=$?
[ $rc -eq 4 ] || { cat job.err >&2; fail "SIGUSR1: exit $rc, expected 4"; }
expect_in job.err "SIGUSR1: handing out no more tasks"
grep -qF "(0 interrupted)" job.err || { cat job.err >&2; fail "drain interrupted a running realization"; }

# 3. The rerun completes; results equal the uninterrupted run.
run_expect 0 rerun "${CMD[@]}"
digest "$STORE" sig.digest
same_digests "$WORK/ref.digest" sig.digest

# 4. A drain that comes while the last realization runs, and which that realization outlives
# (Slurm's warning signal at the very end of an allocation), stops nothing: the run is complete
# (exit 0, end_reason "complete"), not "interrupted" with nothing to resume. One realization of
# a few seconds (ckpt.toml's first point at delta 200, 4x its steps: about 4 s here), the signal
# once it runs (sent with the job frozen while status lists it running: it cannot have ended, nor
# not yet been handed out, when the signal comes), a grace far longer than it.
if [ "$NP" -eq 0 ]; then
    sed -e 's/^realizations = .*/realizations = 1/' -e 's/^D_cm = .*/D_cm = [2.0]/' \
        -e 's/^steps_per_collision = .*/steps_per_collision = 200/' \
        "$SRC/tests/campaign/data/ckpt.toml" >"$WORK/last.toml"
    : >job.err
    start_job "$EXE" run "$WORK/last.toml" --store "$WORK/last.h5" --progress-interval 0 \
        --grace 300 --threads 1
    freeze_when "$WORK/last.h5" "len(s['running']) == 1" "the last realization running"
    kill -USR1 "$JOB"
    thaw_job
    wait "$JOB"
    rc=$?
    expect_in job.err "SIGUSR1: handing out no more tasks"
    [ $rc -eq 0 ] || { cat job.err >&2; fail "a drain the last realization outlived: exit $rc, expected 0"; }
    expect_in job.err "SIGUSR1 came after the last realization was handed out, and it finished"
    "$EXE" status "$WORK/last.h5" --json >last.json || fail "status after the late drain"
    "$PY" - last.json <<'PY' || fail "store after a drain the last realization outlived"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["done"] == s["total"] == 1 and s["pending"] == 0, s
assert s["runs"][-1]["end_reason"] == "complete", s["runs"]
PY
fi
echo "ok"
