#!/bin/bash
# Failed realizations: stored with their reason, shown by status (text and JSON) and in the
# summary, exit code 3, refused by `campaign plot` (nothing to draw), and not run again by the
# next `campaign run` (the engine is
# deterministic: the same seed fails the same way).
source "$(dirname "$0")/lib.sh"
run_expect 3 first "$EXE" run "$DATA/failing.toml" --store "$WORK/f.h5" --progress-interval 0
expect_in first.err "finished with 2 failed realization(s)"
expect_in first.out "D_cm=3 theta_deg=60"
"$EXE" status "$WORK/f.h5" >status.txt || fail "status"
expect_in status.txt "0/2 done, 2 failed, 0 pending"
expect_in status.txt "status failed): "
expect_in status.txt "overlap"
"$EXE" status "$WORK/f.h5" --json >status.json || fail "status --json"
"$PY" - status.json <<'PY' || fail "status JSON"
import json, sys
s = json.load(open(sys.argv[1]))
assert (s["total"], s["done"], s["failed"], s["pending"], s["errors"]) == (2, 0, 2, 0, 0), s
assert all(f["kind"] == "failed" and "overlap" in f["reason"] for f in s["failures"]), s
assert s["points"][0]["failed"] == 2
PY
# nothing to draw: `campaign plot` says why and exits 3, instead of drawing empty figures
if "$PY" -c "import matplotlib, pandas" 2>/dev/null; then
    run_expect 3 plot "$EXE" plot "$WORK/f.h5" --out "$WORK/f_plots"
    expect_in plot.err "every realization of '$WORK/f.h5' failed (2 of 2; the first: "
    expect_in plot.err "nothing to draw"
    [ ! -e "$WORK/f_plots" ] || fail "campaign plot made $WORK/f_plots for a store with nothing to draw"
fi
run_expect 3 second "$EXE" run "$DATA/failing.toml" --store "$WORK/f.h5" --progress-interval 0
expect_in second.err "2 stored (2 failed), 0 to run"
"$PY" - "$WORK/f.h5" <<'PY' || fail "failed results in the HDF5 file"
import h5py, sys
f = h5py.File(sys.argv[1], "r")
st = h5py.check_enum_dtype(f["realizations/status"].dtype)
assert list(f["realizations/status"][:]) == [st["failed"]] * 2
assert all("overlap" in m for m in f["realizations/message"].asstr()[:])
ts = h5py.check_enum_dtype(f["tasks/state"].dtype)
assert list(f["tasks/state"][:]) == [ts["failed"]] * 2
PY
echo "ok"
