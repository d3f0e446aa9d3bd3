"""Reads a finished campaign store with h5py and checks what docs/store.md (the HDF5 layout) promises.

usage: check_store.py STORE.h5 CAMPAIGN_EXE SWEEP.toml

- root attributes (format, version, consistent, physics hash, campaign), every group present;
- every dataset carries `units` and `description` attributes; no NaN or infinity anywhere;
- /realizations columns all have one row per stored realization; ragged indices tile /ragged;
- /tasks agrees with /realizations; /points and /runs are filled;
- one realization equals `campaign simulate` of the same point and seed, field by field.
"""
import json
import subprocess
import sys

import h5py
import numpy as np

path, exe, sweep = sys.argv[1:4]
f = h5py.File(path, "r")


def check(cond, what):
    if not cond:
        sys.exit("check_store.py: " + what)


a = f.attrs
check(a["format"] == "hopper campaign store", "format attribute")
check(a["format_version"] == 1, "format_version")
check(a["consistent"] == 1, "consistent")
check(len(a["physics_hash"]) == 16, "physics_hash")
check(a["campaign_name"] == "mini", "campaign_name")
for g in ["realizations", "realizations/diagnostics", "ragged", "points", "tasks", "runs", "failures"]:
    check(isinstance(f.get(g), h5py.Group), "group /" + g)

datasets = []
f.visititems(lambda name, obj: datasets.append(name) if isinstance(obj, h5py.Dataset) else None)
check(len(datasets) > 60, "%d datasets" % len(datasets))
for name in datasets:
    d = f[name]
    check("description" in d.attrs, name + " has no description")
    check("units" in d.attrs or d.dtype.kind in "OS", name + " has no units")
    if d.dtype.kind == "f":
        check(np.all(np.isfinite(d[:])), name + " holds NaN or infinity")

rows = f["realizations/point"].shape[0]
check(rows == 12, "%d rows" % rows)
for name in list(f["realizations"]) + ["diagnostics/" + n for n in f["realizations/diagnostics"]]:
    obj = f["realizations/" + name]
    if isinstance(obj, h5py.Dataset):
        check(obj.shape == (rows,), "/realizations/%s has shape %s" % (name, obj.shape))

families = {"survival": ["survival_times", "censored"], "jam": ["jam_onsets", "shakes_per_jam"],
            "exit": ["exit_times"], "curve": ["curve_time", "curve_in_hopper"],
            "event": ["event_kind", "event_time", "event_sim_time", "event_in_hopper"]}
for fam, names in families.items():
    start = f["realizations/%s_start" % fam][:]
    length = f["realizations/%s_length" % fam][:]
    check(start[0] == 0 and np.all(start[1:] == (start + length)[:-1]), fam + " indices do not tile")
    for n in names:
        check(f["ragged/" + n].shape[0] == start[-1] + length[-1], n + " length")

check(f["ragged/censored"].dtype == np.bool_, "censored reads as numpy bool")
status = h5py.check_enum_dtype(f["realizations/status"].dtype)
check(status == {"complete": 0, "arrested": 1, "time_limit": 2, "failed": 3}, "status enum")
state = h5py.check_enum_dtype(f["tasks/state"].dtype)
check(np.all(f["tasks/state"][:] == state["done"]), "every task done")
check(sorted(f["tasks/row"][:]) == list(range(rows)), "tasks/row")
check(f["points/label"].shape == (3,), "points")
check(f["runs/sweep_text"].asstr()[0].startswith("# mini.toml"), "sweep text kept")
check(f["runs/end_reason"].asstr()[-1] == "complete", "run end reason")

# One realization against `campaign simulate` of the same point and seed.
row = int(np.argmax(f["realizations/n_jams"][:]))  # one with jams, if any
point = f["realizations/point"][row]
label = f["points/label"].asstr()[point]
seed = int(f["realizations/seed"][row])
D, theta = f["points/D_cm"][point], f["points/theta_deg"][point]
out = subprocess.run([exe, "simulate", sweep, "--D", repr(D), "--theta", repr(theta), "--seed",
                      str(seed), "--json"], capture_output=True, text=True, check=True).stdout
sim = json.loads(out)
s, l = f["realizations/survival_start"][row], f["realizations/survival_length"][row]
check(sim["survival_times"] == f["ragged/survival_times"][s:s + l].tolist(), "survival_times")
check(sim["censored"] == f["ragged/censored"][s:s + l].tolist(), "censored")
check(sim["n_jams"] == f["realizations/n_jams"][row], "n_jams")
check(sim["particles"] == f["realizations/particles"][row], "particles")
has_empty = bool(f["realizations/has_empty_time"][row])
check((sim["empty_time"] is None) == (not has_empty), "has_empty_time")
if has_empty:
    check(sim["empty_time"] == f["realizations/empty_time"][row], "empty_time")
s, l = f["realizations/curve_start"][row], f["realizations/curve_length"][row]
check(sim["discharge_curve"]["in_hopper"] == f["ragged/curve_in_hopper"][s:s + l].tolist(), "curve")
s, l = f["realizations/event_start"][row], f["realizations/event_length"][row]
kinds = {v: k for k, v in h5py.check_enum_dtype(f["ragged/event_kind"].dtype).items()}
check([e["kind"] for e in sim["events"]] == [kinds[k] for k in f["ragged/event_kind"][s:s + l]], "events")
check(sim["diagnostics"]["steps"] == f["realizations/diagnostics/steps"][row], "steps")
print("check_store.py: ok (%d realizations, %d datasets; '%s' seed %d matches simulate)" % (rows, len(datasets), label, seed))
