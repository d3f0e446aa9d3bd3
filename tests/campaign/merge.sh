#!/bin/bash
# campaign merge (issue 43): stores of one campaign joined into one with nothing lost or
# duplicated and every realization identical to its source (store_digest: one line per
# realization, fails on a duplicate or a journal/HDF5 mismatch):
#   (a) the sweep's points split into two halves run into A and B, merged: the reference's digests
#   (b) a store merged with itself: the same digests, nothing twice, its runs once (also one with
#       fields: the same maps)
#   (c) a run killed (SIGKILL) mid-way into A, A copied to B and B resumed to the end, A and B
#       merged: the reference's digests
#   (d) refusals, exit 2 and nothing written: another campaign seed, a point of the same label
#       with other physics, the output existing, an input missing, a store a run is writing
#   (e) the merged store resumed by `campaign run` with the sweep: nothing to run, unchanged,
#       and readable by status, analyze, export and hopper_store.py
source "$(dirname "$0")/lib.sh"
reference

# count LINES_FILE: lines in it
count() { wc -l <"$1" | tr -d ' '; }
# lost_duplicated REF MERGED NAME: the reference's realizations missing from (or changed in) the
# merged store's digests, and those the merged store holds more than once (store_digest already
# fails on one in its journal or HDF5 file); both must be 0
lost_duplicated() {
    local lost dup
    lost=$(comm -23 <(sort "$1") <(sort -u "$2") | wc -l)
    dup=$(($(count "$2") - $(sort -u "$2" | wc -l)))
    echo "$3: $(count "$2") realizations, $lost lost, $dup duplicated"
    [ "$lost" -eq 0 ] && [ "$dup" -eq 0 ] || fail "$3: $lost lost, $dup duplicated"
}
# no_output STORE: a refused merge left nothing behind
no_output() { [ ! -e "$1" ] && [ ! -e "$1.journal" ] || fail "a refused merge left $1 behind"; }

# (a) Two halves of the points, run separately.
sed 's/^D_cm = .*/D_cm = [1.9]/' "$MINI" >half1.toml
sed 's/^D_cm = .*/D_cm = [2.6, 3.5]/' "$MINI" >half2.toml
run_expect 0 half1 "$EXE" run half1.toml --store "$WORK/A.h5" --progress-interval 0
run_expect 0 half2 "$EXE" run half2.toml --store "$WORK/B.h5" --progress-interval 0
digest "$WORK/A.h5" A.digest
digest "$WORK/B.h5" B.digest
[ "$(count A.digest)" -eq 4 ] && [ "$(count B.digest)" -eq 8 ] || fail "halves hold $(count A.digest) and $(count B.digest)"
run_expect 0 merge_ab "$EXE" merge "$WORK/A.h5" "$WORK/B.h5" --store "$WORK/AB.h5"
expect_in merge_ab.out "3 points, 12 realizations (0 identical copies stored once), 2 runs"
digest "$WORK/AB.h5" AB.digest
lost_duplicated ref.digest AB.digest "merge AB"
same_digests ref.digest AB.digest

# (b) A store merged with itself.
run_expect 0 merge_self "$EXE" merge "$WORK/ref.h5" "$WORK/ref.h5" --store "$WORK/self.h5"
expect_in merge_self.out "12 realizations (12 identical copies stored once), 1 runs (1 shared"
digest "$WORK/self.h5" self.digest
lost_duplicated ref.digest self.digest "merge self"
same_digests ref.digest self.digest

# ... and a store with fields: the maps of every realization as they were
run_expect 0 fields "$EXE" run "$DATA/mini_fields.toml" --store "$WORK/F.h5" --progress-interval 0
run_expect 0 merge_fields "$EXE" merge "$WORK/F.h5" "$WORK/F.h5" --store "$WORK/FF.h5"
digest "$WORK/F.h5" F.digest
digest "$WORK/FF.h5" FF.digest
lost_duplicated F.digest FF.digest "merge fields"
same_digests F.digest FF.digest
"$PY" - "$WORK/F.h5" "$WORK/FF.h5" <<'EOF' || fail "the merged field maps differ"
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
assert sorted(a["fields"]) == sorted(b["fields"]) and len(a["fields"]) > 0
for k in a["fields"]:
    for m in a["fields"][k]:
        assert np.array_equal(a["fields"][k][m][()], b["fields"][k][m][()]), (k, m)
EOF

# (c) Two halves of a killed-and-resumed run.
start_job "$EXE" run "$MINI" --store "$WORK/K.h5" --progress-interval 0
wait_stored "$WORK/K.h5" 4
kill_job KILL
cp "$WORK/K.h5.journal" "$WORK/R.h5.journal"
[ -e "$WORK/K.h5" ] && cp "$WORK/K.h5" "$WORK/R.h5"
killed=$("$PY" -c 'import json,sys; print(json.load(sys.stdin)["done"])' < <("$EXE" status "$WORK/K.h5" --json))
[ "$killed" -ge 4 ] && [ "$killed" -lt 12 ] || fail "the killed run holds $killed realizations (not mid-way)"
run_expect 0 resume_r "$EXE" run "$MINI" --store "$WORK/R.h5" --progress-interval 0
run_expect 0 merge_kr "$EXE" merge "$WORK/K.h5" "$WORK/R.h5" --store "$WORK/KR.h5"
expect_in merge_kr.out "12 realizations ($killed identical copies stored once), 2 runs (1 shared"
digest "$WORK/KR.h5" KR.digest
lost_duplicated ref.digest KR.digest "merge KR"
same_digests ref.digest KR.digest
# ... in either order
run_expect 0 merge_rk "$EXE" merge "$WORK/R.h5" "$WORK/K.h5" --store "$WORK/RK.h5"
digest "$WORK/RK.h5" RK.digest
lost_duplicated ref.digest RK.digest "merge RK"
same_digests ref.digest RK.digest

