#!/usr/bin/python3
"""Tables of issue 23 (docs/clogging.md): arrests and the growing shakes, the head scan, the lid.

usage:
  clogging.py arrests STORE.h5 [--json OUT]
      realizations by status, and tau and jams per realization for all realizations, for those
      in which every jam cleared at the first shake (no grown shake) and for the others
  clogging.py levels PUBLISHED.h5 [--bins 0,300,700,...] [--json OUT]
      the published protocol's tau by fill level: per bin of particles in the hopper, the
      flowing time spent there (discharge curve) and the jams whose onset fell there; what a
      steady state of that many particles is to be compared with
  clogging.py question STORE.h5 [--json OUT] [--md OUT] [--png OUT]
      the open question's table (campaigns/open-question/survival.toml): per outlet D, the
      realizations, flowing time, jams, tau [95 % CI] (a 95 % lower bound where no jam),
      <s> +- se, tau's relative 95 % half-width against the campaign's +-10 %, and the worker
      core-hours (per point and per jam); then the store's own fits of the jam rate and of <s>
      versus D (`campaign analyze`: exponential against power law, the AIC verdict)
  clogging.py plan STORE.h5 [--outlets 3.6,...] [--fit poisson|store] [--dc CM] [--core-s-per-flow-s X]
                  [--power 0.95]
                  [--json OUT] [--md OUT]
      what would decide the open question: with the store's two fitted laws of the jam rate
      (exponential and power law; the Poisson fit over every outlet, or with --fit store
      `campaign analyze`'s) taken as they are, for each outlet D the
      flowing time after which one outlet's jam count favours the true law by an AIC margin of
      2 with the given probability under either law, the jams each law expects there, the
      core-hours at the store's measured cost per flowing second, and what the store already
      holds there (default outlets: the ten beyond the largest one with a jam)
  clogging.py published STORE.h5 [STORE.h5 ...] [--json OUT] [--md OUT]
      the jam rate per flowing second of each point at theta = 45 deg and a published outlet
      (D = 2.7-3.5 cm) against the published study's (its Table 3's jams over 40 fills of its
      mean empty time; issue 39, part 5): jams, flowing time, rate, the published rate, their
      ratio, the jams the published rate expects in that flowing time and the two-sided Poisson
      p of the count; then per store the combined test (Poisson deviance against chi-square with
      one degree of freedom per outlet)
  clogging.py heads PUBLISHED.h5 STEADY.h5 [--ns-per-particle-step LABEL=NS ...] [--json OUT]
      per point of both stores: jams, tau [95 % CI], <s> +- se, particle-steps per jam (the
      work, independent of the machine's load) and, where a point's CPU cost per particle-step
      is given, core-seconds per jam; each steady-state point against the published protocol
      (z = difference over the combined standard error)
  clogging.py heads - STEADY.h5 --reference TAU,TAU_SE,S,S_SE,JAMS [...]
      the same against a published side given as numbers (docs/clogging.md quotes them) when its
      store is not at hand
  clogging.py heads REF.h5 STEADY.h5 --reference-point LABEL_PART [...]
      the same against the one point of REF.h5 whose label contains LABEL_PART; with the same
      store twice, its other points against that one (the lid against the 1500-disk head at
      D = 3.1 cm: campaigns/open-question/lid-scan-3.1.toml)
  clogging.py lid-stress STORE.h5 [--half-width 0.03] [--height 0.05] [--json OUT]
      per point of a store with fields: the mean coarse-grained pressure (units of m g) in the
      cells within the half-width (m) of the axis and between the outlet and the height (m)
      above it, with the discharge rate and the jams: the stress a lid must restore (issue 40;
      campaigns/open-question/lid-stress.toml)

Both read a store with analysis/hopper_store.py (h5py). tau is the censored exponential MLE
(total observed time over jams) with the chi-square 95 % interval, as `campaign analyze`
(docs/statistics.md); <s> likewise over the avalanche sizes of the survival intervals.
"""
import argparse
import json
import math
import os
import sys

import numpy as np
from scipy import stats

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hopper_store import open_store  # noqa: E402


def censored_mean(values, events):
    """Censored exponential MLE: sum / events, chi-square 95 % interval, se = mean/sqrt(k)."""
    values = np.asarray(values, float)
    k = int(np.sum(events))
    total = float(np.sum(values))
    if k == 0:
        # No event: only a lower bound (95 %): total / (chi2_{0.95}(2) / 2).
        return {"jams": 0, "total": total, "mean": None, "lo": total / (stats.chi2.ppf(0.95, 2) / 2),
                "hi": None, "se": None}
    mean = total / k
    lo = 2 * total / stats.chi2.ppf(0.975, 2 * k)
    hi = 2 * total / stats.chi2.ppf(0.025, 2 * k)
    return {"jams": k, "total": total, "mean": mean, "lo": lo, "hi": hi, "se": mean / math.sqrt(k)}


def z_of(a, b):
    if a["mean"] is None or b["mean"] is None:
        return None
    return (a["mean"] - b["mean"]) / math.hypot(a["se"], b["se"])


def sig(x, digits=3):
    """x to `digits` significant digits, like %g but without an exponent between 1e-3 and 1e7
    (1200, not 1.2e+03; 140 000 reads 140000)."""
    if x == 0 or not math.isfinite(x) or not 1e-3 <= abs(x) < 1e7:
        return "%.*g" % (digits, x)
    dec = digits - 1 - math.floor(math.log10(abs(x)))
    if abs(round(x, dec)) >= 10 ** (digits - dec):  # rounding carried into the next decade
        dec -= 1
    text = "%.*f" % (max(dec, 0), round(x, dec))
    return text.rstrip("0").rstrip(".") if "." in text else text


def fmt(e, digits=3):
    if e["mean"] is None:
        return "> %s (no jam)" % sig(e["lo"], digits)
    return "%s +- %s [%s, %s]" % (sig(e["mean"], digits), sig(e["se"], 2), sig(e["lo"], digits),
                                  sig(e["hi"], digits))


def particle_steps(store):
    """Particle-steps per realization: wall seconds x 1e9 / ns per particle-step."""
    d = store._f["realizations/diagnostics"]
    wall = np.asarray(d["wall_seconds"][:], float)
    ns = np.asarray(d["ns_per_particle_step"][:], float)
    out = np.where(ns > 0, wall * 1e9 / np.where(ns > 0, ns, 1), 0.0)
    return out


def edge_disks(pt):
    """Right-hand edge disk and the next wall disk up the funnel wall (centres, m) and the wall
    disks' radius, for the default outlet measure (D between the edge disks' surfaces)."""
    th = float(pt["hopper.theta_rad"])
    dw = float(pt["hopper.wall_diameter_m"])
    sp = float(pt.get("hopper.wall_spacing", 1.0))
    off = float(pt["hopper.edge_offset"]) if "hopper.edge_offset" in pt and \
        np.isfinite(pt["hopper.edge_offset"]) else 0.0
    xc = float(pt["hopper.outlet_m"]) / 2 + dw / 2
    e = (xc + off * dw * math.cos(th), off * dw * math.sin(th))
    n = (e[0] + sp * dw * math.cos(th), e[1] + sp * dw * math.sin(th))
    return e, n, dw / 2


