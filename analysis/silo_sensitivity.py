#!/usr/bin/python3
"""The flat silo's sensitivity map (issue 39, docs/validation.md "Sensitivity"): each lever's
effect on ln(<s>+1) per outlet and on the slope b.

usage: silo_sensitivity.py STORE.h5[@LEVER]|EARLIER.json [...] [--baseline JSON_OR_STORE]
                           [--json F] [--md F] [--png F]

Every point of the stores is one lever setting at one outlet: its lever is the point's label
less the outlet and the angle (`material.mu_r=0.1`; a point with nothing else is "baseline");
STORE.h5@LEVER puts LEVER before every point's own (a store whose campaign-wide settings differ
from the baseline's, which its labels do not show: `width.h5@hopper.width_cm=38.5`).
Per point, as silo_validation.py (whose estimator this reuses): the steady avalanches (each
realization's first, from the settled fill, left out), <s> = grains / clogs with its standard
error <s>/sqrt(clogs), y = ln(<s>+1) with sigma_y = se / (<s>+1), worker core-hours. Against the
baseline at the same outlet (the arch-removal campaign of docs/validation.md: by default
docs/figures/silo_validation.json's rows; or another store, or the points labelled baseline):
the difference dy and its z = dy / sqrt(sigma^2 + sigma_base^2). A lever with 3 or more outlets
of 5+ clogs gets its own fit of ln(<s>+1) = a + b (D/d)^2 (silo_validation.fit).
EARLIER.json (this script's --json of an earlier call) brings in the rows measured then, whose
stores may be gone (a machine's scratch space): each is kept as it was, unless a store given
here has the same lever at the same outlet; rows that were still waiting are left out.
"""
import argparse
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hopper_store import open_store  # noqa: E402
from silo_validation import EXPERIMENTS, band, fit, summarize_store  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_BASELINE = os.path.join(HERE, "..", "docs", "figures", "silo_validation.json")


def lever_of(label, common=""):
    """The label less its outlet and angle: 'D_cm=2.695 theta_deg=0 material.mu=0.2' ->
    'material.mu=0.2'; nothing left -> 'baseline'. `common` names what a store sets for all its
    points (a campaign-wide setting such as the silo's width, which no label shows): it comes
    first, and the point is no longer the baseline."""
    rest = [t for t in label.split() if not re.match(r"^(D_cm|theta_deg)=", t)]
    return " ".join(common.split() + rest) or "baseline"


def store_and_lever(arg):
    """'STORE.h5@hopper.width_cm=38.5 hopper.particles=1600' -> (path, common lever); a plain
    path -> (path, '')."""
    path, _, common = arg.partition("@")
    return path, common.strip()


def with_log(row):
    s, se = row["mean_s"], row["se"]
    row["y"] = math.log(s + 1) if s is not None and math.isfinite(s) else None
    row["y_err"] = se / (s + 1) if row["y"] is not None and se is not None else None
    return row


def rows_of(path, common=""):
    with open_store(path) as s:
        rows = summarize_store(s, path, skip_first=True)
        r = s.realizations
        hours = {}
        for i, pt in s.points.iterrows():
            hours[pt["label"]] = float(r[r["point"] == i]["task_seconds"].sum()) / 3600
    for row in rows:
        row["lever"] = lever_of(row["label"], common)
        row["core_hours"] = hours.get(row["label"], 0.0)
        row.pop("first_by_seed", None)
        with_log(row)
    return rows


def baseline_rows(spec, rows):
    if spec and spec.endswith(".h5"):
        return [r for r in rows_of(spec) if r["lever"] == "baseline"]
    own = [r for r in rows if r["lever"] == "baseline"]
    if own and not spec:
        return own
    with open(spec or DEFAULT_BASELINE) as fh:
        return [with_log(dict(r)) for r in json.load(fh)["remove_arch"]]


def compare(rows, base):
    """Adds dy and z against the baseline row of the same outlet (D/d to 1e-3)."""
    for row in rows:
        b = next((x for x in base if abs(x["D_over_d"] - row["D_over_d"]) < 1e-3), None)
        row["base_y"] = b["y"] if b else None
        if b and row["y"] is not None and row["clogs"] > 0 and b["y"] is not None:
            row["dy"] = row["y"] - b["y"]
            row["z"] = row["dy"] / math.hypot(row["y_err"], b["y_err"])
        else:
            row["dy"] = row["z"] = None
    return rows


def lever_fits(rows):
    out = {}
    for lever in sorted({r["lever"] for r in rows}):
        f = fit([r for r in rows if r["lever"] == lever])
        if f:
            f.pop("critical", None)
            out[lever] = f
    return out


def fmt(v, spec="%.2f"):
    return "-" if v is None else spec % v


