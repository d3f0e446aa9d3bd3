#!/usr/bin/python3
"""analysis/hopper_store.py against a real store (mini_fields.toml, run by store.sh): every table
agrees with the raw datasets read with h5py and with the C++ analysis (/analysis/points), the
settings come typed from /points/parameters (and agree with the scene text), and the export
writes the same rows.
usage: test_hopper_store.py SOURCE_DIR STORE.h5 CSV_DIR"""
import math
import pathlib
import sys

import h5py
import numpy as np
import pandas as pd

src, store_path, csv_dir = pathlib.Path(sys.argv[1]), sys.argv[2], pathlib.Path(sys.argv[3])
sys.path.insert(0, str(src / "analysis"))
from hopper_store import open_store  # noqa: E402

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL: " + what)


f = h5py.File(store_path, "r")
with open_store(store_path) as s:
    p = s.points
    # settings typed, from /points/parameters
    check(p["material.mu"].dtype == np.float64 and (p["material.mu"] == 0.5).all(),
          "material.mu is float 0.5: %s" % p["material.mu"].tolist())
    check(p["particles.count"].dtype == np.int64 and (p["particles.count"] == 100).all(),
          "particles.count is int 100")
    check((p["integrator.scheme"] == "gear4").all(), "integrator.scheme is the string gear4")
    check(np.allclose(p["hopper.outlet_m"] * 100, p["D_cm"]), "outlet_m = D_cm / 100")
    check(np.allclose(np.degrees(p["hopper.theta_rad"]), p["theta_deg"]), "theta_rad = theta_deg")
    check(list(p["label"]) == list(f["points/label"].asstr()[:]), "labels in /points order")
    check(s.varied == ["hopper.outlet_m", "hopper.theta_rad"], "varied: %s" % s.varied)
    # the typed /points/parameters (issue 28): every line of each point's scene text (the
    # fingerprint) has its member with the same value; the units are attributes, in SI
    from hopper_store import parse_scene  # noqa: E402
    rec = f["points/parameters"]
    units = dict(zip(rec.dtype.names, [str(u) for u in rec.attrs["units"]]))
    check(units["hopper.outlet_m"] == "m" and units["hopper.theta_rad"] == "rad"
          and units["particles.density_kg_m3"] == "kg/m^3" and units["protocol.max_time_s"] == "s",
          "units attributes: %r" % {k: units[k] for k in ("hopper.outlet_m", "hopper.theta_rad")})
    sweep = dict(zip(rec.dtype.names, [str(u) for u in rec.attrs["sweep_name"]]))
    check(sweep["hopper.outlet_m"] == "D_cm" and sweep["material.mu"] == "material.mu",
          "sweep_name attributes")
    check(bool(rec["typed"][:].all()), "every point typed")
    for i, text in enumerate(f["points/scene"].asstr()[:]):
        for name, v in parse_scene(text).items():
            got = p.at[i, name]
            same = (isinstance(v, str) and got == v) or (v is None and pd.isna(got)) or \
                (v is not None and not isinstance(v, str) and float(got) == float(v))
            check(same, "point %d: %s = %r in the scene text, %r typed" % (i, name, v, got))
    check("has_protocol.t_check_s" in rec.dtype.names and p["protocol.t_check_s"].isna().all(),
          "an unset optional: a has_ flag in the file, NaN in pandas")
    check(list(s.groups()) == ["\u03b8 = 45\u00b0", "\u03b8 = 60\u00b0"],
          "groups: %s" % list(s.groups()))

    r = s.realizations
    raw = f["realizations"]
    check(len(r) == raw["point"].shape[0] == 12, "12 realizations, got %d" % len(r))
    has_empty = raw["has_empty_time"][:].astype(bool)
    check(np.array_equal(r["empty_time"].notna().to_numpy(), has_empty),
          "empty_time is NaN exactly where has_empty_time is FALSE")
    check(set(r["status"]) <= {"complete", "arrested", "time_limit", "failed"}, "status names")
    check(np.array_equal(r["seed"].to_numpy(), raw["seed"][:]), "seeds")
    # settings as the sweep file wrote them (D_cm = [1.9, 2.6, 3.5], theta_deg = [45, 60]), in
    # the store itself and in what reads it; not 59.99999999999999
    check(sorted(set(f["points/theta_deg"][:])) == [45.0, 60.0],
          "/points/theta_deg as written: %r" % sorted(set(f["points/theta_deg"][:])))
    check(sorted(set(f["points/D_cm"][:])) == [1.9, 2.6, 3.5],
          "/points/D_cm as written: %r" % sorted(set(f["points/D_cm"][:])))
    check(len(p.query("theta_deg == 60")) == 3 and len(r.query("theta_deg == 60")) == 6,
          "query('theta_deg == 60'): %r" % sorted(set(p["theta_deg"])))
    check(sorted(set(p["D_cm"])) == [1.9, 2.6, 3.5], "D_cm as written: %r" % sorted(set(p["D_cm"])))
    # the seed also as text that no reader takes for a number (R's read.csv makes a double of
    # 15669779132130233510)
    check(list(r["seed_str"]) == ["s%d" % v for v in raw["seed"][:]], "seed_str")

    sv = s.survival
    lengths = sv.groupby("row").size().reindex(range(len(r)), fill_value=0).to_numpy()
    check(np.array_equal(lengths, raw["survival_length"][:]), "intervals per realization")
    check(set(sv["event"]) <= {0, 1} and sv["duration"].ge(0).all(), "event 0/1, duration >= 0")
    a = s.analysis
    check(np.array_equal(sv["duration"], sv["duration_stored"]), "no zero durations here")
    for i in p.index:
        one = sv[sv["point"] == i]
        T, n = float(one["duration_stored"].sum()), int(one["event"].sum())
        check(math.isclose(T, a.at[i, "total_observed_time"], rel_tol=1e-12),
              "point %d: total time %g vs analysis %g" % (i, T, a.at[i, "total_observed_time"]))
        check(n == a.at[i, "n_jams"], "point %d: jams %d vs analysis %d" % (i, n, a.at[i, "n_jams"]))
        if n:
            check(math.isclose(T / n, a.at[i, "tau_mle"], rel_tol=1e-12), "point %d: tau" % i)
        else:
            check(math.isnan(a.at[i, "tau_mle"]), "point %d: tau NaN without jams" % i)
    # every realization ends with a censored interval unless it was arrested
    last = sv.groupby("row").tail(1)
    arrested = r["status"].to_numpy()[last["row"].to_numpy()] == "arrested"
    check((last["event"].to_numpy()[~arrested] == 0).all(), "last interval censored")

    for name, family in (("events", "event"), ("curves", "curve"), ("jams", "jam"),
                         ("exits", "exit")):
        df = getattr(s, name)
        check(len(df) == int(raw[family + "_length"][:].sum()), "%s: every value" % name)
    check(int(s.jams.groupby("row").size().sum()) == int(raw["n_jams"][:].sum()), "jams = n_jams")
    check(set(s.events["kind"]) >= {"opened"}, "event kinds by name")
    # every array of the jam family, a later member (arch_heights, since 5) by its own name
    jams = s.jams
    check(list(jams.columns[6:]) == ["onset", "shakes", "arch_heights"],
          "jams columns: %s" % list(jams.columns))
    check(f["ragged/arch_heights"].attrs["family"] == "jam" and
          int(f["ragged/arch_heights"].attrs["since"]) == 5, "arch_heights' family and since")
    check(np.array_equal(jams["arch_heights"].to_numpy(), f["ragged/arch_heights"][:]),
          "arch_heights as stored")
    check(len(jams) == 0 or (jams["arch_heights"] >= 0).all(), "arch heights >= 0")

    fields = s.fields()
    check(len(fields) == 6, "fields of 6 points, got %d" % len(fields))
    label = p["label"][0]
    ds = fields[label]
    g = f["analysis/fields"][label.replace("/", "_")]
    raw_speed, win = g["mean_speed"][:], g["windows"][:]
    ours = ds["mean_speed"].values
    check(ds["mean_speed"].dims == ("y", "x") and ours.shape == raw_speed.shape, "field shape")
    check(np.array_equal(ours[win > 0], raw_speed[win > 0]) and np.isnan(ours[win == 0]).all(),
          "mean_speed equal where windows > 0, NaN elsewhere")
    check(math.isclose(float(ds.x[0]), float(g.attrs["x0"]) + 0.5 * float(g.attrs["cell"])),
          "x is the cell centre")

    # a row whose result is older than a member holds padding there: NaN, not 0
    import shutil, tempfile
    with tempfile.TemporaryDirectory() as tmp:
        old_copy = pathlib.Path(tmp) / "older.h5"
        shutil.copy(store_path, old_copy)
        with h5py.File(old_copy, "r+") as g:
            v = g["realizations/result_version"]
            jammed = np.flatnonzero(g["realizations/jam_length"][:] > 0)
            if len(jammed):
                v[jammed[0]] = 4
        with open_store(old_copy) as older:
            oj = older.jams
            if len(jammed):
                rows = oj["row"].to_numpy() == jammed[0]
                check(np.isnan(oj["arch_heights"].to_numpy()[rows]).all() and
                      not np.isnan(oj["arch_heights"].to_numpy()[~rows]).any(),
                      "arch_heights NaN in the row of a version-4 result only")
            else:
                check(False, "the store has no jam to test older rows with")

    # the export wrote the same rows
    for name in ("points", "realizations", "survival", "events", "curves", "jams", "exits",
                 "arches", "analysis", "beverloo", "jam_rate", "km", "avalanche", "fields"):
        path = csv_dir / (name + ".csv")
        check(path.exists(), "export wrote %s" % path.name)
    # every table the reader has is exported (issue 43, item 5: arches and avalanche were not)
    if (csv_dir / "arches.csv").exists():
        back = pd.read_csv(csv_dir / "arches.csv")
        ar = s.arches
        check(len(back) == len(ar) > 0 and list(back.columns) == list(ar.columns),
              "arches.csv: %d rows, columns %s" % (len(back), list(back.columns)))
        check([[int(v) for v in str(t).split()] for t in back["ids"]] ==
              [[int(v) for v in ids] for ids in ar["ids"]], "arches.csv ids round trip")
        check(all(np.array_equal(np.array(str(t).split(), float), x)
                  for t, x in zip(back["x"], ar["x"])), "arches.csv x round trip, exact")
    if (csv_dir / "avalanche.csv").exists():
        back = pd.read_csv(csv_dir / "avalanche.csv")
        check(len(back) == len(s.avalanche) == 2, "avalanche.csv: one row per wall angle")
    if (csv_dir / "realizations.csv").exists():
        back = pd.read_csv(csv_dir / "realizations.csv")
        check(back["theta_deg"].isin([45.0, 60.0]).all(), "realizations.csv theta_deg: %r"
              % sorted(set(back["theta_deg"])))
        # a reader that types columns by whether every value parses as a number (R's
        # type.convert, pandas) keeps seed_str as text, exactly
        check(back["seed_str"].dtype == object and
              [int(t[1:]) for t in back["seed_str"]] == [int(v) for v in raw["seed"][:]],
              "realizations.csv seed_str round trip")
        for t in back["seed_str"]:
            try:
                float(t)
                check(False, "seed_str %r reads as a number" % t)
            except ValueError:
                pass
    if (csv_dir / "survival.csv").exists():
        back = pd.read_csv(csv_dir / "survival.csv")
        check(len(back) == len(sv) and np.allclose(back["duration"], sv["duration"], rtol=0,
                                                   atol=1e-15), "survival.csv round trip")