def foot_in_groove(x, y, edge, nxt, r_wall, r_max):
    """An arch's end disk at (x, y) touches both the edge disk and the next wall disk (mirrored
    for x < 0), within 0.1 mm of the largest disk's contact distance."""
    sx = 1.0 if x > 0 else -1.0
    reach = r_wall + r_max + 1e-4
    d_e = math.hypot(x - sx * edge[0], y - edge[1])
    d_n = math.hypot(x - sx * nxt[0], y - nxt[1])
    return d_e <= reach and d_n <= reach


def arrest_summary(s, path):
    """The arrest check of an open store (hopper_store.Store): arrests, shakes per jam,
    where the arches rest, tau and jams per realization by group, and tau per interval
    after an ordinary and after a grown shake."""
    r = s.realizations
    surv = s.survival
    jams = s.jams
    arches = s.arches
    pts = s.points
    by_status = r["status"].value_counts().to_dict()
    grown = set()
    for (pt, real), g in jams.groupby(["point", "realization"]):
        if (g["shakes"] > 1).any():
            grown.add((pt, real))
    result = {"store": path, "realizations": int(len(r)), "by_status": by_status,
              "shakes_needed": {int(k): int(v) for k, v in jams["shakes"].value_counts()
                                .sort_index().items()},
              "groups": {}}
    # Where the arches rest: jams whose arch has both end disks in the groove between the
    # edge disk and the next wall disk, by the shakes the jam needed.
    feet = {}
    if len(arches) and len(jams) == len(arches):
        aj = arches.reset_index(drop=True)
        jj = jams.reset_index(drop=True)
        for k in range(len(aj)):
            pt = pts.loc[int(aj.loc[k, "point"])]
            edge, nxt, rw = edge_disks(pt)
            r_max = float(pt["particles.d_large_m"]) / 2
            xs, ys = aj.loc[k, "x"], aj.loc[k, "y"]
            cls = "needed 1 shake" if int(jj.loc[k, "shakes"]) <= 1 else "needed more"
            f = feet.setdefault(cls, {"jams": 0, "arches": 0, "both_feet_in_groove": 0})
            f["jams"] += 1
            if len(xs) >= 1:
                f["arches"] += 1
                if foot_in_groove(xs[0], ys[0], edge, nxt, rw, r_max) and \
                        foot_in_groove(xs[-1], ys[-1], edge, nxt, rw, r_max):
                    f["both_feet_in_groove"] += 1
    result["arch_feet"] = feet
    keys = list(zip(r["point"], r["realization"]))
    for name, keep in (("all", lambda k: True), ("no grown shake", lambda k: k not in grown),
                       ("grown shake", lambda k: k in grown)):
        sel = [k for k in keys if keep(k)]
        if not sel:
            continue
        mask = [(p, q) in set(sel) for p, q in zip(surv["point"], surv["realization"])]
        sv = surv[mask]
        tau = censored_mean(sv["duration"], sv["event"])
        rr = r[[k in set(sel) for k in keys]]
        n = rr["n_jams"].to_numpy(float)
        result["groups"][name] = {
            "realizations": len(sel), "tau": tau,
            "jams_per_realization": float(n.mean()),
            "jams_per_realization_se": float(n.std(ddof=1) / math.sqrt(len(n))) if len(n) > 1
            else None,
            "arrested": int((rr["status"] == "arrested").sum())}
    # The comparison by realization selects: a realization with more jams has more chances
    # to meet one that needs a grown shake, so its group has more jams and shorter intervals
    # even when the shakes change nothing. Per interval instead: the flow that a grown shake
    # restarted against the flow that one ordinary shake restarted (interval k follows jam
    # k - 1; the first interval follows the opening and is in neither).
    jj = jams.copy()
    jj["interval"] = jj.groupby(["point", "realization"]).cumcount() + 1
    after = surv.merge(jj[["point", "realization", "interval", "shakes"]],
                       on=["point", "realization", "interval"], how="inner")
    result["intervals"] = {}
    for name, keep in (("after one shake", after["shakes"] <= 1),
                       ("after a grown shake", after["shakes"] > 1)):
        sv = after[keep]
        if len(sv) and sv["event"].sum() > 0:
            result["intervals"][name] = {"intervals": int(len(sv)),
                                         "tau": censored_mean(sv["duration"], sv["event"])}
    i1, i2 = (result["intervals"].get(k) for k in ("after one shake", "after a grown shake"))
    if i1 and i2:
        result["z_tau_after_shake"] = z_of(i2["tau"], i1["tau"])
    a, b = result["groups"].get("no grown shake"), result["groups"].get("grown shake")
    if a and b:
        result["z_tau"] = z_of(b["tau"], a["tau"])
        if a["jams_per_realization_se"] and b["jams_per_realization_se"]:
            result["z_jams_per_realization"] = (
                (b["jams_per_realization"] - a["jams_per_realization"]) /
                math.hypot(a["jams_per_realization_se"], b["jams_per_realization_se"]))
    return result


def arrests(path, out):
    with open_store(path) as s:
        result = arrest_summary(s, path)
    print("%s: %d realizations, %s" % (path, result["realizations"], result["by_status"]))
    print("shakes needed per jam (count of jams): %s" % result["shakes_needed"])
    print("%-16s %5s %8s %-34s %s" % ("realizations", "n", "arrested", "tau (s) +- se [95% CI]",
                                      "jams per realization +- se"))
    for name, g in result["groups"].items():
        se = g["jams_per_realization_se"]
        print("%-16s %5d %8d %-34s %.3g%s" % (name, g["realizations"], g["arrested"], fmt(g["tau"]),
                                              g["jams_per_realization"],
                                              " +- %.2g" % se if se else ""))
    for cls, f in result["arch_feet"].items():
        print("jams that %s: %d, arches found %d, both end disks in the edge groove %d" % (
            cls, f["jams"], f["arches"], f["both_feet_in_groove"]))
    for name, g in result["intervals"].items():
        print("intervals %-20s %5d  tau %s" % (name, g["intervals"], fmt(g["tau"])))
    for key in ("z_tau", "z_jams_per_realization", "z_tau_after_shake"):
        if result.get(key) is not None:
            print("%s (grown - ordinary) / combined se: %+.2f" % (key, result[key]))
    if out:
        with open(out, "w") as fh:
            json.dump(result, fh, indent=1)


def point_rows(path, ns_by_label):
    rows = []
    with open_store(path) as s:
        r = s.realizations
        surv = s.survival
        ps = particle_steps(s)
        pts = s.points
        for i, pt in pts.iterrows():
            sv = surv[surv["point"] == i]
            rr = r[r["point"] == i]
            tau = censored_mean(sv["duration"], sv["event"])
            sizes = sv["avalanche_size"].to_numpy(float)
            s_mean = censored_mean(sizes, sv["event"])
            steps = float(ps[rr.index.to_numpy()].sum()) if len(rr) else 0.0
            row = {"store": path, "label": pt["label"], "particles": int(pt["particles"]),
                   "realizations": int(len(rr)), "tau": tau, "mean_s": s_mean,
                   "particle_steps": steps,
                   "particle_steps_per_jam": steps / tau["jams"] if tau["jams"] else None,
                   "discharge_rate": (float(rr["discharge_rate"].mean())
                                      if len(rr) and "discharge_rate" in rr else None),
                   "statuses": rr["status"].value_counts().to_dict()}
            ns = ns_by_label.get(pt["label"])
            if ns:
                row["ns_per_particle_step"] = ns
                row["core_seconds"] = steps * ns * 1e-9
                row["core_seconds_per_jam"] = (steps * ns * 1e-9 / tau["jams"]
                                               if tau["jams"] else None)
            rows.append(row)
    return rows


