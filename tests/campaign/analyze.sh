#!/bin/bash
# `campaign analyze` and analysis/plots.py end to end on mini.toml (12 realizations, 3 outlets):
# - `campaign run` analyzes at the end (/analysis written) and prints the plots command;
# - `analyze --json` parses, has every key of docs/statistics.md, and agrees with the raw realizations
#   read with h5py (tau = total time / jams, counts, means); a point without jams has
#   tau_mle null with a reason; the /analysis datasets have units, descriptions, no NaN;
# - re-analysis replaces the group (same members, one row per point, no duplicates);
# - deleting the HDF5 file: the next `campaign run` rebuilds it and analyzes again;
# - plots.py writes every figure (skipped, exit 77, only if matplotlib is missing).
source "$(dirname "$0")/lib.sh"
reference
expect_in ref.out "analysis written to $WORK/ref.h5:/analysis"
expect_in ref.out "figures: campaign plot $WORK/ref.h5 --out $WORK/ref_plots"

run_expect 0 json "$EXE" analyze "$WORK/ref.h5" --json
"$PY" "$SRC/tests/campaign/check_analysis.py" json.out "$WORK/ref.h5" || fail "check_analysis.py"

# Re-analysis replaces the group: same members, same row counts, a later creation time.
created() {  # the /analysis group's creation time (UTC, whole seconds, ISO 8601)
    "$PY" -c "
import h5py, sys
c = h5py.File(sys.argv[1], 'r')['analysis'].attrs['created']
print(c.decode() if isinstance(c, bytes) else c)" "$WORK/ref.h5"
}
created >created1.txt || fail "h5py"
h5ls -r "$WORK/ref.h5" | grep '^/analysis' >members1.txt || fail "h5ls"
# The time stamp has whole seconds: wait until the clock has left the first one's second.
wait_until "the UTC clock passing $(cat created1.txt)" eval '[[ "$(date -u +%Y-%m-%dT%H:%M:%SZ)" > "$(cat created1.txt)" ]]'
run_expect 0 again "$EXE" analyze "$WORK/ref.h5"
expect_in again.out "analysis written to"
h5ls -r "$WORK/ref.h5" | grep '^/analysis' >members2.txt || fail "h5ls"
cmp -s members1.txt members2.txt || { diff members1.txt members2.txt >&2; fail "members differ"; }
grep -q '^/analysis/points/label *Dataset {3/Inf}' members2.txt || fail "/analysis/points rows"
created >created2.txt || fail "h5py"
[[ "$(cat created2.txt)" > "$(cat created1.txt)" ]] ||
    fail "re-analysis did not replace /analysis: created $(cat created1.txt), then $(cat created2.txt)"
"$PY" "$SRC/tests/campaign/check_store.py" "$WORK/ref.h5" "$EXE" "$MINI" || fail "check_store.py"
digest "$WORK/ref.h5" "$WORK/after.digest"
same_digests "$WORK/ref.digest" "$WORK/after.digest"

# --no-write leaves the file alone; a missing store is an error (exit 1).
run_expect 0 nowrite "$EXE" analyze "$WORK/ref.h5" --no-write
run_expect 1 missing "$EXE" analyze "$WORK/nothing.h5"
expect_in missing.err "no store at"

# The HDF5 file is a view: delete it, the next run rebuilds it and analyzes again.
cp "$WORK/ref.h5" "$WORK/kept.h5"
rm "$WORK/ref.h5"
run_expect 1 stale "$EXE" analyze "$WORK/ref.h5"
expect_in stale.err "not in step"
run_expect 0 rebuild "$EXE" run "$MINI" --store "$WORK/ref.h5" --progress-interval 0
expect_in rebuild.out "analysis written to"
h5ls -r "$WORK/ref.h5" | grep '^/analysis' >members3.txt || fail "h5ls"
cmp -s members1.txt members3.txt || { diff members1.txt members3.txt >&2; fail "members differ after rebuild"; }

# The figures.
if ! "$PY" -c "import matplotlib" 2>/dev/null; then
    echo "SKIP: plots.py not run: matplotlib is missing (apt-get install python3-matplotlib)"
    exit 77
fi
run_expect 0 plots "$PY" "$SRC/analysis/plots.py" "$WORK/ref.h5" --out "$WORK/plots"
for fig in survival jam_onsets beverloo in_hopper; do
    f="$WORK/plots/$fig.png"
    [ -s "$f" ] || fail "plots.py did not write $fig.png"
    head -c 8 "$f" | od -An -tx1 | grep -q '89 50 4e 47 0d 0a 1a 0a' || fail "$fig.png is not a PNG"
    expect_in plots.out "$fig.png"
done
run_expect 2 plots_noanalysis "$PY" "$SRC/analysis/plots.py" "$WORK/nothing.h5" --out "$WORK/p2"
echo "ok"
