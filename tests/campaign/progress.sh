#!/bin/bash
# Honest progress: while mini_fields.toml runs (one worker, about 2 s), `campaign status` shows
# a rate line with an ETA from the cost model and the busy worker with its age; --json has
# eta_seconds and busy_workers; after the run the rate is positive and nothing is pending.
# `campaign simulate --progress` prints the wall-clock rate and, once particles leave, an ETA.
source "$(dirname "$0")/lib.sh"
"$EXE" run "$DATA/mini_fields.toml" --store "$WORK/p.h5" --progress-interval 0 >run.out 2>run.err &
pid=$!
seen=0
for _ in $(seq 1 200); do
    if "$EXE" status "$WORK/p.h5" >st.out 2>/dev/null && grep -q "is writing the store" st.out &&
        grep -q " pending" st.out && ! grep -q "0 pending" st.out; then
        "$EXE" status "$WORK/p.h5" --json >st.json 2>/dev/null && seen=1 && break
    fi
    sleep 0.02
done
wait $pid || fail "the run failed: $(cat run.err)"
[ $seen -eq 1 ] || fail "never saw the run in progress"
grep -Eq "^rate .* realizations per hour \(last run\); ETA [0-9]" st.out || { cat st.out; fail "no ETA while running"; }
grep -Eq "^workers   rank 1 busy [0-9]" st.out || { cat st.out; fail "no busy worker"; }
"$PY" - st.json <<'PYEOF' || fail "status --json while running"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["active"] and d["pending"] > 0, d
assert d["eta_seconds"] is not None and 0 < d["eta_seconds"] < 600, d["eta_seconds"]
assert d["busy_workers"] and d["busy_workers"][0]["rank"] == 1, d["busy_workers"]
assert d["eta_basis"].startswith("cost model"), d["eta_basis"]
PYEOF
run_expect 0 after "$EXE" status "$WORK/p.h5" --json
"$PY" -c "import json,sys; d=json.load(open('after.out')); assert d['per_hour'] > 0 and d['eta_seconds'] is None and d['busy_workers'] == [], d" ||
    fail "status after the run"
run_expect 0 sim "$EXE" simulate "$SRC/campaigns/tiny.toml" --D 3 --theta 60 --seed 2 --progress
grep -Eq "sim-s/s  elapsed [0-9]+s  ETA [0-9]" sim.err || { cat sim.err; fail "simulate --progress has no rate and ETA"; }
echo "progress.sh: passed"
