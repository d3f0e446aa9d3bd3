#!/usr/bin/python3
"""The flat-silo validation of issue 26 (docs/validation.md): table, fit and figure.

usage: silo_validation.py REMOVE_ARCH.h5 [REFILL.h5] [--out DIR] [--keep-first]

Per outlet D/d (d: the disks' diameter; the silos are monodisperse): the avalanches (survival
intervals ended by a clog; the censored last interval of a realization counts in <s>'s exposure,
as `campaign analyze`, docs/statistics.md), <s> = grains / clogs with its standard error
<s>/sqrt(clogs) and 95 % chi-square interval, the arches at the clogs (size in disks, the share
found, the mean aspect ratio span / height), for both protocols. The fit
ln(<s> + 1) = a + b (D/d)^2 is weighted least squares with sigma_i = se_i / (<s>_i + 1), over the
outlets with at least 5 clogs; a and b with their standard errors and the reduced chi-square;
with 4 or more such outlets also the critical alternative ln(<s>+1) = ln A - gamma ln(R_c - D/d)
(a finite outlet R_c beyond which nothing clogs) and the AIC verdict between the two; a best
R_c at the far end of its scan (50 beyond the largest outlet) is no finite R_c, and when that
limit wins the verdict says "exponential in D/d (no finite R_c)".
The arch-removal store's <s> leaves out each realization's first avalanche, the one from the
settled fill to the first clog (a settled packing is not the steady flow the protocol is
about), and reports it apart; --keep-first counts it. Every clog's arch counts, the first
ones too ("arches found / all clogs"). A refill realization is one first avalanche. With both
stores, the protocol effect per outlet in both: arch removal's <s> over refill's with the z of
the log, and the realizations of the same seed, whose first avalanches must be equal (the same
fill, and both protocols run alike until the first clog).
Arch height: the top of the arch's highest disk above the outlet plane (y_i + d/2); span: the
distance between the arch's two contacts with the wall disks (docs/model.md, step 9).

Writes DIR/silo_validation.json, DIR/silo_validation.md (the tables) and DIR/silo_validation.png
(ln(<s>+1) against (D/d)^2 with the fit; the arch size distributions per D/d). Per outlet also
the shape of the avalanche sizes: coefficient of variation and Kolmogorov-Smirnov p against an
exponential (the literature finds exponential sizes at every outlet).
"""
import argparse
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from clogging import censored_mean  # noqa: E402
from hopper_store import open_store  # noqa: E402

MIN_CLOGS_FIT = 5      # an outlet enters the fits with this many clogs or more
R_C_SCAN_SPAN = 50.0   # the critical fit scans R_c up to this far (D/d) beyond the largest outlet

# The experiments of the 2-D silo (arch removal) as compared by Goldberg, Carlevaro and Pugnaloni
# (J. Stat. Mech. (2018) 113201, Fig. 3a): ln(<s>+1) per D/d, read off that figure (+-0.3; issue
# 39). The band the model is held to: from the lower to the higher of the two at each outlet,
# widened by BAND_MARGIN on each side (one experiment alone at D/d 3).
EXPERIMENTS = {
    "Janda et al. 2008": {3.0: 3.9, 3.5: 5.1, 4.0: 6.4, 4.5: 8.0, 5.0: 9.7},
    "To 2005": {3.5: 4.2, 4.0: 5.4, 4.5: 6.3, 5.0: 7.8},
}
BAND_MARGIN = 0.5


def band(D_over_d):
    """(lo, hi) of the experimental band at this outlet (within 0.01 of a tabulated D/d), or
    None where no experiment was read."""
    vals = [v for tab in EXPERIMENTS.values() for k, v in tab.items() if abs(k - D_over_d) < 0.01]
    if not vals:
        return None
    return min(vals) - BAND_MARGIN, max(vals) + BAND_MARGIN


def band_check(rows):
    """Per row with clogs and an experimental band at its outlet: ln(<s>+1), the band, and
    whether it lies inside; plus whether every such row does."""
    out = []
    for r in rows:
        b = band(r["D_over_d"])
        if b is None or not r["clogs"] or r["mean_s"] is None:
            continue
        y = math.log(r["mean_s"] + 1)
        out.append({"D_over_d": r["D_over_d"], "y": y, "lo": b[0], "hi": b[1],
                    "inside": b[0] <= y <= b[1]})
    return {"rows": out, "all_inside": bool(out) and all(x["inside"] for x in out)}


plt.rcParams.update({"pdf.fonttype": 42, "ps.fonttype": 42, "svg.hashsalt": "hopper"})