def reference_row(text):
    """A published reference given as numbers, "TAU,TAU_SE,S,S_SE,JAMS" (s, s, grains, grains,
    count): for when the published store is not at hand (docs/clogging.md quotes them)."""
    try:
        tau, tau_se, s_mean, s_se, jams = (float(v) for v in text.split(","))
    except ValueError:
        sys.exit("clogging.py heads: --reference takes TAU,TAU_SE,S,S_SE,JAMS (five numbers), "
                 "got %r" % text)
    if min(tau, tau_se, s_mean, s_se, jams) <= 0:
        sys.exit("clogging.py heads: --reference: every number must be positive, got %r" % text)
    k = int(round(jams))

    def given(mean, se):  # the censored MLE's chi-square interval for k jams
        return {"jams": k, "total": mean * k, "mean": mean, "se": se,
                "lo": 2 * mean * k / stats.chi2.ppf(0.975, 2 * k),
                "hi": 2 * mean * k / stats.chi2.ppf(0.025, 2 * k)}
    return {"store": "--reference", "label": "published (given)", "particles": 0,
            "realizations": 0, "particle_steps_per_jam": None,
            "tau": given(tau, tau_se), "mean_s": given(s_mean, s_se)}


def pick_reference(rows, text):
    """The row whose label is `text`, else the one row whose label contains it (heads
    --reference-point: the reference is a point of a store with several, such as the 1500-disk
    head beside the lid in one store); SystemExit naming the labels when none or several match."""
    hits = [r for r in rows if r["label"] == text] or [r for r in rows if text in r["label"]]
    if len(hits) != 1:
        sys.exit("clogging.py heads: --reference-point %r matches %d points of %s (one is "
                 "needed); its labels: %s" % (text, len(hits), rows[0]["store"] if rows else
                                              "the store", "; ".join(r["label"] for r in rows)))
    return hits[0]


def heads(published, steady, ns_args, out, reference=None, reference_point=None):
    ns_by_label = {}
    for a in ns_args or []:
        label, _, ns = a.rpartition("=")
        ns_by_label[label] = float(ns)
    ref = [reference_row(reference)] if reference else point_rows(published, ns_by_label)
    rows = point_rows(steady, ns_by_label)
    if reference_point is not None and not reference:
        ref = [pick_reference(ref, reference_point)]
        if os.path.realpath(published) == os.path.realpath(steady):  # the others against it
            rows = [r for r in rows if r["label"] != ref[0]["label"]]
    if len(ref) != 1:
        sys.exit("clogging.py heads: the published store must hold one point, it has %d "
                 "(--reference-point LABEL_PART chooses one)" % len(ref))
    ref = ref[0]
    for row in rows:
        row["z_tau"] = z_of(row["tau"], ref["tau"])
        row["z_mean_s"] = z_of(row["mean_s"], ref["mean_s"])
    w = max([len("point")] + [len(r["label"]) for r in [ref] + rows])  # whole labels
    print("%-*s %6s %5s %-30s %-30s %8s %8s %12s %10s" % (
        w, "point", "N", "jams", "tau (s) +- se [95% CI]", "<s> +- se [95% CI]", "z tau", "z <s>",
        "Mps/jam", "rate (1/s)"))
    for row in [ref] + rows:
        print("%-*s %6d %5d %-30s %-30s %8s %8s %12s %10s" % (
            w, row["label"], row["particles"], row["tau"]["jams"], fmt(row["tau"]),
            fmt(row["mean_s"]),
            "%+.2f" % row["z_tau"] if row.get("z_tau") is not None else "-",
            "%+.2f" % row["z_mean_s"] if row.get("z_mean_s") is not None else "-",
            "%.4g" % (row["particle_steps_per_jam"] / 1e6) if row["particle_steps_per_jam"]
            else "-", "%.0f" % row["discharge_rate"] if row.get("discharge_rate") else "-"))
    if out:
        with open(out, "w") as fh:
            json.dump({"published": ref, "steady_state": rows}, fh, indent=1)


def lid_stress_summary(s, half_width, height):
    """The mean coarse-grained pressure (m g) in the field cells whose centres lie within
    `half_width` of the axis and between the outlet and `height` above it, per point, with the
    point's discharge rate: the stress a lid must restore (docs/clogging.md). Cells no window
    reached are left out; ValueError when the store has no fields."""
    fields = s.fields()
    if not fields:
        raise ValueError("no fields (its sweep needs [fields] enabled = true)")
    r = s.realizations
    rows = []
    for label, ds in fields.items():
        sel = (abs(ds.x) < half_width) & (ds.y > 0) & (ds.y < height)
        p = ds["mean_pressure"].where(sel)
        rr = r[(r["label"] == label) & r["status"].isin(["complete", "time_limit"])]
        rows.append({"label": label, "pressure": float(p.mean()),
                     "cells": int(p.notnull().sum()),
                     "discharge_rate": float(rr["discharge_rate"].mean()) if len(rr) else None,
                     "jams": int(rr["n_jams"].sum())})
    return rows


def lid_stress(path, half_width, height, out):
    with open_store(path) as s:
        try:
            rows = lid_stress_summary(s, half_width, height)
        except ValueError as e:
            sys.exit("clogging.py lid-stress: %s: %s" % (path, e))
    print("pressure above the outlet (|x| < %.3g m, 0 < y < %.3g m), units of m g" %
          (half_width, height))
    print("%-70s %9s %6s %10s %5s" % ("point", "pressure", "cells", "rate (1/s)", "jams"))
    for row in rows:
        print("%-70s %9.1f %6d %10s %5d" % (row["label"][:70], row["pressure"], row["cells"],
                                             "%.0f" % row["discharge_rate"]
                                             if row["discharge_rate"] else "-", row["jams"]))
    if out:
        with open(out, "w") as fh:
            json.dump(rows, fh, indent=1)


def fill_levels(s, bins):
    """The published protocol's jam rate by fill level (particles in the hopper): per bin
    [bins[i], bins[i+1]), the flowing time the realizations spent there and the jams whose onset
    fell there, tau = time / jams (censored_mean's interval). A survival interval ended by a jam
    spans [onset - duration, onset] on the discharge curve's clock (which also holds each jam's
    detection window, outside every interval); a realization's last, censored interval ends at
    the curve's last sample. in_hopper is the curve's sample at or before a moment."""
    curves, jams, surv = s.curves, s.jams, s.survival
    nb = len(bins) - 1
    time = np.zeros(nb)
    count = np.zeros(nb, int)
    bad = 0
    for (pt, r), sv in surv.groupby(["point", "realization"]):
        cc = curves[(curves["point"] == pt) & (curves["realization"] == r)]
        if len(cc) < 2:
            continue
        t = cc["time"].to_numpy(float)
        n = cc["in_hopper"].to_numpy(float)
        level = np.digitize(n[:-1], bins) - 1  # of each segment [t[k], t[k+1])
        onsets = np.sort(jams[(jams["point"] == pt) & (jams["realization"] == r)]["onset"]
                         .to_numpy(float))
        sv = sv.sort_values("interval")
        ends = list(onsets[:int(sv["event"].sum())])
        if not sv["event"].iloc[-1]:
            ends.append(t[-1])
        if len(ends) != len(sv):
            bad += 1
            continue
        for end, dur in zip(ends, sv["duration"].to_numpy(float)):
            a, b = end - dur, end
            overlap = np.clip(np.minimum(b, t[1:]) - np.maximum(a, t[:-1]), 0, None)
            inside = (level >= 0) & (level < nb)
            time += np.bincount(level[inside], overlap[inside], nb)
        for o in onsets:
            k = max(int(np.searchsorted(t, o, side="right")) - 1, 0)
            i = int(np.digitize([n[k]], bins)[0]) - 1
            if 0 <= i < nb:
                count[i] += 1
    rows = []
    for i in range(nb):
        e = censored_mean([time[i]], [count[i]])
        rows.append({"from": bins[i], "to": bins[i + 1], "flow_time": float(time[i]),
                     "jams": int(count[i]), "tau": e})
    return {"levels": rows, "realizations_skipped": bad}


