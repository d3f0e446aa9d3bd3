"""Checks `campaign analyze --json` against the raw realizations of the store (h5py).

usage: check_analysis.py ANALYZE.json STORE.h5

- the output is one JSON object with every key docs/statistics.md lists (no NaN: json.load with
  parse_constant rejecting NaN/Infinity);
- per point: realizations, status counts, jams, shakes, survival intervals, total observed time,
  tau = T / r, the algebraic mean, empty-time mean and standard deviation, discharge-rate mean
  and standard error, all recomputed from /realizations and /ragged;
- a point without jams has tau_mle null with tau_mle_reason "no jams" (and the same for the CI);
- /analysis/points agrees with the JSON; every /analysis dataset has units and a description.
"""
import json
import math
import sys

import h5py
import numpy as np


def check(cond, what):
    if not cond:
        sys.exit("check_analysis.py: " + what)


def close(a, b, what, rel=1e-9):
    check(a is not None and b is not None and abs(a - b) <= rel * max(abs(a), abs(b), 1e-300),
          "%s: %r != %r" % (what, a, b))


def no_nan(name):
    raise ValueError("JSON holds " + name)


path_json, path_store = sys.argv[1:3]
with open(path_json) as fh:
    a = json.load(fh, parse_constant=no_nan)

for k in ["points", "beverloo", "jam_rate_fits", "rho_b_source", "d_definition"]:
    check(k in a, "top-level key " + k)
point_keys = ["D_cm", "theta_deg", "realizations", "n_jams", "mean_survival", "tau_mle",
              "tau_ci95", "total_observed_time", "n_uncensored", "gof_p", "r2_log_survival",
              "empty_time_mean", "empty_time_std", "discharge_rate", "discharge_rate_err",
              "status_counts", "n_shakes", "jam_time_dependence"]
for p in a["points"]:
    for k in point_keys:
        check(k in p, "point %s lacks %s" % (p.get("label"), k))
        if p[k] is None:
            check(isinstance(p.get(k + "_reason"), str) and p[k + "_reason"],
                  "point %s: %s is null without a reason" % (p["label"], k))
for b in a["beverloo"]:
    for k in ["theta_deg", "C", "C_err", "k", "k_err", "n_points"]:
        check(k in b, "beverloo lacks " + k)
        if b[k] is None:
            check(b.get(k + "_reason"), "beverloo %s null without a reason" % k)
for j in a["jam_rate_fits"]:
    for k in ["theta_deg", "n_points", "exponential", "power_law", "preferred", "decision"]:
        check(k in j, "jam_rate_fits lacks " + k)

f = h5py.File(path_store, "r")
r = f["realizations"]
labels = list(f["points/label"].asstr()[:])
status_names = {v: k for k, v in h5py.check_enum_dtype(r["status"].dtype).items()}
check([p["label"] for p in a["points"]] == labels, "points in /points order")
no_jam_points = 0
for i, p in enumerate(a["points"]):
    rows = [k for k in range(r["point"].shape[0]) if r["point"][k] == i]
    check(p["realizations"] == len(rows), "%s realizations" % labels[i])
    counts = {"complete": 0, "failed": 0, "arrested": 0, "time_limit": 0}
    t, cens, empty, rate = [], [], [], []
    jams = shakes = 0
    for k in rows:
        st = status_names[r["status"][k]]
        counts[st] += 1
        if st == "failed":
            continue
        jams += int(r["n_jams"][k])
        shakes += int(r["n_shakes"][k])
        s, n = r["survival_start"][k], r["survival_length"][k]
        t += list(f["ragged/survival_times"][s:s + n])
        cens += list(f["ragged/censored"][s:s + n])
        if r["has_empty_time"][k]:
            empty.append(r["empty_time"][k])
        if r["has_discharge_rate"][k]:
            rate.append(r["discharge_rate"][k])
    check(p["status_counts"] == counts, "%s status counts %s" % (labels[i], p["status_counts"]))
    check(p["n_jams"] == jams and p["n_shakes"] == shakes, "%s jams/shakes" % labels[i])
    r_unc = int(np.sum(~np.array(cens, dtype=bool)))
    check(p["n_uncensored"] == r_unc, "%s uncensored %d vs %d" % (labels[i], p["n_uncensored"], r_unc))
    check(r_unc == jams, "%s: every jam ends one interval" % labels[i])
    T = float(np.sum(t))
    close(p["total_observed_time"], T, labels[i] + " total observed time")
    close(p["mean_survival"], T / len(t), labels[i] + " algebraic mean")
    if jams > 0:
        close(p["tau_mle"], T / jams, labels[i] + " tau = T / jams")
        lo, hi = p["tau_ci95"]
        check(lo < p["tau_mle"] < hi, labels[i] + " CI brackets tau")
    else:
        no_jam_points += 1
        check(p["tau_mle"] is None and p["tau_mle_reason"] == "no jams", labels[i] + " no jams")
        check(p["tau_ci95"] is None and p["tau_ci95_reason"] == "no jams", labels[i] + " CI")
        check(p["tau_lower_bound95"] > 0, labels[i] + " lower bound")
    close(p["empty_time_mean"], float(np.mean(empty)), labels[i] + " empty mean")
    close(p["empty_time_std"], float(np.std(empty, ddof=1)), labels[i] + " empty std", 1e-7)
    close(p["discharge_rate"], float(np.mean(rate)), labels[i] + " rate mean")
    close(p["discharge_rate_err"], float(np.std(rate, ddof=1) / math.sqrt(len(rate))),
          labels[i] + " rate s.e.", 1e-7)
    if p["gof_p"] is not None:
        check(0 < p["gof_p"] <= 1, labels[i] + " gof p")
check(no_jam_points >= 1, "mini.toml's largest outlet should have no jams (the null case)")

ap = f["analysis/points"]
check(list(ap["label"].asstr()[:]) == labels, "/analysis/points/label")
for i, p in enumerate(a["points"]):
    if p["tau_mle"] is None:
        check(not ap["has_tau_mle"][i] and ap["tau_mle"][i] == 0, "/analysis tau null")
    else:
        close(float(ap["tau_mle"][i]), p["tau_mle"], "/analysis tau")
check(json.loads(f["analysis"].attrs["json"])["points"][0]["label"] == labels[0], "json attribute")
names = []
f["analysis"].visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
for n in names:
    d = f["analysis/" + n]
    check("description" in d.attrs, n + " description")
    check("units" in d.attrs or d.dtype.kind in "OS", n + " units")
    if d.dtype.kind == "f":
        check(np.all(np.isfinite(d[:])), n + " NaN")
print("check_analysis.py: ok (%d points, %d with no jams)" % (len(labels), no_jam_points))