def markdown(rows, fits):
    lines = ["| lever | D/d | realizations | clogs | <s> +- se | ln(<s>+1) +- se | baseline | "
             "difference | z | core-hours |", "|---|---|---|---|---|---|---|---|---|---|"]
    waiting = [r for r in rows if not r["realizations"]]
    for r in sorted(rows, key=lambda r: (r["D_over_d"], r["lever"])):
        if not r["realizations"]:
            continue
        ms = "-" if not r["clogs"] else "%.4g +- %.2g" % (r["mean_s"], r["se"])
        lines.append("| %s | %.2f | %d | %d | %s | %s | %s | %s | %s | %.2f |" % (
            r["lever"], r["D_over_d"], r["realizations"], r["clogs"], ms,
            "-" if r["y"] is None or not r["clogs"] else "%.2f +- %.2f" % (r["y"], r["y_err"]),
            fmt(r["base_y"]), fmt(r["dy"], "%+.2f"), fmt(r["z"], "%+.1f"), r["core_hours"]))
    if waiting:
        lines += ["", "Nothing stored yet: " + "; ".join(
            "%s at D/d %.2f" % (r["lever"], r["D_over_d"])
            for r in sorted(waiting, key=lambda r: (r["D_over_d"], r["lever"]))) + "."]
    if fits:
        lines += ["", "| lever | outlets | b +- se | a +- se |", "|---|---|---|---|"]
        for lever, f in fits.items():
            lines.append("| %s | %s | %.3f +- %.3f | %.2f +- %.2f |" % (
                lever, ", ".join("%.1f" % x for x in f["outlets"]), f["b"], f["b_err"], f["a"],
                f["a_err"]))
    return "\n".join(lines) + "\n"


def kappa_label(value):
    """A collision time's stiffness as kappa = k_n d / (m g), which goes as 1 / tau_c^2: the
    published photoelastic disks' 7.3e-4 s are kappa = 7.3e3 (docs/validation.md)."""
    return "kappa %.2g (%s s)" % (7.3e3 * (7.3e-4 / float(value)) ** 2, value)


def figure(rows, base, fits, path):
    """ln(<s>+1) against (D/d)^2, one panel per lever family (the setting's name): the baseline
    and its fit, each lever's points with their errors (joined where it has several outlets, its
    fit drawn where it has one), the experiments and the band the model is held to."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def family(lever):
        return lever.split("=")[0] if lever.count("=") == 1 else lever.split("=")[0] + " + ..."

    levers = sorted({r["lever"] for r in rows if r["lever"] != "baseline" and r["clogs"]})
    fams = sorted({family(lv) for lv in levers})
    if not fams:
        raise SystemExit("silo_sensitivity.py: no lever with clogs to draw")
    ncol = min(3, len(fams))
    nrow = (len(fams) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.4 * nrow), squeeze=False,
                             sharex=True, sharey=True)
    xs = sorted({k for tab in EXPERIMENTS.values() for k in tab})
    bx = [x * x for x in xs]
    bands = [band(x) for x in xs]
    bfit = fit(base)
    for ax, fam in zip(axes.flat, fams):
        ax.fill_between(bx, [b[0] for b in bands], [b[1] for b in bands], color="0.88",
                        label="experiments +- 0.5")
        for name, tab in EXPERIMENTS.items():
            ks = sorted(tab)
            ax.plot([k * k for k in ks], [tab[k] for k in ks], "k:" if "To" in name else "k--",
                    lw=0.8, label=name)
        bb = [r for r in base if r.get("y") is not None]
        ax.errorbar([r["D_over_d"] ** 2 for r in bb], [r["y"] for r in bb],
                    yerr=[r["y_err"] for r in bb], fmt="s", color="0.4", ms=4,
                    label="baseline (kappa 7.3e3)")
        if bfit:
            ax.plot(bx, [bfit["a"] + bfit["b"] * x for x in bx], "-", color="0.4", lw=0.8)
        for lever in [lv for lv in levers if family(lv) == fam]:
            pts = sorted((r for r in rows if r["lever"] == lever and r["clogs"]),
                         key=lambda r: r["D_over_d"])
            x = [r["D_over_d"] ** 2 for r in pts]
            name = lever.split(fam + "=")[-1] if family(lever) == fam else lever
            if fam == "material.collision_time_s":
                name = kappa_label(name)
            line = ax.errorbar(x, [r["y"] for r in pts], yerr=[r["y_err"] for r in pts], fmt="o-",
                               ms=4, lw=0.8, capsize=2, label=name)
            f = fits.get(lever)
            if f:
                ax.plot(bx, [f["a"] + f["b"] * v for v in bx], "-", lw=1.4,
                        color=line[0].get_color(), alpha=0.6)
        ax.set_title(fam, fontsize=9)
        ax.legend(fontsize=6, loc="upper left")
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(fams):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("(D/d)^2")
    for ax in axes[:, 0]:
        ax.set_ylabel("ln(<s>+1)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("stores", nargs="+")
    ap.add_argument("--baseline", help="a JSON of silo_validation.py or an arch-removal store "
                    "(default: the stores' own baseline points, else %s)" % DEFAULT_BASELINE)
    ap.add_argument("--json")
    ap.add_argument("--md")
    ap.add_argument("--png", help="the figure: ln(<s>+1) against (D/d)^2 per lever family")
    a = ap.parse_args()
    stores = [store_and_lever(p) for p in a.stores]
    for p, _ in stores:
        if not os.path.exists(p):
            sys.exit("silo_sensitivity.py: no store %s" % p)
    rows = [r for p, common in stores if not p.endswith(".json") for r in rows_of(p, common)]
    have = {(r["lever"], round(r["D_over_d"], 3)) for r in rows}
    for p, _ in stores:
        if p.endswith(".json"):
            with open(p) as fh:
                earlier = [r for r in json.load(fh)["rows"] if r["realizations"]]
            rows += [r for r in earlier if (r["lever"], round(r["D_over_d"], 3)) not in have]
    base = baseline_rows(a.baseline, rows)
    rows = compare(rows, base)
    fits = lever_fits(rows)
    md = markdown(rows, fits)
    sys.stdout.write(md)
    if a.md:
        with open(a.md, "w") as fh:
            fh.write(md)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"rows": rows, "fits": fits}, fh, indent=1)
    if a.png:
        figure(rows, base, fits, a.png)


if __name__ == "__main__":
    main()
