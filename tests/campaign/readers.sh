#!/bin/bash
# Readers during a run (issue 27): `campaign export`, `plot`, `analyze` and hopper_store's
# open_store() on a store that a `campaign run` is writing show every realization stored at
# that moment and do not disturb the writer, which ends with exit 0 and the results of an
# uninterrupted run. (Before: export and plot exited 1 on HDF5's file lock, analyze exited 1.)
source "$(dirname "$0")/lib.sh"
reference
STORE=$WORK/live.h5
done_now() {
    "$EXE" status "$STORE" --json | "$PY" -c 'import json,sys; print(json.load(sys.stdin)["done"])'
}
csv_rows() {
    echo $(($(wc -l <"$1/realizations.csv") - 1))
}

start_job env HOPPER_STORE_STOP=result:3 "$EXE" run "$MINI" --store "$STORE" --progress-interval 0 --threads 1
trap thaw_job EXIT  # a failed check must not leave the writer frozen
# The writer frozen mid-run (its journal locked, its HDF5 file open for writing): what is
# stored at the moment of reading is then fixed. It stops itself once 3 are stored (lib.sh's
# freeze_at_stop), 9 still to run: it holds the store during the reads however fast it runs.
freeze_at_stop "$STORE" "s['done'] == 3 and s['pending'] > 0" "3 realizations stored, more to run"
stored=$(done_now)
"$EXE" status "$STORE" --json | "$PY" -c 'import json,sys; sys.exit(0 if json.load(sys.stdin)["active"] else 1)' ||
    fail "the writer is not holding the store"
beside=$(ls "$WORK" | grep '^live\.h5')

run_expect 0 export "$EXE" export "$STORE" --csv csv
expect_in export.err "a \`campaign run\` is writing"
[ "$(csv_rows csv)" -eq "$stored" ] || fail "export wrote $(csv_rows csv) realizations, $stored stored"

run_expect 0 analyze "$EXE" analyze "$STORE" --json
expect_in analyze.err "/analysis not written: a \`campaign run\` is writing the store"
"$PY" - analyze.out "$stored" <<'PY' || fail "analyze during the run"
import json, sys
a = json.load(open(sys.argv[1]))
n = sum(p["realizations"] for p in a["points"])
assert n == int(sys.argv[2]), (n, sys.argv[2])
PY

HOPPER_CAMPAIGN=$EXE PYTHONPATH=$SRC/analysis "$PY" - "$STORE" "$stored" <<'PY' || fail "open_store during the run"
import os, sys
from hopper_store import open_store, writer_active
assert writer_active(sys.argv[1])
s = open_store(sys.argv[1])
assert len(s.realizations) == int(sys.argv[2]), (len(s.realizations), sys.argv[2])
assert s.path == sys.argv[1]
view = s._f.filename
s.close()
assert not os.path.exists(view), view  # the snapshot is removed by close()
PY

# hopper_store.readable(): scripts that read the HDF5 layout themselves (analysis/calibration.py)
# get a snapshot's path during the run (before: h5py failed on the writer's file lock).
HOPPER_CAMPAIGN=$EXE PYTHONPATH=$SRC/analysis "$PY" - "$STORE" "$stored" <<'PY' || fail "readable() during the run"
import os, sys, h5py
from hopper_store import readable
with readable(sys.argv[1]) as path:
    assert path != sys.argv[1], path
    with h5py.File(path, "r") as f:
        assert len(f["realizations/seed"]) == int(sys.argv[2]), len(f["realizations/seed"])
assert not os.path.exists(path), path  # the snapshot is removed at the block's end
PY

if "$PY" -c 'import matplotlib' 2>/dev/null; then
    run_expect 0 plot "$EXE" plot "$STORE" --out plots
    expect_in plot.err "a \`campaign run\` is writing"
    ls plots/*.png >/dev/null 2>&1 || fail "plot drew nothing during the run"
fi
# Nothing was written beside the store.
[ "$(ls "$WORK" | grep '^live\.h5')" = "$beside" ] || fail "readers left files beside the store"

# The writer goes on; readers poll while it runs, each seeing between what was stored before
# and after it read.
thaw_job
polls=0
while kill -0 "$JOB" 2>/dev/null && [ $polls -lt 50 ]; do
    before=$(done_now)
    rm -rf poll
    "$EXE" export "$STORE" --csv poll >poll.out 2>poll.err || { cat poll.err >&2; fail "export while running"; }
    after=$(done_now)
    rows=$(csv_rows poll)
    [ "$rows" -ge "$before" ] && [ "$rows" -le "$after" ] || fail "export saw $rows, stored $before..$after"
    polls=$((polls + 1))
done
wait "$JOB" || { cat job.err >&2; fail "the writer failed while readers read"; }
digest "$STORE" live.digest
same_digests "$WORK/ref.digest" live.digest
echo "ok ($polls polls while running)"
