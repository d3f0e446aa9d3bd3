#!/bin/bash
# Honest progress: while mini_fields.toml runs (one worker, about 2 s), `campaign status` shows
# a rate line with an ETA from the cost model, the busy worker with its age and the realization
# it runs (the master's STORE.running file, issue 16); --json has eta_seconds, busy_workers and
# running; after the run the rate is positive, nothing is pending and nothing is running.
# `campaign simulate --progress` prints the wall-clock rate and, once particles leave, an ETA.
source "$(dirname "$0")/lib.sh"
# The run is frozen (lib.sh) once status --json sees it in progress (active, a realization
# running, more pending); both status forms are then read from that one state.
start_job "$EXE" run "$DATA/mini_fields.toml" --store "$WORK/p.h5" --progress-interval 0
freeze_when "$WORK/p.h5" "s['active'] and s['pending'] > 0 and len(s['running']) == 1" \
    "status seeing the run in progress"
"$EXE" status "$WORK/p.h5" >st.out 2>st.err || { thaw_job; cat st.err; fail "status while running"; }
"$EXE" status "$WORK/p.h5" --json >st.json 2>/dev/null || { thaw_job; fail "status --json while running"; }
thaw_job
wait "$JOB" || fail "the run failed: $(cat job.err)"
grep -q "is writing the store" st.out && grep -Eq "^progress .*, [1-9][0-9]* pending" st.out &&
    grep -q "^running " st.out || { cat st.out; fail "status does not show the run in progress"; }
grep -Eq "^rate .* realizations per hour \(last run\); ETA [0-9]" st.out || { cat st.out; fail "no ETA while running"; }
grep -Eq "^workers   worker 1 busy [0-9]" st.out && ! grep -q "rank " st.out || { cat st.out; fail "no busy worker"; }
grep -Eq "^running   worker 1: 'D_cm=[0-9.]+ theta_deg=[0-9]+ material.mu=0.5' #[0-9] for [0-9]+s" st.out ||
    { cat st.out; fail "no running realization with its worker and age"; }
"$PY" - st.json <<'PYEOF' || fail "status --json while running"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["active"] and d["pending"] > 0, d
assert d["eta_seconds"] is not None and 0 < d["eta_seconds"] < 600, d["eta_seconds"]
assert d["busy_workers"] and d["busy_workers"][0]["worker"] == 1, d["busy_workers"]
assert d["busy_workers"][0]["rank"] == 1, d["busy_workers"]  # the 0.4 key, kept
assert d["eta_basis"].startswith("cost model"), d["eta_basis"]
r = d["running"]
assert len(r) == 1 and r[0]["worker"] == 1 and r[0]["label"].startswith("D_cm="), r
assert 0 <= r[0]["seconds"] < 600 and r[0]["attempt"] == 1 and not r[0]["resumed"], r
PYEOF
run_expect 0 after "$EXE" status "$WORK/p.h5" --json
"$PY" -c "import json,sys; d=json.load(open('after.out')); assert d['per_hour'] > 0 and d['eta_seconds'] is None and d['busy_workers'] == [] and d['running'] == [], d" ||
    fail "status after the run"
run_expect 0 sim "$EXE" simulate "$SRC/campaigns/tiny.toml" --D 3 --theta 60 --seed 2 --progress
grep -Eq "sim-s/s  elapsed [0-9]+s  ETA [0-9]" sim.err || { cat sim.err; fail "simulate --progress has no rate and ETA"; }
echo "progress.sh: passed"
