#!/bin/bash
# A sweep that lowers its points' realizations below what an earlier run planned: `campaign run`
# runs the sweep's count, and `campaign status` counts from the last run's sweep too (total and
# pending; the rest reported as beyond it), not from the store's plan, which only grows. Before,
# status kept counting the earlier plan's tasks as pending, which a batch script resubmitting
# while `status --json` says pending > 0 would do for ever. Raising the count again runs them.
source "$(dirname "$0")/lib.sh"
STORE=$WORK/low.h5
# 1. mini.toml (3 points x 4) stopped after its first result: 12 planned, 1 stored.
start_job env HOPPER_STORE_STOP=result:1 "$EXE" run "$MINI" --store "$STORE" --progress-interval 0 --threads 1
freeze_at_stop "$STORE" "s['done'] == 1" "one realization stored"
kill -TERM $FROZEN
thaw_job
wait "$JOB"
rc=$?
[ "$rc" -eq 4 ] || fail "the stopped run exited $rc, expected 4"
run_expect 0 st1 "$EXE" status "$STORE" --json
"$PY" -c "import json; s = json.load(open('st1.out')); assert (s['total'], s['done'], s['pending']) == (12, 1, 11), s" ||
    fail "status after the stopped run: $(cat st1.out)"
# 2. The same sweep with 1 realization per point: the run completes the two missing ones.
sed 's/^realizations = 4/realizations = 1/' "$MINI" >low.toml
grep -q "^realizations = 1" low.toml || fail "low.toml: mini.toml has no 'realizations = 4' line"
run_expect 0 run2 "$EXE" run low.toml --store "$STORE" --progress-interval 0 --threads 1
expect_in run2.err "3 realizations in the sweep, 1 stored, 2 to run"
run_expect 0 st2 "$EXE" status "$STORE" --json
"$PY" - st2.out <<'PYEOF' || fail "status after the lowered run: $(cat st2.out)"
import json, sys
s = json.load(open(sys.argv[1]))
assert (s["total"], s["done"], s["pending"]) == (3, 3, 0), s
assert all((p["total"], p["limit"], p["done"], p["pending"], p["beyond_sweep"],
            p["stored_beyond_plan"]) == (1, 1, 1, 0, 3, 0) for p in s["points"]), s["points"]
assert s["eta_seconds"] is None, s["eta_seconds"]
PYEOF
run_expect 0 st3 "$EXE" status "$STORE"
expect_in st3.out "progress  3/3 done, 0 failed, 0 pending"
expect_in st3.out "the last run's sweep lowered the realizations of 3 point(s): 9 realization(s)"
# 3. Raised to 2 again: 3 more run, and status counts 2 per point with nothing beyond.
sed 's/^realizations = 4/realizations = 2/' "$MINI" >two.toml
run_expect 0 run3 "$EXE" run two.toml --store "$STORE" --progress-interval 0 --threads 1
run_expect 0 st4 "$EXE" status "$STORE" --json
"$PY" -c "import json; s = json.load(open('st4.out')); assert (s['total'], s['done'], s['pending']) == (6, 6, 0) and all(p['beyond_sweep'] == 2 for p in s['points']), s" ||
    fail "status after raising the count again: $(cat st4.out)"
echo "lowered.sh: passed"
