#!/bin/bash
# Checkpoints inside a realization, end to end (issue 15): real processes, real files.
#  1. SIGTERM in the middle of realizations: each running one saves its state beside the store
#     (STORE.checkpoints/), the run exits 4 and its /runs row says the worker time was kept
#     (saved > 0, lost = 0); status lists the checkpoints.
#  2. One of those files rewritten as if by another code version (valid checksum): the rerun
#     refuses it with the reason and restarts that realization; the other continues from its
#     state. Every realization ends identical to an uninterrupted run, and the files are gone.
#  3. SIGKILL of the whole job (no chance to save at the stop) with --checkpoint-interval 0.3:
#     the periodic states let the rerun continue; results identical again (delta-200
#     realizations, long enough to be still running at the kill on a fast machine).
#  4. A checkpoint of this sweep put beside a store of other physics under the same labels is
#     refused ("other physics") and the realization restarts.
#  5. --no-checkpoints: the same SIGTERM throws the running realizations' worker time away, and
#     /runs says how much (lost > 0): the "before" of issue 15.
#  6. --deadline: before anything is measured realizations start and are stopped, states saved,
#     at the deadline minus the grace; once durations are measured, none starts that cannot end
#     in time (the run ends at once, exit 4); bad values are refused with the allowed forms.
# Usage: checkpoint.sh NP (0 = one process with 2 worker threads; else mpirun -np NP).
NP=$1
source "$(dirname "$0")/lib.sh"
SWEEP=$DATA/ckpt.toml
run_cmd() {  # run_cmd STORE [options...]: the command line for this NP
    local store=$1
    shift
    if [ "$NP" -eq 0 ]; then
        echo "$EXE" run "$SWEEP" --store "$store" --progress-interval 0 --threads 2 "$@"
    else
        echo mpirun -np "$NP" "$EXE" run "$SWEEP" --store "$store" --progress-interval 0 "$@"
    fi
}
# wait_running STORE SECONDS: returns with the job frozen (lib.sh's freeze_when: the job
# advances in slices between looks, so the state cannot pass unseen however slow the looks) once
# a realization has been running for SECONDS (status --json; its age on the master's clock, from
# the dispatch). Writes "LABEL' #R" of the longest-running one to running.txt (the form of the
# run's log lines), for the cases that check its fate. A signal sent before thaw_job (stop_all
# thaws) meets that very state.
wait_running() {
    freeze_when "$1" "s['running'] and max(t['seconds'] for t in s['running']) >= $2" \
        "a realization of $1 running for $2 s"
    "$EXE" status "$1" --json 2>/dev/null | "$PY" -c "
import json, sys
t = max(json.load(sys.stdin)['running'], key=lambda t: t['seconds'])
open('running.txt', 'w').write(\"%s' #%d\" % (t['label'], t['realization']))" ||
        fail "reading the running realization of $1"
}
stop_all() {  # SIGTERM to every campaign process of the job (as Slurm at the limit), frozen or not
    if [ "$NP" -eq 0 ]; then kill -TERM "$JOB"; else kill -TERM $(pgrep -s "$JOB" -x campaign); fi
    thaw_job
    wait "$JOB"
    JOB_RC=$?
}

run_expect 0 ref "$EXE" run "$SWEEP" --store "$WORK/ref.h5" --progress-interval 0
digest "$WORK/ref.h5" ref.digest
[ "$(wc -l <ref.digest)" -eq 4 ] || fail "reference has $(wc -l <ref.digest) realizations"

# 1. SIGTERM mid-realization: states saved.
STORE=$WORK/c.h5
: >job.err
start_job $(run_cmd "$STORE")
# (Margin: the SIGTERM must find a realization running, any one: each running one saves its
# state at its next step. Seen at 0.4 s into the first pair, at least the second pair of
# about 1 s each is still to come, whatever the load.)
wait_running "$STORE" 0.4
stop_all
[ "$JOB_RC" -eq 4 ] || { cat job.err >&2; fail "SIGTERM: exit $JOB_RC, expected 4"; }
expect_in job.err "its state is saved and continues on resume"
n=$(ls "$STORE.checkpoints"/*.ckpt 2>/dev/null | wc -l)
[ "$n" -ge 1 ] || fail "no checkpoint file after SIGTERM"
run_expect 0 st1 "$EXE" status "$STORE" --json
"$PY" - st1.out "$n" <<'PY' || fail "status after SIGTERM"
import json, sys
s = json.load(open(sys.argv[1]))
r = s["runs"][-1]
assert r["end_reason"] == "interrupted by SIGTERM", r
assert r["saved_worker_seconds"] > 0 and r["lost_worker_seconds"] == 0, r
assert s["checkpoints"] == int(sys.argv[2]) and s["running"] == [], s
PY
"$PY" - "$STORE" <<'PY' || fail "runs table in the HDF5 file"
import h5py, sys
with h5py.File(sys.argv[1], "r") as f:
    runs = f["runs"]
    assert runs["saved_worker_seconds"][-1] > 0 and runs["lost_worker_seconds"][-1] == 0
PY
cp "$STORE.checkpoints"/*.ckpt "$WORK/" # kept for case 4

# 2. One file as if from another code version (checksum recomputed): refused, restarted.
victim=$(ls "$STORE.checkpoints"/*.ckpt | head -1)
"$PY" - "$victim" <<'PY' || fail "rewriting the checkpoint"
import os, struct, sys
sys.path.insert(0, os.path.join(os.environ["SRC"], "tests", "campaign"))
from ckpt_file import read_body, write_body
body = read_body(sys.argv[1])
n = struct.unpack("<I", body[12:16])[0]  # the code version's length prefix
new = b"v0.0-other"
write_body(sys.argv[1], body[:12] + struct.pack("<I", len(new)) + new + body[16 + n:])
PY
run_expect 0 rerun $(run_cmd "$STORE")
expect_in rerun.err "written by code version v0.0-other"
expect_in rerun.err "the realization restarts from its beginning"
if [ "$n" -ge 2 ]; then expect_in rerun.err "realization(s) continued from a checkpoint"; fi
[ ! -e "$STORE.checkpoints" ] || fail "checkpoints left after the campaign finished: $(ls "$STORE.checkpoints")"
digest "$STORE" c.digest
same_digests ref.digest c.digest

# Slow realizations for the cases that need one still running after a second or more (3 and
# 6): delta 200, 4x the steps of ckpt.toml's (other bits, so they have their own reference).
# On a fast machine ckpt.toml's can end, and their checkpoints be removed, before the stop.
sed 's/^steps_per_collision = 50$/steps_per_collision = 200/' "$SWEEP" >slow.toml
grep -q '^steps_per_collision = 200$' slow.toml || fail "slow.toml: no steps_per_collision line"
FAST_SWEEP=$SWEEP
SWEEP=slow.toml
run_expect 0 slowref $(run_cmd "$WORK/slow_ref.h5")
digest "$WORK/slow_ref.h5" slow_ref.digest

# 3. SIGKILL with periodic checkpoints: the rerun continues from them (slow realizations:
# 3.5-5.5 s each on a quiet core, so the one seen running for 1 s is still running at the kill).
STORE=$WORK/k.h5
: >job.err
start_job $(run_cmd "$STORE" --checkpoint-interval 0.3)
wait_running "$STORE" 1.0
thaw_job
# The first periodic state is due 0.3 s into the realization; wait for its file (the condition
# the kill needs), not a fixed time: on a loaded machine it can come later.
t_end=$((SECONDS + 120))
until ls "$STORE.checkpoints"/*.ckpt >/dev/null 2>&1 || [ "$SECONDS" -ge "$t_end" ]; do sleep 0.05; done
n=$(ls "$STORE.checkpoints"/*.ckpt 2>/dev/null | wc -l)
kill_job KILL
[ "$n" -ge 1 ] || fail "no periodic checkpoint within 120 s with --checkpoint-interval 0.3"
run_expect 0 krerun $(run_cmd "$STORE")
expect_in krerun.err "realization(s) continued from a checkpoint"
digest "$STORE" k.digest
same_digests slow_ref.digest k.digest
SWEEP=$FAST_SWEEP

# 4. Other physics under the same labels: refused, restarted.
STORE=$WORK/p.h5
mkdir -p "$STORE.checkpoints" && cp "$WORK"/*.ckpt "$STORE.checkpoints/"
run_expect 0 phys "$EXE" run "$DATA/ckpt_physics.toml" --store "$STORE" --progress-interval 0 --threads 2
expect_in phys.err "it was written for other physics of this point"
[ ! -e "$STORE.checkpoints" ] || fail "refused checkpoints were not removed"

# 5. Without checkpoints the interrupted worker time is thrown away, and /runs says so.
#    The slow realizations (3.5-5.5 s of one quiet core each, ckpt.toml's about 1 s): the one
#    seen running for 1 s is still running at the SIGTERM, sent while the job is frozen in the
#    state that was seen (wait_running), however loaded the machine.
#    (With ckpt.toml's, under ctest -j2 the one seen could end in that gap and a fresh one be
#    stopped instead: 0.04 s lost, issue 45.) The test then checks that very realization was
#    the one stopped, from the run's own log, before it asserts the loss: its worker time is
#    counted from its arrival at the worker, at most a scheduling delay after the dispatch the
#    1 s is counted from, so more than 0.3 s is thrown away.
SWEEP=slow.toml
STORE=$WORK/n.h5
: >job.err
start_job $(run_cmd "$STORE" --no-checkpoints)
wait_running "$STORE" 1.0
stop_all
[ "$JOB_RC" -eq 4 ] || { cat job.err >&2; fail "SIGTERM without checkpoints: exit $JOB_RC"; }
[ ! -e "$STORE.checkpoints" ] || fail "--no-checkpoints wrote checkpoints"
seen=$(cat running.txt)
grep -F -- "$seen stopped after" job.err | grep -qF "of its worker time is thrown away (checkpoints are off)" ||
    { cat job.err >&2; fail "the realization seen running for 1 s ($seen) was not the one stopped"; }
run_expect 0 st5 "$EXE" status "$STORE" --json
"$PY" -c "
import json, sys
r = json.load(open('st5.out'))['runs'][-1]
assert r['lost_worker_seconds'] > 0.3 and r['saved_worker_seconds'] == 0, r" ||
    fail "lost worker seconds without checkpoints"
SWEEP=$FAST_SWEEP

# 6. Deadlines. Nothing measured yet: realizations start and are stopped (states saved) at the
#    deadline minus the grace; the rest of the campaign then ends identical. Measured (the
#    reference store, extended by 2 realizations per point), without checkpoints: none is
#    started that the measured durations say cannot end in time. (With checkpoints one that is
#    longer than the whole allocation starts anyway: it can only finish in pieces.)
#    The realizations run at delta 200 here (4x the steps of ckpt.toml's; other bits, so they
#    have their own reference): on a fast machine ckpt.toml's could all end before the stop,
#    and nothing would be saved.
FAST_SWEEP=$SWEEP
SWEEP=slow.toml
STORE=$WORK/d.h5
t0=$(date +%s.%N)
# (stop at 3 s: mpirun's start can take a second on a loaded machine, and a realization must
# be running at the stop; these take 3.5-5.5 s each on a quiet core)
run_expect 4 dl $(run_cmd "$STORE" --deadline +4 --grace 1)
took=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
# (A bound against hanging, not a speed test: mpirun's start and end add seconds on a loaded
# or one-core machine, and a hang would last until ctest's timeout.)
awk -v t="$took" 'BEGIN { exit !(t < 30) }' || fail "the deadline run took $took s (deadline 4 s)"
expect_in dl.err "nothing of this campaign is measured yet"
expect_in dl.err "stopped by the deadline"
run_expect 0 dst "$EXE" status "$STORE" --json
"$PY" -c "
import json
r = json.load(open('dst.out'))['runs'][-1]
assert r['end_reason'] == 'interrupted by the deadline', r
assert r['lost_worker_seconds'] == 0 and r['saved_worker_seconds'] > 0, r
assert json.load(open('dst.out'))['done'] < 4" || fail "deadline run"
run_expect 0 dfinish $(run_cmd "$STORE")
digest "$STORE" d.digest
same_digests slow_ref.digest d.digest
# The measured speed against a deadline of 1 s: the slow realizations (3.5-5.5 s each, measured
# on slow_ref.h5's stored ones) cannot end before it, whatever the machine (ckpt.toml's took
# about 1 s with 0.4.0's engine, and one was started: failed in CI).
sed 's/^realizations = 2$/realizations = 4/' slow.toml >more.toml
grep -q '^realizations = 4$' more.toml || fail "more.toml: no realizations line"
SWEEP=$FAST_SWEEP
run_expect 4 dm "$EXE" run more.toml --store "$WORK/slow_ref.h5" --progress-interval 0 --deadline +1 \
    --grace 0.5 --no-checkpoints
expect_in dm.err "none of the 4 realization(s) left is expected to finish before it"
expect_in dm.err "and checkpoints are off: it cannot finish in an allocation this long"
run_expect 0 dmst "$EXE" status "$WORK/slow_ref.h5" --json
"$PY" -c "
import json
s = json.load(open('dmst.out'))
assert s['done'] == 4 and s['pending'] == 4, s" || fail "a realization started after the measured deadline"
for bad in tomorrow +5x @ 2026-13-01T00:00:00 slurm; do
    run_expect 2 badd env -u SLURM_JOB_ID "$EXE" run "$SWEEP" --store "$WORK/x.h5" --deadline "$bad"
    expect_in badd.err "--deadline '$bad'"
done
expect_in badd.err "not inside a Slurm job"
run_expect 2 both "$EXE" run "$SWEEP" --store "$WORK/x.h5" --no-checkpoints --checkpoint-interval 5
expect_in both.err "contradict"
[ ! -e "$WORK/x.h5" ] || fail "a refused command line created a store"
echo "checkpoint.sh: passed"