# A jam at the opening (issue 43, item 1): the store holds an interval of 0.0 with event 1, which
# R's survreg refuses ("Invalid survival times for this distribution") and so do lifelines'
# parametric fitters. A copy of the store with one such interval: the survival table and
# survival.csv hold it as half the detector interval (duration_stored keeps 0.0), nothing is
# dropped, and R's survreg (when R and its survival package are installed) or the same check in
# Python accepts every CSV the export writes.
import shutil  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402

with tempfile.TemporaryDirectory() as tmp:
    tmp = pathlib.Path(tmp)
    copy = tmp / "zero.h5"  # the HDF5 file alone: no journal, so it is read as it stands
    shutil.copy(store_path, copy)
    with h5py.File(copy, "r+") as g:
        r = g["realizations"]
        k = int(r["survival_start"][0])  # realization row 0's first interval
        cens = h5py.check_enum_dtype(g["ragged/censored"].dtype)
        g["ragged/censored"][k] = cens["FALSE"] if cens else 0
        g["ragged/survival_times"][k] = 0.0
    with open_store(copy) as z:
        zs = z.survival
        zero = zs[(zs["row"] == 0) & (zs["interval"] == 0)]
        check(len(zs) == len(sv), "no interval dropped: %d of %d" % (len(zs), len(sv)))
        check(len(zero) == 1 and zero["duration_stored"].iloc[0] == 0.0
              and zero["event"].iloc[0] == 1, "the zero interval is there: %s" % zero.to_dict())
        check(len(zero) == 1 and zero["duration"].iloc[0] == 5e-5,
              "its duration is half the detector interval (5e-5 s): %s" % zero["duration"].tolist())
        check((zs["duration"] > 0).all(), "every duration > 0")
    out = tmp / "csv"
    done = subprocess.run([sys.executable, str(src / "analysis" / "export.py"), str(copy),
                           "--csv", str(out)], capture_output=True, text=True)
    check(done.returncode == 0, "export of the copy: %s" % done.stderr)
    for csv in sorted(out.glob("*.csv")) if out.exists() else []:
        t = pd.read_csv(csv)
        if not {"duration", "event"} <= set(t.columns):
            continue
        rscript = shutil.which("Rscript")
        has_survival = rscript and subprocess.run(
            [rscript, "-e", "library(survival)"], capture_output=True).returncode == 0
        if has_survival:
            fit = subprocess.run([rscript, "-e", "library(survival); d <- read.csv('%s'); "
                                  "f <- survreg(Surv(duration, event) ~ 1, data = d, "
                                  "dist = 'exponential'); cat(exp(coef(f)))" % csv],
                                 capture_output=True, text=True)
            check(fit.returncode == 0, "R survreg on %s: %s" % (csv.name, fit.stderr.strip()))
        else:
            # survreg's own test for the exponential (survreg.fit: "Invalid survival times for
            # this distribution" when any time <= 0) and lifelines' (positive durations), then
            # the censored exponential's maximum-likelihood mean
            check((t["duration"] > 0).all() and t["event"].isin([0, 1]).all(),
                  "%s: survreg's check, every duration > 0 (R is not installed)" % csv.name)
            tau = t["duration"].sum() / t["event"].sum()
            check(np.isfinite(tau) and tau > 0, "%s: exponential fit tau %r" % (csv.name, tau))
        print("survreg-ready: %s (%s)" % (csv.name, "R" if has_survival else "Python check"))

