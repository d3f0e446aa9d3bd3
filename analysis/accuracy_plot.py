#!/usr/bin/python3
"""Error against cost (the Pareto front) from a bench_accuracy CSV (issue 6).

    /usr/bin/python3 analysis/accuracy_plot.py bench/results/accuracy.csv \
        -o bench/results/accuracy_pareto.png

Rows are keyed by (scheme, delta); when several files are given, a later file fills the fields
an earlier one left empty. Cost axis: CPU seconds per simulated second of the discharging
400-disk hopper, measured in the same run as the errors. The decision (columns chosen_default,
chosen_all_en) is made by bench_accuracy; this script draws it and prints the Pareto front.

Left: the worst deterministic error (phase-averaged restitution, contact-duration and spin bias,
energy drift, column force) at the default material (filled) and over all e_n (open). Right:
every observable of each scheme; the statistical ones (bottom profile, discharge rate) with
their noise level (2 standard errors) dotted.
"""
import argparse
import csv
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

DET_DEFAULT = ["bias_e", "bias_tc", "bias_w", "err_energy", "err_column_force"]
DET_ALL = ["bias_e_all", "bias_tc_all", "bias_w_all", "err_energy", "err_column_force"]
OBSERVABLES = [  # key, label, error-bar key (2 se drawn) or None
    ("bias_e", "restitution bias", None),
    ("bias_tc", "contact-duration bias", None),
    ("bias_w", "rebound-spin bias", None),
    ("err_energy", "energy drift (e_n=1, mu=0)", None),
    ("err_column_force", "column wall force", None),
    ("err_profile", "bottom profile (L2)", "err_profile_noise"),
    ("err_rate", "discharge rate", "err_rate_se"),
]
SCHEMES = {"gear4": ("o", "C0"), "verlet": ("s", "C3")}
LABEL_OFFSET = {"gear4": (5, 5), "verlet": (-16, -13)}  # delta labels, points
FLOOR = 1e-5  # errors below this are drawn at this value (log axis)


def num(x):
    try:
        v = float(x)
        return v if math.isfinite(v) else None
    except (TypeError, ValueError):
        return None


def load(paths):
    rows = {}
    for path in paths:
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                key = (r["scheme"], float(r["delta"]))
                cur = rows.setdefault(key, {"scheme": key[0], "delta": key[1]})
                for k, v in r.items():
                    if k in ("scheme", "delta"):
                        continue
                    if k == "status":
                        if cur.get("status") != "unstable":
                            cur["status"] = v
                    elif num(v) is not None:
                        cur.setdefault(k, num(v))
                    elif v:
                        cur.setdefault(k, v)
    return [rows[k] for k in sorted(rows)]


def worst(r, keys):
    errs = [r.get(k) for k in keys]
    if r.get("status") == "unstable" or any(e is None for e in errs):
        return None
    return max(errs)