def levels(path, bins, out):
    with open_store(path) as s:
        result = fill_levels(s, bins)
    print("%s: jams by particles in the hopper at their onset" % path)
    print("%-14s %10s %5s  %s" % ("in hopper", "flow (s)", "jams", "tau (s) +- se [95% CI]"))
    for row in result["levels"]:
        print("%-14s %10.1f %5d  %s" % ("%d-%d" % (row["from"], row["to"]), row["flow_time"],
                                       row["jams"], fmt(row["tau"])))
    if result["realizations_skipped"]:
        print("skipped %d realization(s) whose jams and intervals do not match"
              % result["realizations_skipped"])
    if out:
        with open(out, "w") as fh:
            json.dump(result, fh, indent=1)


def question_summary(s, path):
    """The open question's table of an open store (hopper_store.Store): per point in order of D,
    flowing time (the survival intervals' durations), jams, tau and <s> (censored_mean; a bound
    without a jam), tau's relative 95 % half-width, worker core-hours (task_seconds) per point and
    per jam; and the fits `campaign analyze` stored (jam rate and <s> versus D), not refitted."""
    r, surv, pts = s.realizations, s.survival, s.points
    rows = []
    for i, pt in pts.sort_values("D_cm").iterrows():
        sv = surv[surv["point"] == i]
        rr = r[r["point"] == i]
        tau = censored_mean(sv["duration"], sv["event"])
        mean_s = censored_mean(sv["avalanche_size"], sv["event"]) if "avalanche_size" in sv \
            else None
        core_h = float(rr["task_seconds"].sum()) / 3600 if len(rr) else 0.0
        half = (tau["hi"] - tau["lo"]) / 2 / tau["mean"] if tau["mean"] else None
        rows.append({"label": pt["label"], "D_cm": float(pt["D_cm"]),
                     "realizations": int(len(rr)),
                     "statuses": {str(k): int(v) for k, v in rr["status"].value_counts().items()},
                     "flow_time": tau["total"], "tau": tau, "mean_s": mean_s,
                     "tau_rel_half_width": half, "core_hours": core_h,
                     "core_hours_per_jam": core_h / tau["jams"] if tau["jams"] else None})
    fits = {}
    if s.has_analysis:
        for name, table in (("jam_rate", s.jam_rate), ("mean_s", s.avalanche)):
            fits[name] = [{k: (None if isinstance(v, float) and math.isnan(v) else
                               v.item() if hasattr(v, "item") else v)
                           for k, v in row.items() if not str(k).startswith("has_")}
                          for _, row in table.iterrows()]
    return {"store": path, "points": rows, "fits": fits, "poisson_fit": poisson_fits(rows),
            "core_hours": sum(row["core_hours"] for row in rows)}


# The published study's jams at theta = 45 deg over 40 fills (its Table 3) and its mean empty
# times there (calibration.PUBLISHED_EMPTY, issue 24: restarts included, shaking excluded): the
# published jam rate per flowing second is jams / (fills x empty time).
PUBLISHED_JAMS_45 = {2.7: 261, 2.9: 124, 3.1: 48, 3.3: 26, 3.5: 8}
PUBLISHED_FILLS = 40
PUBLISHED_EMPTY_45 = {2.7: 34.45, 2.9: 30.44, 3.1: 27.83, 3.3: 25.25, 3.5: 22.82}


def poisson_two_sided(n, mu):
    """Two-sided p of a count n under Poisson(mu): twice the smaller tail, at most 1."""
    return float(min(1.0, 2.0 * min(stats.poisson.cdf(n, mu), stats.poisson.sf(n - 1, mu))))


def poisson_deviance(n, mu):
    """2 [n ln(n/mu) - (n - mu)] (0 ln 0 = 0): one outlet's share of the combined test."""
    return 2.0 * ((n * math.log(n / mu) if n > 0 else 0.0) - (n - mu))


def published_summary(s, path):
    """Per point of an open store at theta = 45 deg and a published outlet: its jams and flowing
    time (question_summary's) against the published rate; and the combined test over them."""
    q = question_summary(s, path)
    theta = {str(pt["label"]): float(pt["theta_deg"]) if "theta_deg" in pt else None
             for _, pt in s.points.iterrows()}
    rows, dev = [], 0.0
    for r in q["points"]:
        D = round(r["D_cm"], 3)
        th = theta.get(r["label"])
        if D not in PUBLISHED_JAMS_45 or th is None or abs(th - 45.0) > 1e-6:
            continue
        if not r["flow_time"] > 0:  # nothing stored there yet
            continue
        n, T = int(r["tau"]["jams"]), float(r["flow_time"])
        rate_pub = PUBLISHED_JAMS_45[D] / (PUBLISHED_FILLS * PUBLISHED_EMPTY_45[D])
        mu = rate_pub * T
        row = {"label": r["label"], "D_cm": D, "realizations": r["realizations"], "jams": n,
               "flow_time": T, "rate": n / T if T > 0 else None, "published_rate": rate_pub,
               "expected": mu, "ratio": n / mu if mu > 0 else None,
               "p": poisson_two_sided(n, mu) if mu > 0 else None}
        if mu > 0:
            dev += poisson_deviance(n, mu)
        rows.append(row)
    k = sum(1 for r in rows if r["expected"] > 0)
    combined = {"outlets": k, "deviance": dev,
                "p": float(stats.chi2.sf(dev, k)) if k else None}
    return {"store": path, "points": rows, "combined": combined}


def opt(x):
    return "-" if x is None else sig(x)