# open_store() of a store that is not in step (as during a run) reads a snapshot (issue 43, item
# 10): it says so, holds what was stored, and its temporary directory goes without a
# ResourceWarning when the Store is dropped unclosed, and at once on close()
import gc  # noqa: E402
import warnings  # noqa: E402

with tempfile.TemporaryDirectory() as tmp:
    copy = pathlib.Path(tmp) / "busy.h5"
    shutil.copy(store_path, copy)
    shutil.copy(store_path + ".journal", str(copy) + ".journal")
    with h5py.File(copy, "r+") as g:
        g.attrs["consistent"] = 0  # what a killed or running writer leaves
    import hopper_store  # noqa: E402
    check("snapshot" in (hopper_store.open_store.__doc__ or ""),
          "open_store's docstring says it reads a snapshot")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        z = open_store(copy)
        view = pathlib.Path(z._f.filename).parent
        check(z.snapshot and view.is_dir() and len(z.realizations) == 12,
              "a snapshot with 12 realizations in %s" % view)
        del z
        gc.collect()
        check(not view.exists(), "the dropped snapshot's directory %s is removed" % view)
        z = open_store(copy)
        view = pathlib.Path(z._f.filename).parent
        z.close()
        check(not view.exists() and z.snapshot, "close() removes the snapshot's directory")
        del z
        gc.collect()
    warned = [str(w.message) for w in seen if issubclass(w.category, ResourceWarning)]
    check(not warned, "ResourceWarning: %s" % warned)
    with open_store(store_path) as plain:
        check(not plain.snapshot, "a store in step is read as it stands")

print("%d failures" % len(failures))
sys.exit(1 if failures else 0)