def summarize(path, skip_first=False):
    with open_store(path) as s:
        return summarize_store(s, path, skip_first)


def interval_stats(sv):
    """<s> of survival intervals `sv`: grains / clogs (censored intervals add grains, no clog),
    its standard error and 95 % chi-square interval; with no clog the one-sided 95 % lower bound
    grains / (-ln 0.05)."""
    e = censored_mean(sv["avalanche_size"], sv["event"])
    row = {"clogs": e["jams"], "grains": e["total"], "mean_s": e["mean"], "se": e["se"],
           "lo": e["lo"], "hi": e["hi"]}
    # The shape: the literature finds exponential avalanche sizes at every outlet. Of the
    # completed avalanches (censored ones left out), with 10 or more: the coefficient of
    # variation (1 for an exponential) and the Kolmogorov-Smirnov p-value against the
    # exponential of their mean (approximate: the mean is fitted, which makes it conservative).
    done = sv[sv["event"] == 1]["avalanche_size"].to_numpy(float)
    if len(done) >= 10 and done.mean() > 0:
        row["cv"] = float(done.std(ddof=1) / done.mean())
        row["ks_p"] = float(stats.kstest(done, "expon", args=(0, done.mean())).pvalue)
    else:
        row["cv"] = row["ks_p"] = None
    return row


def summarize_store(s, path, skip_first=False):
    """One row per point of the store `s` (a hopper_store.Store; `path` names it in errors),
    sorted by D/d. With skip_first the first interval of every realization (the avalanche from
    the settled fill to the first clog) is left out of <s> and reported apart ("first")."""
    rows = []
    pts = s.points
    surv = s.survival
    arches = s.arches
    r = s.realizations
    for i, pt in pts.iterrows():
        d = float(pt["particles.d_large_m"]) if "particles.d_large_m" in pt else None
        if d is None or not np.isfinite(d):
            sys.exit("silo_validation.py: %s has no particles.d_large_m" % path)
        D = float(pt["hopper.outlet_m"])
        sv = surv[surv["point"] == i]
        row = {"label": pt["label"], "D_over_d": D / d, "realizations": int((r["point"] == i).sum())}
        if skip_first:
            row.update(interval_stats(sv[sv["interval"] > 0]))
            row["first"] = interval_stats(sv[sv["interval"] == 0])
        else:
            row.update(interval_stats(sv))
        # Each realization's first avalanche by seed (size, duration), for the check that two
        # protocols given the same seed flow alike until their first clog.
        seeds = dict(zip(r[r["point"] == i]["realization"], r[r["point"] == i]["seed_str"]))
        row["first_by_seed"] = {
            str(seeds[x.realization]): [float(x.avalanche_size), float(x.duration)]
            for x in sv[sv["interval"] == 0].itertuples() if x.realization in seeds}
        a = arches[arches["point"] == i]
        found = a[a["disks"] > 0]
        sizes = found["disks"].to_numpy(int)
        ratios = []  # span / height
        for span, ys in zip(found["span"], found["y"]):
            h = max(ys) + d / 2
            if h > 0 and span > 0:
                ratios.append(span / h)
        # Garcimartin et al. (PRE 82, 031306, 2010) give height / half-span per arch; here of
        # the disks' centres: the highest centre above the line through the two end disks'
        # centres, over half their horizontal distance (a semicircle of centres gives 1).
        halves = []
        for xs, ys in zip(found["x"], found["y"]):
            if len(xs) >= 2 and xs[-1] > xs[0]:
                base = 0.5 * (ys[0] + ys[-1])
                halves.append((max(ys) - base) / (0.5 * (xs[-1] - xs[0])))
        row.update({"arches_found": int(len(found)), "arch_jams": int(len(a)),
                    "arch_mean_size": float(sizes.mean()) if len(sizes) else None,
                    "arch_size_counts": {int(n): int(c) for n, c in
                                         zip(*np.unique(sizes, return_counts=True))},
                    "aspect_mean": float(np.mean(ratios)) if ratios else None,
                    "aspect_se": float(np.std(ratios, ddof=1) / math.sqrt(len(ratios)))
                    if len(ratios) > 1 else None,
                    "height_over_half_span": float(np.mean(halves)) if halves else None,
                    "height_over_half_span_se":
                    float(np.std(halves, ddof=1) / math.sqrt(len(halves)))
                    if len(halves) > 1 else None})
        rows.append(row)
    return sorted(rows, key=lambda x: x["D_over_d"])