def published_markdown(results):
    lines = ["| store | D (cm) | realizations | jams | flowing time (s) | rate (1/s) | "
             "published rate (1/s) | ratio | published rate expects | Poisson p |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for res in results:
        for r in res["points"]:
            lines.append("| %s | %.1f | %d | %d | %.0f | %s | %.4g | %s | %.1f | %s |" % (
                os.path.basename(res["store"]), r["D_cm"], r["realizations"], r["jams"],
                r["flow_time"], opt(r["rate"]), r["published_rate"], opt(r["ratio"]),
                r["expected"], opt(r["p"])))
    lines.append("")
    for res in results:
        c = res["combined"]
        lines.append("%s: combined over %d outlets, Poisson deviance %.2f, p = %s" % (
            os.path.basename(res["store"]), c["outlets"], c["deviance"], opt(c["p"])))
    return "\n".join(lines) + "\n"


def published(paths, out, md):
    results = []
    for path in paths:
        with open_store(path) as s:
            results.append(published_summary(s, path))
    emit(results, published_markdown(results), out, md)


def _poisson_glm(X, n, T):
    """Maximum of sum n ln(lambda T) - lambda T with ln lambda = X beta (BFGS with the analytic
    gradient; the Poisson log-likelihood with a log link is concave). Returns (beta,
    log-likelihood without the n-only constant)."""
    from scipy import optimize
    X, n, T = (np.asarray(v, float) for v in (X, n, T))

    def neg(beta):
        eta = X @ beta
        lam_t = np.exp(eta) * T
        return -(n @ eta - lam_t.sum()), -(X.T @ (n - lam_t))

    start = np.zeros(X.shape[1])
    start[0] = math.log(max(n.sum(), 0.5) / T.sum())
    res = optimize.minimize(neg, start, jac=True, method="BFGS", options={"gtol": 1e-10})
    beta = res.x
    eta = X @ beta
    return beta, float(n @ (eta + np.log(T)) - (np.exp(eta) * T).sum())


def poisson_fits(points, dc_span_m=0.5, dc_fixed_m=None):
    """The jam rate against D fitted to every outlet's jam count and flowing time (Poisson, so
    an outlet without a jam counts too, unlike the least-squares fit of `campaign analyze`
    that leaves it out): exponential ln lambda = ln A - B D, and power law ln lambda = ln A +
    gamma ln(D_c - D), zero at and beyond D_c, profiled over D_c from just above the largest
    outlet with a jam to dc_span_m beyond it. AIC = -2 ln L + 2 k (k = 2, 3). Keys as the
    store's fits (SI: B per m, D_c in m); a best D_c at the scan's far end means no finite D_c.
    With dc_fixed_m the power law's D_c is that one (the alternative to test; k = 2 then), the
    rest as is."""
    # An outlet without flowing time yet (its first realizations still running) says nothing,
    # and its n ln T would be 0 x -inf: left out.
    points = [p for p in points if p["flow_time"] > 0]
    D = np.array([p["D_cm"] / 100 for p in points])
    n = np.array([p["tau"]["jams"] for p in points], float)
    T = np.array([p["flow_time"] for p in points], float)
    if (n > 0).sum() < 2 or len(points) < 3:
        return {"reason": "too few outlets (needs 3, 2 with jams)"}
    beta, ll_e = _poisson_glm(np.column_stack([np.ones_like(D), -D]), n, T)
    out = {"n_points": len(points), "exp_ln_A": float(beta[0]), "exp_B": float(beta[1]),
           "exp_lnL": ll_e, "exp_aic": -2 * ll_e + 4}
    top = D[n > 0].max()
    if dc_fixed_m is not None and dc_fixed_m <= top:
        return {"reason": "D_c = %.3g cm is not above the largest outlet with a jam (%.3g cm)"
                % (dc_fixed_m * 100, top * 100)}

    def power_law_at(dc):  # outlets at and beyond D_c expect no jam and add nothing
        inside = D < dc
        return _poisson_glm(np.column_stack([np.ones(inside.sum()), np.log(dc - D[inside])]),
                            n[inside], T[inside])

    profile = [(dc,) + power_law_at(dc) for dc in top + np.geomspace(1e-4, dc_span_m, 400)]
    dc, b, ll = max(profile, key=lambda t: t[2])
    # The profile likelihood's 95 % lower bound on D_c: the smallest D_c with
    # 2 (ln L_best - ln L(D_c)) < chi2_{0.95}(1) = 3.84.
    allowed = [t[0] for t in profile if 2 * (ll - t[2]) < stats.chi2.ppf(0.95, 1)]
    out["pow_Dc_lower_95"] = float(min(allowed))
    if dc_fixed_m is not None:
        dc = dc_fixed_m
        b, ll = power_law_at(dc)
        out["pow_Dc_fixed"] = True
    out.update({"pow_Dc": float(dc), "pow_ln_A": float(b[0]), "pow_gamma": float(b[1]),
                "pow_lnL": ll, "pow_aic": -2 * ll + (4 if dc_fixed_m is not None else 6),
                "pow_Dc_at_scan_end": bool(dc >= top + 0.99 * dc_span_m)})
    d_aic = out["pow_aic"] - out["exp_aic"]
    if dc_fixed_m is not None:
        out["preferred"] = "power law" if d_aic < -2 else "exponential" if d_aic > 2 else \
            "undecided"
        out["decision"] = "D_c fixed at %.3g cm: AIC power law - exponential = %+.2f" % (
            dc_fixed_m * 100, d_aic)
    elif out["pow_Dc_at_scan_end"]:
        out["preferred"] = "exponential"
        out["decision"] = ("the power law's best D_c is the scan's far end (%.3g cm beyond the "
                           "largest jamming outlet): no finite D_c" % (dc_span_m * 100))
    elif abs(d_aic) <= 2:
        out["preferred"] = "undecided"
        out["decision"] = "|Delta AIC| <= 2: the data do not distinguish the two laws"
    else:
        out["preferred"] = "power law" if d_aic < 0 else "exponential"
        out["decision"] = "AIC power law - exponential = %+.2f" % d_aic
    return out


def poisson_markdown(f):
    if "exp_B" not in f:
        return "Poisson fit of the jam rate: %s." % f.get("reason")
    return ("Poisson fit of the jam rate (%d outlets, those without a jam included): exponential B "
            "= %.3g per cm; power law best D_c = %.3g cm (gamma = %.3g), a critical outlet below "
            "%.3g cm excluded at 95 %% (profile likelihood); AIC power law - exponential = %+.2f; "
            "preferred: %s; %s." % (f["n_points"], f["exp_B"] / 100, f["pow_Dc"] * 100,
                                    f["pow_gamma"], f["pow_Dc_lower_95"] * 100,
                                    f["pow_aic"] - f["exp_aic"], f["preferred"], f["decision"]))


def question_markdown(result, target=0.1):
    """The table and the fits' verdicts as Markdown (docs/clogging.md, section 3)."""
    out = ["| D (cm) | realizations | flowing time (s) | jams | tau (s) +- se [95 % CI] | "
           "tau +-95 % | <s> +- se | core-hours | core-hours per jam |",
           "|---|---|---|---|---|---|---|---|---|"]
    for row in result["points"]:
        half = row["tau_rel_half_width"]
        ms = row["mean_s"]
        out.append("| %.3g | %d | %.0f | %d | %s | %s | %s | %.2f | %s |" % (
            row["D_cm"], row["realizations"], row["flow_time"], row["tau"]["jams"],
            fmt(row["tau"]),
            "%.0f %%%s" % (100 * half, " (met)" if half <= target else "") if half else "-",
            ("%s +- %s" % (sig(ms["mean"]), sig(ms["se"], 2)) if ms and ms["mean"] is not None
             else "> %s" % sig(ms["lo"]) if ms else "-"),
            row["core_hours"],
            "%.3g" % row["core_hours_per_jam"] if row["core_hours_per_jam"] else "-"))
    out.append("")
    out.append("Core-hours in all (worker time): %.2f." % result["core_hours"])
    for name, what in (("jam_rate", "jam rate 1/tau"), ("mean_s", "<s>")):
        for f in result["fits"].get(name, []):
            out.append("")
            parts = []
            if f.get("exp_B") is not None:  # the rate falls as exp(-B D), <s> grows as exp(B D)
                law = "1/tau ~ exp(-B D)" if name == "jam_rate" else "<s> ~ exp(B D)"
                parts.append("exponential %s, B = %.3g +- %.2g per cm" % (
                    law, f["exp_B"] / 100, (f.get("exp_B_err") or 0) / 100))
            if f.get("pow_Dc") is not None and f.get("pow_gamma") is not None:
                parts.append("power law with D_c = %.3g cm, gamma = %.3g" % (
                    f["pow_Dc"] * 100, f["pow_gamma"]))
            if f.get("exp_aic") is not None and f.get("pow_aic") is not None:
                parts.append("AIC power law - exponential = %+.2f" % (f["pow_aic"] - f["exp_aic"]))
            out.append("Fit of the %s versus D (%s, %d outlets): %spreferred: %s; %s." % (
                what, f.get("group") or "all points", f.get("n_points", 0),
                "; ".join(parts) + "; " if parts else "", f.get("preferred"), f.get("decision")))
    if "poisson_fit" in result:
        out += ["", poisson_markdown(result["poisson_fit"])]
    return "\n".join(out) + "\n"


def emit(result, text, out, md):
    """Print the Markdown text; write the result as JSON to `out` and the text to `md`, if given."""
    print(text, end="")
    if out:
        with open(out, "w") as fh:
            json.dump(result, fh, indent=1)
    if md:
        with open(md, "w") as fh:
            fh.write(text)


def question_figure(result, png, dc_cm=5.0):
    """The jam rate against D (rate with its 95 % interval; a 95 % upper bound where no jam) with
    the Poisson fits: the exponential, the best power law and the power law with D_c fixed at
    dc_cm, each with its AIC."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    pts = result["points"]
    f = result["poisson_fit"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for r in pts:
        t = r["tau"]
        if t["jams"]:
            ax.errorbar(r["D_cm"], 1 / t["mean"], yerr=[[1 / t["mean"] - 1 / t["hi"]],
                                                        [1 / t["lo"] - 1 / t["mean"]]],
                        fmt="o", color="C0", capsize=3)
        else:
            ax.errorbar(r["D_cm"], 1 / t["lo"], yerr=[[0.5 / t["lo"]], [0]], uplims=True,
                        fmt="v", color="C0", mfc="white", capsize=3)
    if "exp_B" in f:
        D = np.linspace(min(r["D_cm"] for r in pts), max(r["D_cm"] for r in pts) + 0.6, 300)
        fixed = poisson_fits(pts, dc_fixed_m=dc_cm / 100)
        ax.plot(D, [law_rates(f, d / 100)[0] for d in D], color="C1",
                label="exponential, B = %.2f/cm (AIC 0)" % (f["exp_B"] / 100))
        for g, style, what in ((f, "--", "best power law"), (fixed, ":", "power law")):
            if "pow_Dc" not in g:
                continue
            Dm = D[D / 100 < g["pow_Dc"]]
            ax.plot(Dm, [law_rates(g, d / 100)[1] for d in Dm],
                    style, color="C2" if style == "--" else "C3",
                    label="%s, D_c = %.3g cm (AIC %+.1f)" % (what, g["pow_Dc"] * 100,
                                                             g["pow_aic"] - g["exp_aic"]))
        ax.set_title("critical outlet below %.3g cm excluded at 95 %%" % (f["pow_Dc_lower_95"] * 100),
                     fontsize=10)
    ax.set_yscale("log")
    rates = [1 / (r["tau"]["hi"] or r["tau"]["lo"] * 2) for r in pts]
    ax.set_ylim(min(rates) / 100, 2 * max(1 / r["tau"]["lo"] for r in pts))
    ax.set_xlabel("D (cm)")
    ax.set_ylabel("jam rate 1/tau (1/s)")
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def question(path, out, md, png=None):
    with open_store(path) as s:
        result = question_summary(s, path)
    emit(result, question_markdown(result), out, md)
    if png:
        question_figure(result, png)


def law_rates(fit, D_m):
    """The jam rates (1/s) the two fitted laws give at outlet D (m): exponential
    ln lambda = ln A - B D, power law ln lambda = ln A + gamma ln(D_c - D), zero at and beyond
    D_c (docs/statistics.md, "Jam rate versus D")."""
    exp_rate = math.exp(fit["exp_ln_A"] - fit["exp_B"] * D_m)
    if D_m >= fit["pow_Dc"]:
        return exp_rate, 0.0
    return exp_rate, math.exp(fit["pow_ln_A"] + fit["pow_gamma"] * math.log(fit["pow_Dc"] - D_m))


def decision_probabilities(T, rate_e, rate_p, margin=1.0):
    """One outlet observed for T flowing seconds, its jams n Poisson with the true law's mean.
    The log-likelihood ratio of the two laws (no parameter refitted) is
    n ln(rate_e / rate_p) - (rate_e - rate_p) T; it favours a law when it exceeds `margin`
    (1: an AIC difference of 2) its way. Returns (P(exponential favoured | exponential true),
    P(power law favoured | power law true))."""
    mean_e, mean_p = rate_e * T, rate_p * T
    hi = int(max(mean_e, mean_p) + 12 * math.sqrt(max(mean_e, mean_p)) + 30)
    n = np.arange(hi + 1)
    if rate_p == 0.0:  # beyond D_c: one jam rules the power law out
        llr = np.where(n > 0, np.inf, -mean_e)
    else:
        llr = n * math.log(rate_e / rate_p) - (mean_e - mean_p)
    p_e = float(stats.poisson.pmf(n, mean_e)[llr > margin].sum())
    p_p = float(stats.poisson.pmf(n, mean_p)[llr < -margin].sum()) if rate_p > 0 else \
        (1.0 if mean_e > margin else 0.0)
    return p_e, p_p


def flow_time_to_decide(rate_e, rate_p, power=0.95, margin=1.0, step=1.01, t_max=1e10):
    """The shortest flowing time (on a grid of ratio `step`) after which each law, when true, is
    favoured with probability >= power; None when not reached before t_max or the laws agree."""
    if rate_e == rate_p:
        return None
    T = 0.1 / max(rate_e, rate_p)
    while T < t_max:
        p_e, p_p = decision_probabilities(T, rate_e, rate_p, margin)
        if p_e >= power and p_p >= power:
            return T
        T *= step
    return None


def bound_probabilities(points, fit, outlets_cm, flows, bound_cm, tail=1e-4):
    """Where more flow would raise the profile likelihood's 95 % lower bound on D_c above
    bound_cm (the open question's second target): for each outlet D and flowing time T added
    there, P(the refitted bound > bound_cm) when the fitted exponential is true. The jams in T
    are Poisson with the exponential's mean, so the probability is exact, a sum over their
    count n (to a Poisson tail below `tail`) of P(n) times whether poisson_fits over `points`
    with n jams and T seconds added at D moves the bound past bound_cm. Beyond the bound one jam
    does it (a critical law cannot jam at or beyond D_c), so there P = 1 - exp(-lambda T) unless
    the points already exclude it. Returns one row per outlet and time."""
    def raised(D, T, n):  # the bound refitted with n jams in T more seconds at D
        pts = [dict(p, tau=dict(p["tau"])) for p in points]
        here = [p for p in pts if abs(p["D_cm"] - D) < 1e-6]
        if not here:
            here = [{"D_cm": D, "flow_time": 0.0, "tau": {"jams": 0}}]
            pts.append(here[0])
        here[0]["flow_time"] += T
        here[0]["tau"]["jams"] += n
        f = poisson_fits(pts)
        return "pow_Dc_lower_95" in f and f["pow_Dc_lower_95"] * 100 > bound_cm

    rows = []
    for D in outlets_cm:
        rate = law_rates(fit, D / 100)[0]
        for T in flows:
            mean = rate * T
            top = int(stats.poisson.isf(tail, mean)) + 1
            prob = sum(stats.poisson.pmf(n, mean) for n in range(top + 1) if raised(D, T, n))
            rows.append({"D_cm": D, "flow_time": T, "jams_exponential": mean,
                         "p_bound_raised": prob})
    return rows


def plan_summary(s, path, outlets_cm=None, core_s_per_flow_s=None, power=0.95, fit="poisson",
                 dc_cm=None, bound_cm=None, flows=(8000.0, 16000.0)):
    """Per fitted group of the store's jam-rate fits, per outlet: both laws' tau, the flowing
    time that decides between them (flow_time_to_decide), the jams each law expects in it and
    the core-hours at the store's cost per flowing second (worker time over flowing time, all
    points) unless given. With bound_cm (Poisson fit only), per outlet and flowing time in
    `flows` also the probability that this much more flow raises the D_c lower bound above it
    (bound_probabilities)."""
    q = question_summary(s, path)
    if core_s_per_flow_s is None:
        flow = sum(r["flow_time"] for r in q["points"])
        if flow <= 0:
            raise ValueError("the store has no flowing time to measure the cost of a flowing second "
                             "(give --core-s-per-flow-s)")
        core_s_per_flow_s = 3600 * q["core_hours"] / flow
    if fit == "poisson" and dc_cm is not None:
        q["poisson_fit"] = poisson_fits(q["points"], dc_fixed_m=dc_cm / 100)
    candidates = ([dict(q["poisson_fit"], group="the Poisson fit over every outlet%s" % (
        ", D_c fixed at %.3g cm" % dc_cm if dc_cm is not None else ""))] if fit == "poisson"
        else q["fits"].get("jam_rate", []))
    fits = [f for f in candidates
            if all(f.get(k) is not None for k in ("exp_ln_A", "exp_B", "pow_ln_A", "pow_Dc",
                                                  "pow_gamma"))]
    if not fits:
        raise ValueError("no jam-rate fit with both laws (%s)" % (
            q["poisson_fit"].get("reason") if fit == "poisson" else
            "run `campaign analyze` on the store; its power law needs 4 outlets with jams"))
    if outlets_cm is None:  # where jams were seen the laws agree to within their fit
        jammed = [r["D_cm"] for r in q["points"] if r["tau"]["jams"] > 0]
        if not jammed:
            raise ValueError("no outlet of the store has a jam (give --outlets)")
        outlets_cm = [round(max(jammed) + 0.1 * i, 6) for i in range(1, 11)]
    groups = []
    for f in fits:
        rows = []
        for D in outlets_cm:
            rate_e, rate_p = law_rates(f, D / 100)
            T = flow_time_to_decide(rate_e, rate_p, power)
            here = [r for r in q["points"] if abs(r["D_cm"] - D) < 1e-6]
            flown = sum(r["flow_time"] for r in here)
            to_go = max(T - flown, 0.0) if T else None
            rows.append({"D_cm": D, "tau_exponential": 1 / rate_e,
                         "tau_power_law": 1 / rate_p if rate_p > 0 else None,
                         "flow_time": T,
                         "jams_exponential": rate_e * T if T else None,
                         "jams_power_law": rate_p * T if T else None,
                         "core_hours": T * core_s_per_flow_s / 3600 if T else None,
                         "flow_measured": flown,
                         "jams_measured": sum(r["tau"]["jams"] for r in here),
                         "core_hours_to_go": to_go * core_s_per_flow_s / 3600 if T else None})
        best = min((r for r in rows if r["core_hours_to_go"] is not None),
                   key=lambda r: r["core_hours_to_go"], default=None)
        groups.append({"group": f.get("group"), "fit": f, "outlets": rows,
                       "cheapest": best["D_cm"] if best else None})
    result = {"store": path, "power": power, "core_s_per_flow_s": core_s_per_flow_s,
              "groups": groups}
    if bound_cm is not None:  # the best-fitting laws (the fixed-D_c fit, if any, replaced them)
        base = q["poisson_fit"] if dc_cm is None else poisson_fits(q["points"])
        rows = bound_probabilities(q["points"], base, outlets_cm, flows, bound_cm)
        for r in rows:
            r["core_hours"] = r["flow_time"] * core_s_per_flow_s / 3600
        best = max(rows, key=lambda r: (r["p_bound_raised"] / r["core_hours"]), default=None)
        result["bound"] = {"bound_cm": bound_cm, "lower_95_cm": base["pow_Dc_lower_95"] * 100,
                           "rows": rows, "best": best}
    return result


def plan_markdown(result):
    out = []
    for g in result["groups"]:
        f = g["fit"]
        out.append("Jam-rate laws of %s: exponential B = %.3g per cm; power "
                   "law D_c = %.3g cm, gamma = %.3g. Flowing time at one outlet after which each "
                   "law, when true, is favoured by an AIC margin of 2 with probability %.2f; "
                   "core-hours at %.3g core-s per flowing second:" % (
                       g["group"] or "all points", f["exp_B"] / 100, f["pow_Dc"] * 100,
                       f["pow_gamma"], result["power"], result["core_s_per_flow_s"]))
        out.append("")
        out.append("| D (cm) | tau exponential (s) | tau power law (s) | flowing time (s) | "
                   "jams if exponential | jams if power law | core-hours | measured: flow (s), "
                   "jams | core-hours to go |")
        out.append("|---|---|---|---|---|---|---|---|---|")
        for r in g["outlets"]:
            out.append("| %.3g | %s | %s | %s | %s | %s | %s | %s | %s |%s" % (
                r["D_cm"], sig(r["tau_exponential"]),
                sig(r["tau_power_law"]) if r["tau_power_law"] else "inf (D >= D_c)",
                sig(r["flow_time"]) if r["flow_time"] else "-",
                sig(r["jams_exponential"]) if r["flow_time"] else "-",
                sig(r["jams_power_law"]) if r["flow_time"] else "-",
                sig(r["core_hours"]) if r["core_hours"] else "-",
                "%.0f, %d" % (r["flow_measured"], r["jams_measured"]) if r["flow_measured"]
                else "-",
                sig(r["core_hours_to_go"]) if r["core_hours_to_go"] is not None else "-",
                "  <- cheapest" if r["D_cm"] == g["cheapest"] else ""))
        out.append("")
        out.append("The laws are taken as fitted (their errors and a refit with the new outlet "
                   "are left out): a plan, not a guarantee. To go: the flowing time still "
                   "missing after what the store holds at that outlet.")
        out.append("")
    b = result.get("bound")
    if b:
        out.append("The D_c lower bound (95 %%, profile likelihood) stands at %.3g cm. The "
                   "probability that more flow at one outlet raises it above %.3g cm, if the "
                   "Poisson exponential is true (exact over the jam count, every count refitted "
                   "with the store's points):" % (b["lower_95_cm"], b["bound_cm"]))
        out.append("")
        out.append("| D (cm) | flowing time added (s) | jams if exponential | P(bound > %.3g cm) "
                   "| core-hours | P per core-hour |" % b["bound_cm"])
        out.append("|---|---|---|---|---|---|")
        for r in b["rows"]:
            out.append("| %.3g | %s | %s | %.2f | %s | %.3f |%s" % (
                r["D_cm"], sig(r["flow_time"]), sig(r["jams_exponential"]),
                r["p_bound_raised"], sig(r["core_hours"]),
                r["p_bound_raised"] / r["core_hours"],
                "  <- best per core-hour" if r is b["best"] else ""))
        out.append("")
    return "\n".join(out)


def plan(path, outlets, core_s, power, fit, dc, out, md, bound=None, flows=(8000.0, 16000.0)):
    with open_store(path) as s:
        try:
            result = plan_summary(s, path, outlets, core_s, power, fit, dc, bound, flows)
        except ValueError as e:
            sys.exit("clogging.py plan: %s: %s" % (path, e))
    emit(result, plan_markdown(result), out, md)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("arrests")
    a.add_argument("store")
    a.add_argument("--json")
    h = sub.add_parser("heads")
    h.add_argument("published")
    h.add_argument("steady")
    h.add_argument("--ns-per-particle-step", nargs="*", metavar="LABEL=NS")
    h.add_argument("--reference", metavar="TAU,TAU_SE,S,S_SE,JAMS",
                   help="the published side as numbers instead of the store (give the store's "
                   "argument as -)")
    h.add_argument("--reference-point", metavar="LABEL_PART",
                   help="the point of the published store whose label contains this is the "
                   "reference (the store may hold several; given twice, a store's other points "
                   "against one of its own)")
    h.add_argument("--json")
    ls = sub.add_parser("lid-stress")
    ls.add_argument("store")
    ls.add_argument("--half-width", type=float, default=0.03, help="m (default %(default)s)")
    ls.add_argument("--height", type=float, default=0.05, help="m (default %(default)s)")
    ls.add_argument("--json")
    lv = sub.add_parser("levels")
    lv.add_argument("store")
    lv.add_argument("--bins", default="0,300,700,1500,3000,5000,9000",
                    help="fill-level bin edges, particles in the hopper (default %(default)s)")
    lv.add_argument("--json")
    q = sub.add_parser("question")
    q.add_argument("store")
    q.add_argument("--json")
    q.add_argument("--md", help="write the table as Markdown too")
    q.add_argument("--png", help="draw the jam rate with the Poisson fits (matplotlib)")
    pb = sub.add_parser("published")
    pb.add_argument("stores", nargs="+")
    pb.add_argument("--json")
    pb.add_argument("--md", help="write the table as Markdown too")
    pl = sub.add_parser("plan")
    pl.add_argument("store")
    pl.add_argument("--outlets", help="outlets D in cm, comma-separated (default: the ten "
                    "beyond the largest with a jam, in steps of 0.1 cm)")
    pl.add_argument("--core-s-per-flow-s", type=float,
                    help="cost of a flowing second (default: the store's worker time over its "
                    "flowing time)")
    pl.add_argument("--power", type=float, default=0.95,
                    help="probability of favouring the true law (default %(default)s)")
    pl.add_argument("--fit", choices=("poisson", "store"), default="poisson",
                    help="the laws: the Poisson fit over every outlet (default) or the store's "
                    "own (`campaign analyze`, outlets without a jam left out)")
    pl.add_argument("--dc", type=float, help="test the exponential against the power law with "
                    "this critical outlet (cm) instead of the best-fitting one")
    pl.add_argument("--bound", type=float, metavar="CM",
                    help="also: the probability that more flow at each outlet raises the D_c "
                    "lower bound above CM (Poisson fit; slow: a refit per jam count)")
    pl.add_argument("--flows", default="8000,16000", metavar="S,S",
                    help="with --bound: the flowing times to add per outlet, s (default "
                    "%(default)s)")
    pl.add_argument("--json")
    pl.add_argument("--md", help="write the table as Markdown too")
    args = ap.parse_args()
    for p in [getattr(args, k) for k in ("store", "published", "steady") if hasattr(args, k)] + \
            list(getattr(args, "stores", [])):
        if p == "-" and getattr(args, "reference", None):
            continue
        if not os.path.exists(p):
            sys.exit("clogging.py: no such store: %s" % p)
    if args.cmd == "arrests":
        arrests(args.store, args.json)
    elif args.cmd == "published":
        published(args.stores, args.json, args.md)
    elif args.cmd == "question":
        question(args.store, args.json, args.md, args.png)
    elif args.cmd == "plan":
        try:
            outlets = [float(v) for v in args.outlets.split(",")] if args.outlets else None
        except ValueError:
            sys.exit("clogging.py plan: --outlets must be numbers (cm) separated by commas, got %r"
                     % args.outlets)
        if outlets is not None and any(not (d > 0 and math.isfinite(d)) for d in outlets):
            sys.exit("clogging.py plan: --outlets must be positive (cm), got %r" % args.outlets)
        if not 0 < args.power < 1:
            sys.exit("clogging.py plan: --power must lie between 0 and 1, got %g" % args.power)
        if args.core_s_per_flow_s is not None and not (args.core_s_per_flow_s > 0 and
                                                       math.isfinite(args.core_s_per_flow_s)):
            sys.exit("clogging.py plan: --core-s-per-flow-s must be positive, got %g"
                     % args.core_s_per_flow_s)
        if args.dc is not None and (args.fit != "poisson" or not args.dc > 0):
            sys.exit("clogging.py plan: --dc takes a positive D_c in cm, with --fit poisson")
        try:
            flows = [float(v) for v in args.flows.split(",")]
        except ValueError:
            flows = None
        if not flows or any(not (t > 0 and math.isfinite(t)) for t in flows):
            sys.exit("clogging.py plan: --flows must be positive times (s) separated by commas, "
                     "got %r" % args.flows)
        if args.bound is not None and (args.fit != "poisson" or args.dc is not None or
                                       not (args.bound > 0 and math.isfinite(args.bound))):
            sys.exit("clogging.py plan: --bound takes a positive D_c in cm, with --fit poisson "
                     "and without --dc")
        plan(args.store, outlets, args.core_s_per_flow_s, args.power, args.fit, args.dc,
             args.json, args.md, args.bound, flows)
    elif args.cmd == "levels":
        try:
            bins = [float(v) for v in args.bins.split(",")]
        except ValueError:
            sys.exit("clogging.py levels: --bins must be numbers separated by commas, got %r"
                     % args.bins)
        if len(bins) < 2 or any(b <= a for a, b in zip(bins, bins[1:])):
            sys.exit("clogging.py levels: --bins must be two or more increasing edges, got %r"
                     % args.bins)
        levels(args.store, bins, args.json)
    elif args.cmd == "lid-stress":
        if not (args.half_width > 0 and args.height > 0):
            sys.exit("clogging.py lid-stress: --half-width and --height must be positive")
        lid_stress(args.store, args.half_width, args.height, args.json)
    else:
        if args.reference and args.reference_point:
            sys.exit("clogging.py heads: --reference and --reference-point exclude each other")
        heads(args.published, args.steady, args.ns_per_particle_step, args.json, args.reference,
              args.reference_point)


if __name__ == "__main__":
    main()