# (e) The merged stores resume with nothing to run and stay the same; readers read them.
for s in AB KR; do
    run_expect 0 resume_$s "$EXE" run "$MINI" --store "$WORK/$s.h5" --progress-interval 0
    expect_in resume_$s.err "12 realizations in the sweep, 12 stored"
    digest "$WORK/$s.h5" $s.after
    same_digests ref.digest $s.after
done
run_expect 0 status_ab "$EXE" status "$WORK/AB.h5" --json
"$PY" -c 'import json,sys; s=json.load(open("status_ab.out")); sys.exit(0 if s["done"] == 12 and s["pending"] == 0 else 1)' ||
    fail "status of the merged store: $(cat status_ab.out)"
run_expect 0 analyze_ab "$EXE" analyze "$WORK/AB.h5"
run_expect 0 export_ab "$EXE" export "$WORK/AB.h5" --csv "$WORK/ab_csv"
"$PY" - "$SRC/analysis" "$WORK/KR.h5" <<'EOF' || fail "hopper_store.py on the merged store"
import sys
sys.path.insert(0, sys.argv[1])
import hopper_store
s = hopper_store.open_store(sys.argv[2])
assert len(s.realizations) == 12, len(s.realizations)
assert len(s.realizations.groupby(["point", "realization"])) == 12
s.close()
import h5py
with h5py.File(sys.argv[2], "r") as f:
    reasons = list(f["runs/end_reason"].asstr()[:])
    stored = [int(x) for x in f["runs/stored"][:]]
# the killed run once (no end), its copy's resume, the merge, the resume of (e)
assert reasons == ["", "complete", "merged 2 stores", "complete"], reasons
assert sum(stored) == 12, stored
print("hopper_store ok")
EOF

# (d) Refusals: exit 2, a message naming the problem, nothing written.
run_expect 0 seed12 "$EXE" run "$DATA/mini_seed.toml" --store "$WORK/S12.h5" --progress-interval 0
run_expect 2 r_seed "$EXE" merge "$WORK/ref.h5" "$WORK/S12.h5" --store "$WORK/x.h5"
expect_in r_seed.err "the campaign seeds differ"
expect_in r_seed.err "has seed 12"
no_output "$WORK/x.h5"
run_expect 0 phys "$EXE" run "$DATA/mini_physics.toml" --store "$WORK/P.h5" --progress-interval 0
run_expect 2 r_phys "$EXE" merge "$WORK/ref.h5" "$WORK/P.h5" --store "$WORK/x.h5"
expect_in r_phys.err "has other physics in"
expect_in r_phys.err "material.e_n = 0.5 in"
no_output "$WORK/x.h5"
run_expect 2 r_exists "$EXE" merge "$WORK/A.h5" "$WORK/B.h5" --store "$WORK/AB.h5"
expect_in r_exists.err "AB.h5' exists; a merge writes a new store"
digest "$WORK/AB.h5" AB.again
same_digests ref.digest AB.again
run_expect 2 r_missing "$EXE" merge "$WORK/A.h5" "$WORK/nowhere.h5" --store "$WORK/x.h5"
expect_in r_missing.err "no store at '$WORK/nowhere.h5'"
no_output "$WORK/x.h5"
run_expect 2 r_noargs "$EXE" merge --store "$WORK/x.h5"
expect_in r_noargs.err "missing the stores to merge"
# A journal whose HDF5 file holds more than it knows (the journal replaced).
cp "$WORK/ref.h5" "$WORK/J.h5" && cp "$WORK/A.h5.journal" "$WORK/J.h5.journal"
run_expect 2 r_disagree "$EXE" merge "$WORK/J.h5" --store "$WORK/x.h5"
expect_in r_disagree.err "the journal and the HDF5 file disagree"
no_output "$WORK/x.h5"
# A store a run is writing (frozen while it holds the journal's lock).
start_job "$EXE" run "$MINI" --store "$WORK/live.h5" --progress-interval 0
freeze_when "$WORK/live.h5" "s['active'] and s['pending'] > 0" "status seeing the run active"
run_expect 2 r_live "$EXE" merge "$WORK/live.h5" "$WORK/A.h5" --store "$WORK/x.h5"
expect_in r_live.err "is being written by a \`campaign run\`"
no_output "$WORK/x.h5"
thaw_job
wait "$JOB" || { cat job.err >&2; fail "the run failed while a merge was refused"; }
digest "$WORK/live.h5" live.digest
same_digests ref.digest live.digest

run_expect 0 help "$EXE" help merge
expect_in help.out "exit codes:"
echo "ok: merge, 0 lost, 0 duplicated (halves, self, killed+resumed); refusals"