def fit(rows):
    use = [r for r in rows if r["clogs"] >= MIN_CLOGS_FIT]
    if len(use) < 3:
        return None
    x = np.array([r["D_over_d"] ** 2 for r in use])
    y = np.array([math.log(r["mean_s"] + 1) for r in use])
    sig = np.array([r["se"] / (r["mean_s"] + 1) for r in use])
    w = 1 / sig ** 2
    X = np.vstack([np.ones_like(x), x]).T
    cov = np.linalg.inv(X.T @ (w[:, None] * X))
    a, b = cov @ (X.T @ (w * y))
    chi2 = float(np.sum(w * (y - a - b * x) ** 2))
    out = {"a": float(a), "a_err": float(math.sqrt(cov[0, 0])), "b": float(b),
           "b_err": float(math.sqrt(cov[1, 1])), "cov_ab": float(cov[0, 1]),
           "chi2_reduced": chi2 / (len(use) - 2) if len(use) > 2 else None,
           "outlets": [r["D_over_d"] for r in use]}
    out["critical"] = critical_fit(np.sqrt(x), y, w, chi2)
    return out


def critical_fit(R, y, w, chi2_exp):
    """The alternative of a critical outlet R_c (D/d) beyond which nothing clogs:
    ln(<s>+1) = ln A - gamma ln(R_c - R), weighted as the exponential fit; R_c scanned on a grid
    above the largest outlet (each R_c a linear fit), the least chi-square kept. AIC = chi2 +
    2 k (k = 2 exponential, 3 critical); a difference under 2 decides nothing. Needs 4 outlets."""
    if len(R) < 4:
        return None
    best = None
    for rc in R.max() + np.geomspace(1e-3, R_C_SCAN_SPAN, 4000):
        X = np.vstack([np.ones_like(R), -np.log(rc - R)]).T
        cov = np.linalg.inv(X.T @ (w[:, None] * X))
        c0, g = cov @ (X.T @ (w * y))
        c2 = float(np.sum(w * (y - c0 - g * X[:, 1]) ** 2))
        if best is None or c2 < best[0]:
            best = (c2, float(rc), float(g), float(c0))
    c2, rc, g, c0 = best
    d_aic = (c2 + 6) - (chi2_exp + 4)
    # At the scan's far end the law has no finite R_c to offer: it only mimics a smooth growth,
    # ln(<s>+1) close to linear in D/d, and a verdict for it is not one for a critical outlet.
    edge = bool(rc >= R.max() + R_C_SCAN_SPAN - 0.1)
    verdict = ("exponential" if d_aic > 2 else "undecided" if d_aic >= -2 else
               "exponential in D/d (no finite R_c)" if edge else "critical")
    return {"R_c": rc, "R_c_at_scan_edge": edge,
            "gamma": g, "ln_A": c0, "chi2": c2, "chi2_exponential": chi2_exp,
            "aic_critical_minus_exponential": d_aic, "verdict": verdict}


def mean_s_text(r):
    if r["mean_s"] is not None:
        return "%.4g +- %.2g [%.4g, %.4g]" % (r["mean_s"], r["se"], r["lo"], r["hi"])
    return "> %.4g (no clog)" % r["lo"] if r["grains"] > 0 else "-"


def table(name, rows):
    first = any("first" in r for r in rows)
    out = ["### %s" % name, "",
           "| D/d | realizations | clogs | <s> +- se [95 % CI] |" +
           (" first avalanches: clogs, <s> +- se |" if first else "") +
           " arches found / all clogs | mean arch size (disks) | span / height +- se |"
           " height / half-span +- se | sizes: CV, KS p (exponential) |",
           "|---|---|---|---|" + ("---|" if first else "") + "---|---|---|---|---|"]
    for r in rows:
        if r["realizations"] == 0:
            out.append("| %.2f | 0 | not run yet |" % r["D_over_d"])
            continue
        f = ""
        if first:
            q = r["first"]
            f = " %d, %s |" % (q["clogs"], "%.3g +- %.2g" % (q["mean_s"], q["se"])
                               if q["mean_s"] is not None else mean_s_text(q))
        out.append("| %.2f | %d | %d | %s |%s %d / %d | %s | %s | %s | %s |" % (
            r["D_over_d"], r["realizations"], r["clogs"], mean_s_text(r), f, r["arches_found"],
            r["arch_jams"], "%.2f" % r["arch_mean_size"] if r["arch_mean_size"] is not None else "-",
            "%.2f +- %.2f" % (r["aspect_mean"], r["aspect_se"]) if r["aspect_se"] else "-",
            "%.2f +- %.2f" % (r["height_over_half_span"], r["height_over_half_span_se"])
            if r["height_over_half_span_se"] else "-",
            "%.2f, %.2g" % (r["cv"], r["ks_p"]) if r["cv"] is not None else "-"))
    return "\n".join(out) + "\n"