def before_after(old_csv, new_csv, out):
    """Worst deterministic error (all e_n) against cost relative to verlet delta = 200 of the
    same run (runs on a shared machine differ in absolute cost): before and after the contact
    corrections (issue 12)."""
    fig, ax = plt.subplots(figsize=(5.2, 3.8))
    for path, tag, style in ((old_csv, "without corrections", "-"),
                             (new_csv, "with contact corrections", "--")):
        rows = load([path])
        base = next((r.get("cost_hopper") for r in rows
                     if r["scheme"] == "verlet" and r["delta"] == 200.0), None)
        if not base:
            continue
        for scheme, (mk, col) in SCHEMES.items():
            sr = [r for r in rows if r["scheme"] == scheme and r.get("cost_hopper")
                  and worst(r, DET_ALL) is not None]
            if not sr:
                continue
            ax.plot([r["cost_hopper"] / base for r in sr],
                    [100 * max(worst(r, DET_ALL), FLOOR) for r in sr], marker=mk, color=col, ls=style,
                    mfc="none" if style == "--" else col, label=f"{scheme}, {tag}")
            for r in sr:
                ax.annotate(f"{r['delta']:g}", (r["cost_hopper"] / base, 100 * worst(r, DET_ALL)),
                            fontsize=7, xytext=(4, 3), textcoords="offset points")
    ax.axhline(1.0, color="grey", lw=0.8, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("cost per simulated second / verlet delta = 200 (same run)")
    ax.set_ylabel("worst deterministic error, all e_n (%)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=150)
    print(f"wrote {out}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", nargs="+")
    ap.add_argument("-o", "--out", default="accuracy_pareto.png")
    ap.add_argument("--before-after", action="store_true",
                    help="two CSVs: without and with the contact corrections; draws the worst "
                         "error against the cost relative to verlet delta = 200 of each run")
    a = ap.parse_args()
    if a.before_after:
        if len(a.csv) != 2:
            ap.error("--before-after takes two CSV files: without and with the corrections")
        return before_after(a.csv[0], a.csv[1], a.out)
    rows = [r for r in load(a.csv) if r.get("cost_hopper")]

    fig = plt.figure(figsize=(16, 7.4))
    gs = fig.add_gridspec(1, 3, width_ratios=[1.25, 1, 1])
    ax = fig.add_subplot(gs[0])
    for scheme, (mk, col) in SCHEMES.items():
        sr = [r for r in rows if r["scheme"] == scheme]
        pd = [(r["cost_hopper"], worst(r, DET_DEFAULT), r) for r in sr]
        pd = [p for p in pd if p[1] is not None]
        pa = [(r["cost_hopper"], worst(r, DET_ALL)) for r in sr]
        pa = [p for p in pa if p[1] is not None]
        if pd:
            ax.plot([p[0] for p in pd], [max(p[1], FLOOR) for p in pd], marker=mk, color=col,
                    ms=7, lw=1.2, label=f"{scheme}: e_n = 0.5 (default material)")
            for c, w, r in pd:
                ax.annotate(f"{r['delta']:g}", (c, max(w, FLOOR)), fontsize=9, color=col,
                            xytext=LABEL_OFFSET[scheme], textcoords="offset points")
        if pa:
            ax.plot([p[0] for p in pa], [max(p[1], FLOOR) for p in pa], marker=mk, color=col,
                    mfc="none", ms=7, lw=0.8, ls="--", label=f"{scheme}: all e_n in {{0.3, 0.5, 0.8}}")
    for key, style, text in [("chosen_default", dict(s=420, facecolors="none", edgecolors="k",
                                                       linewidths=2.0), "chosen (e_n = 0.5)"),
                             ("chosen_all_en", dict(s=700, facecolors="none", edgecolors="g",
                                                      linewidths=1.5, linestyle=":"),
                              "chosen (all e_n)")]:
        for r in rows:
            if r.get(key) == 1:
                keys = DET_DEFAULT if key == "chosen_default" else DET_ALL
                ax.scatter([r["cost_hopper"]], [max(worst(r, keys), FLOOR)], zorder=5,
                           label=f"{text}: {r['scheme']} delta = {r['delta']:g}", **style)
    ax.axhline(0.01, color="k", lw=1.0, ls=":", label="1 %")
    ax.set(xscale="log", yscale="log",
           xlabel="cost: CPU s per simulated s (discharging 400-disk hopper)",
           ylabel="worst deterministic relative error",
           title="worst error vs cost (labels: delta = tau_c / dt)")
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8, loc="lower left")

    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    ylim = [1.0, 1e-2]
    axes = []
    for k, (scheme, (mk, _)) in enumerate(SCHEMES.items()):
        axs = fig.add_subplot(gs[k + 1], sharey=axes[0] if axes else None)
        axes.append(axs)
        sr = [r for r in rows if r["scheme"] == scheme and r.get("status") != "unstable"]
        for (key, label, se), col in zip(OBSERVABLES, colors):
            pts = [(r["cost_hopper"], r.get(key), r.get(se) if se else None, r["delta"])
                   for r in sr if r.get(key) is not None and r.get("extra", 0) != 1]
            if not pts:
                continue
            xs = [p[0] for p in pts]
            ys = [max(p[1], FLOOR) for p in pts]
            ylim[0] = min(ylim[0], min(ys))
            ylim[1] = max(ylim[1], max(ys))
            axs.plot(xs, ys, marker=mk, color=col, ms=4, lw=1, label=label)
            if se:  # statistical: its noise level (2 standard errors) as a thin dotted line
                noise = [max(2 * (p[2] or 0), FLOOR) for p in pts]
                axs.plot(xs, noise, marker="_", color=col, ms=8, lw=0.8, ls=":",
                         label=label + ": 2 se (noise)")
                ylim[1] = max(ylim[1], max(noise))
        for r in sr:
            if r.get("extra", 0) != 1:
                axs.annotate(f"{r['delta']:g}", (r["cost_hopper"], 1.5 * FLOOR), fontsize=7,
                             ha="center", color="0.4")
        axs.axhline(0.01, color="k", lw=1.0, ls=":")
        axs.set(xscale="log", yscale="log", xlabel="cost: CPU s per simulated s",
                title=f"{scheme}: each observable (e_n = 0.5)")
        axs.grid(True, which="both", alpha=0.25)
        if k == 0:
            axs.set_ylabel("relative error")
        if k == 0:
            handles, labels = axs.get_legend_handles_labels()
    xs = [r["cost_hopper"] for r in rows if r.get("status") != "unstable"]
    for axs in [ax] + axes:
        axs.set_xlim(min(xs) / 1.4, max(xs) * 1.6)
    for axs in axes:
        axs.set_ylim(FLOOR, 3 * ylim[1])
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    fig.legend(handles, labels, loc="lower center", bbox_to_anchor=(0.68, 0.0), ncol=3,
               fontsize=8, title="right panels (thin dotted: noise level, 2 standard errors)",
               title_fontsize=8)
    fig.savefig(a.out, dpi=110)

    pts = sorted(((r["cost_hopper"], worst(r, DET_DEFAULT), r) for r in rows
                  if worst(r, DET_DEFAULT) is not None), key=lambda t: t[0])
    front, best = [], math.inf
    for c, w, r in pts:
        if w < best:
            front.append((c, w, r))
            best = w
    print("Pareto front, worst deterministic error at e_n = 0.5 (cost s/s, error, setting):")
    for c, w, r in front:
        print(f"  {c:8.3g}  {w:9.3e}  {r['scheme']} delta={r['delta']:g}")
    for key, text in [("chosen_default", "e_n = 0.5"), ("chosen_all_en", "all e_n")]:
        ch = [r for r in rows if r.get(key) == 1]
        print(f"chosen ({text}): " + (", ".join(f"{r['scheme']} delta={r['delta']:g}"
                                              for r in ch) or "none"))
    for r in load(a.csv):
        if r.get("status") == "unstable":
            print(f"unstable: {r['scheme']} delta={r['delta']:g}: {r.get('failure', '')[:90]}")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
