#!/bin/bash
# `campaign simulate --store S --point LABEL --realization I` runs a stored realization again:
# on mini_fields.toml (a material setting in every label), every realization of two points is
# re-run; each must report "identical to the stored realization", and its JSON survival times,
# exit times and seed must equal the stored ones read independently with h5py. Bad labels and
# indices exit 2 with the list of points or the range; --point with --D is refused.
source "$(dirname "$0")/lib.sh"
run_expect 0 run "$EXE" run "$DATA/mini_fields.toml" --store "$WORK/s.h5" --progress-interval 0
for label in "D_cm=1.9 theta_deg=45 material.mu=0.5" "D_cm=2.6 theta_deg=60 material.mu=0.5"; do
    for i in 0 1; do
        run_expect 0 re "$EXE" simulate --store "$WORK/s.h5" --point "$label" --realization $i --json
        expect_in re.err "identical to the stored realization"
        "$PY" - "$WORK/s.h5" "$label" $i re.out <<'PYEOF' || fail "JSON of '$label' #$i differs from the store"
import json, sys
import h5py
import numpy as np
f = h5py.File(sys.argv[1], "r")
label, i, d = sys.argv[2], int(sys.argv[3]), json.load(open(sys.argv[4]))
point = list(f["points/label"].asstr()[:]).index(label)
r = f["realizations"]
row = [k for k in range(r["point"].shape[0]) if r["point"][k] == point and r["realization"][k] == i][0]
def ragged(fam, name):
    s, n = r[fam + "_start"][row], r[fam + "_length"][row]
    return f["ragged/" + name][s:s + n]
assert d["seed"] == int(r["seed"][row]), (d["seed"], r["seed"][row])
assert np.array_equal(np.array(d["survival_times"]), ragged("survival", "survival_times"))
assert np.array_equal(np.array(d["exit_times"]), ragged("exit", "exit_times"))
PYEOF
    done
done
run_expect 2 badlabel "$EXE" simulate --store "$WORK/s.h5" --point "D_cm=1.9" --realization 0
expect_in badlabel.err "no point 'D_cm=1.9'"
expect_in badlabel.err "'D_cm=1.9 theta_deg=45 material.mu=0.5'"
run_expect 2 badindex "$EXE" simulate --store "$WORK/s.h5" --point "D_cm=1.9 theta_deg=45 material.mu=0.5" --realization 2
expect_in badindex.err "has realizations 0..1"
run_expect 2 both "$EXE" simulate --store "$WORK/s.h5" --point "D_cm=1.9 theta_deg=45 material.mu=0.5" --realization 0 --D 3
expect_in both.err "cannot be given with --point"
run_expect 2 nopoint "$EXE" simulate "$MINI" --D 3 --theta 60 --seed 1 --realization 0
expect_in nopoint.err "needs --point"
echo "rerun.sh: passed"