def z_log(a, b):
    """ln(<s>_a / <s>_b) and its z (the standard error of ln <s> is 1 / sqrt(clogs)), or None."""
    if not a or not b or a["mean_s"] is None or b["mean_s"] is None:
        return None
    lr = math.log(a["mean_s"] / b["mean_s"])
    return {"ratio": a["mean_s"] / b["mean_s"], "ln_ratio": lr,
            "z": lr / math.hypot(1 / math.sqrt(a["clogs"]), 1 / math.sqrt(b["clogs"]))}


def protocol_effect(remove_arch, refill):
    """Per outlet in both stores: arch removal's steady <s> over refill's, and the realizations
    of the two with the same seed (the same fill): their first avalanches must be equal, size
    and duration, as both protocols run alike until the first clog."""
    out = []
    for f in refill:
        match = [r for r in remove_arch if abs(r["D_over_d"] - f["D_over_d"]) < 1e-6]
        if not match:
            continue
        r = match[0]
        out.append({"D_over_d": f["D_over_d"], "steady_over_refill": z_log(r, f),
                    "same_seed": same_seed(r["first_by_seed"], f["first_by_seed"])})
    return out


def same_seed(a, b):
    both = sorted(set(a) & set(b))
    return {"pairs": len(both), "equal": sum(1 for k in both if a[k] == b[k]),
            "differ": [k for k in both if a[k] != b[k]]}


