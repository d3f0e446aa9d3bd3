#!/bin/bash
# Issue 25: a store written by the engine before round 3 (0.3.0; data/store_before_round3.tar.gz:
# the journal of tests/campaign/data/mini.toml run by commit 0ac00da) with this build, whose
# engine arithmetic is round 3's (0.4.0):
# 1. it opens and is rebuilt from its journal; `campaign run` of the same sweep runs nothing;
# 2. `simulate --point` re-runs a stored realization, which now differs, and says why: the
#    versions that wrote the store, and that another arithmetic reproduces it in distribution;
# 3. it resumes with more realizations and a new point: the stored realizations stay exactly as
#    they were, the new ones are added;
# 4. the same sweep in a fresh store gives the same realizations (seeds) with other step counts.
source "$(dirname "$0")/lib.sh"
tar xzf "$DATA/store_before_round3.tar.gz" -C "$WORK" || fail "cannot unpack the fixture"

run_expect 0 same "$EXE" run "$MINI" --store "$WORK/old.h5" --progress-interval 0 --no-plots
expect_in same.err "12 realizations in the sweep, 12 stored, 0 to run"

snapshot() {
    "$PY" - "$1" "$2" <<'PYEOF' || fail "cannot read $1"
import json, sys, h5py
f = h5py.File(sys.argv[1], "r")
r = f["realizations"]
labels = f["points/label"].asstr()[:]
out = {f"{labels[r['point'][i]]}#{int(r['realization'][i])}":
       [int(r["seed"][i]), int(r["diagnostics/steps"][i]), int(r["survival_length"][i])]
       for i in range(r["point"].shape[0])}
json.dump(out, open(sys.argv[2], "w"), sort_keys=True)
PYEOF
}
snapshot "$WORK/old.h5" "$WORK/before.json"

label=$("$PY" -c "import h5py,sys; print(h5py.File(sys.argv[1],'r')['points/label'].asstr()[0])" "$WORK/old.h5")
run_expect 1 rerun "$EXE" simulate --store "$WORK/old.h5" --point "$label" --realization 0
expect_in rerun.err "the run differs from the stored realization 0"
expect_in rerun.err "the store was written by hopper 0.3.0+0ac00da, this is"
expect_in rerun.err "in distribution, not bit for bit"

run_expect 0 resume "$EXE" run "$DATA/mini_extended.toml" --store "$WORK/old.h5" --progress-interval 0 --no-plots
expect_in resume.err "20 realizations in the sweep, 12 stored, 8 to run"
snapshot "$WORK/old.h5" "$WORK/after.json"

run_expect 0 fresh "$EXE" run "$MINI" --store "$WORK/new.h5" --progress-interval 0 --no-plots
snapshot "$WORK/new.h5" "$WORK/fresh.json"

"$PY" - "$WORK/before.json" "$WORK/after.json" "$WORK/fresh.json" <<'PYEOF' || fail "resume or fresh run wrong"
import json, sys
before, after, fresh = (json.load(open(p)) for p in sys.argv[1:4])
assert len(before) == 12 and len(after) == 20, (len(before), len(after))
for k, v in before.items():
    assert after[k] == v, ("a stored realization changed on resume", k, v, after[k])
assert sorted(fresh) == sorted(before)
assert all(fresh[k][0] == before[k][0] for k in before), "the seeds differ"
differ = sum(fresh[k][1] != before[k][1] for k in before)
assert differ > 0, "every realization took the old engine's steps: this build has the old arithmetic"
print("resume kept 12, added 8; fresh run: the same seeds,", differ, "of 12 with other step counts")
PYEOF
echo "PASS"