def effect_table(effects):
    out = ["### The protocol's effect", "",
           "| D/d | arch removal / refill: <s> ratio (z of its log) |"
           " same seed: first avalanches equal |", "|---|---|---|"]
    for e in effects:
        x, q = e["steady_over_refill"], e["same_seed"]
        out.append("| %.2f | %s | %d of %d |" % (
            e["D_over_d"], "%.3g (z = %+.2f)" % (x["ratio"], x["z"]) if x else "-",
            q["equal"], q["pairs"]))
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("remove_arch")
    ap.add_argument("refill", nargs="?")
    ap.add_argument("--out", default=".")
    ap.add_argument("--keep-first", action="store_true",
                    help="count each arch-removal realization's first avalanche (from the settled "
                    "fill) in <s> too")
    args = ap.parse_args()
    for p in [args.remove_arch, args.refill]:
        if p and not os.path.exists(p):
            sys.exit("silo_validation.py: no such store: %s" % p)
    result = {"remove_arch": summarize(args.remove_arch, skip_first=not args.keep_first)}
    result["fit_remove_arch"] = fit(result["remove_arch"])
    result["band_remove_arch"] = band_check(result["remove_arch"])
    if args.refill:
        result["refill"] = summarize(args.refill)
        result["protocol_effect"] = protocol_effect(result["remove_arch"], result["refill"])
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "silo_validation.json"), "w") as fh:
        json.dump(result, fh, indent=1)
    md = table("Arch removal (steady state)", result["remove_arch"])
    f = result["fit_remove_arch"]
    if f:
        md += ("\nFit ln(<s>+1) = a + b (D/d)^2 over D/d = %s: a = %.3f +- %.3f, b = %.4f +- %.4f"
               " (covariance %.3g), reduced chi-square %.2f\n" % (
                   ", ".join("%.2f" % v for v in f["outlets"]), f["a"], f["a_err"], f["b"],
                   f["b_err"], f["cov_ab"], f["chi2_reduced"] if f["chi2_reduced"] is not None
                   else float("nan")))
        c = f["critical"]
        if c:
            md += ("Critical alternative ln(<s>+1) = ln A - gamma ln(R_c - D/d): R_c = %.3g%s, "
                   "gamma = %.3g, chi-square %.2f against %.2f; AIC(critical) - AIC(exponential) "
                   "= %+.2f: %s\n" % (c["R_c"], " (the scan's far end, %g beyond the largest "
                                       "outlet: no finite R_c)" % R_C_SCAN_SPAN
                                       if c["R_c_at_scan_edge"] else "",
                                       c["gamma"], c["chi2"], c["chi2_exponential"],
                                       c["aic_critical_minus_exponential"], c["verdict"]))
    bc = result["band_remove_arch"]
    if bc["rows"]:
        md += ("\nAgainst the experiments (Janda et al. 2008 and To 2005 as read off Goldberg et al."
               " 2018, Fig. 3a, the band widened by %.1f): %s\n" % (BAND_MARGIN, "; ".join(
                   "D/d %.1f: %.2f in [%.1f, %.1f] %s" % (x["D_over_d"], x["y"], x["lo"], x["hi"],
                                                         "inside" if x["inside"] else "OUTSIDE")
                   for x in bc["rows"])))
    if args.refill:
        md += "\n" + table("Refill after each clog", result["refill"])
        md += "\n" + effect_table(result["protocol_effect"])
    with open(os.path.join(args.out, "silo_validation.md"), "w") as fh:
        fh.write(md)
    print(md)

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(9, 3.6))
    for key, marker, name in (("remove_arch", "o", "arch removal"), ("refill", "s", "refill")):
        rows = [r for r in result.get(key, []) if r["mean_s"] is not None
                and (key != "remove_arch" or r["clogs"] >= MIN_CLOGS_FIT)]
        if not rows:
            continue
        x = [r["D_over_d"] ** 2 for r in rows]
        y = [math.log(r["mean_s"] + 1) for r in rows]
        e = [r["se"] / (r["mean_s"] + 1) for r in rows]
        ax.errorbar(x, y, yerr=e, fmt=marker, mfc="none" if key == "refill" else None,
                    label="%s (%s clogs)" % (name, "/".join(str(r["clogs"]) for r in rows)))
    few = [r for r in result["remove_arch"] if r["mean_s"] is not None
           and r["clogs"] < MIN_CLOGS_FIT]
    if few:  # drawn, but too few clogs to enter the fits: open
        ax.errorbar([r["D_over_d"] ** 2 for r in few], [math.log(r["mean_s"] + 1) for r in few],
                    yerr=[r["se"] / (r["mean_s"] + 1) for r in few], fmt="o", mfc="white",
                    color="C0", label="arch removal, fewer than %d clogs (%s): "
                    "not fitted" % (MIN_CLOGS_FIT, "/".join(str(r["clogs"]) for r in few)))
    bounds = [r for r in result["remove_arch"] if r["mean_s"] is None and r["grains"] > 0]
    for r in bounds:
        ax.annotate("", xy=(r["D_over_d"] ** 2, math.log(r["lo"] + 1) + 0.6),
                    xytext=(r["D_over_d"] ** 2, math.log(r["lo"] + 1)),
                    arrowprops={"arrowstyle": "->"})
    if bounds:
        ax.plot([r["D_over_d"] ** 2 for r in bounds], [math.log(r["lo"] + 1) for r in bounds],
                "^", color="k", label="95 % lower bound (no clog)")
    if f:
        xx = np.linspace(min(f["outlets"]) ** 2 * 0.95, max(f["outlets"]) ** 2 * 1.05, 50)
        ax.plot(xx, f["a"] + f["b"] * xx, "-", color="grey",
                label="a + b (D/d)$^2$: b = %.3f $\\pm$ %.3f" % (f["b"], f["b_err"]))
        c = f["critical"]
        if c:
            R = np.sqrt(xx)
            ax.plot(xx, c["ln_A"] - c["gamma"] * np.log(c["R_c"] - R), "--", color="grey",
                    label="ln A - $\\gamma$ ln(R$_c$ - D/d): %s" % (
                        "no finite R$_c$" if c["R_c_at_scan_edge"] else "R$_c$ = %.3g" % c["R_c"]))
    # The experiments and their band (issue 39)
    grid = sorted({k for tab in EXPERIMENTS.values() for k in tab})
    ax.fill_between([k * k for k in grid], [band(k)[0] for k in grid], [band(k)[1] for k in grid],
                    color="C2", alpha=0.15, lw=0,
                    label="experiments $\\pm$ %.1f (Goldberg et al. 2018, Fig. 3a)" % BAND_MARGIN)
    for (name, tab), m in zip(EXPERIMENTS.items(), ("v", "D")):
        ax.plot([k * k for k in tab], list(tab.values()), m, color="C2", ms=4, mfc="none",
                label=name)
    ax.set_xlabel("(D/d)$^2$")
    ax.set_ylabel("ln(<s> + 1)")
    ax.legend(fontsize=7)
    for r in result["remove_arch"]:
        c = r["arch_size_counts"]
        if not c:
            continue
        n = np.array(sorted(c))
        p = np.array([c[k] for k in n], float)
        bx.plot(n, p / p.sum(), "o", label="D/d = %.1f (%d arches)" % (r["D_over_d"], int(p.sum())))
    bx.set_xlabel("arch size (disks)")
    bx.set_ylabel("fraction of arches")
    bx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "silo_validation.png"), dpi=150,
                metadata={"Software": None})
    print("wrote %s/silo_validation.{json,md,png}" % args.out)


if __name__ == "__main__":
    main()
