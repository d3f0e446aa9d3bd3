#!/usr/bin/python3
"""Error against cost (the Pareto front) from bench_accuracy CSV files (issue 6).

    accuracy_plot.py A.csv [B.csv ...] [-o accuracy.png]

Rows are keyed by (scheme, delta); a later file fills the fields an earlier one left empty, so
the slow discharge part can be run separately (bench_accuracy --parts hopper) and merged.
Cost axis: wall seconds per simulated second of the settled column (400 disks), measured in
the same run as the errors. "Worst error" is the largest of the deterministic errors
(restitution, contact time, rebound spin, energy, column force); the discharge rate has a
statistical error and is drawn on its own with error bars of one standard error.
"""
import argparse
import csv
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

DETERMINISTIC = [
    ("err_restitution", "restitution e"),
    ("err_contact_time", "contact time"),
    ("err_omega", "rebound spin"),
    ("err_energy", "energy (e_n=1, mu=0)"),
    ("err_column_force", "column wall force"),
]


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
                    elif k == "failure":
                        if v:
                            cur["failure"] = (cur.get("failure", "") + " " + v).strip()
                    elif num(v) is not None and cur.get(k) is None:
                        cur[k] = num(v)
    return [rows[k] for k in sorted(rows)]


def worst(r):
    errs = [r.get(k) for k, _ in DETERMINISTIC]
    if r.get("status") == "unstable" or any(e is None for e in errs):
        return None
    return max(errs)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", nargs="+")
    ap.add_argument("-o", "--out", default="accuracy.png")
    a = ap.parse_args()
    rows = load(a.csv)

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 5.2))
    markers = {"gear4": "o", "verlet": "s"}
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for scheme, mk in markers.items():
        sr = [r for r in rows if r["scheme"] == scheme and r.get("cost_column")]
        ls = "-" if scheme == "gear4" else "--"
        for (key, label), c in zip(DETERMINISTIC, colors):
            pts = [(r["cost_column"], r[key]) for r in sr if r.get(key)]
            if pts:
                ax1.plot(*zip(*pts), ls=ls, marker=mk, color=c, ms=4,
                         label=f"{label} ({scheme})")
        rp = [r for r in sr if r.get("err_rate") is not None]
        if rp:
            ax1.errorbar([r["cost_column"] for r in rp], [r["err_rate"] for r in rp],
                         yerr=[r.get("err_rate_se") or 0 for r in rp], ls=ls, marker=mk,
                         color=colors[5], ms=4, capsize=2,
                         label=f"discharge rate ({scheme}, +-1 se)")
    ax1.axhline(0.01, color="k", lw=0.8, ls=":")
    ax1.set(xscale="log", yscale="log", xlabel="cost: wall s per simulated s (column, 400 disks)",
            ylabel="relative error", title="each observable (unstable settings omitted)")
    ax1.legend(fontsize=6, ncol=2)

    pts = [(r["cost_column"], worst(r), r) for r in rows
           if r.get("cost_column") and worst(r) is not None]
    for scheme, mk in markers.items():
        p = [(c, w) for c, w, r in pts if r["scheme"] == scheme]
        ax2.plot(*zip(*p), marker=mk, ls="none", label=scheme, ms=6)
        for c, w, r in pts:
            if r["scheme"] == scheme:
                ax2.annotate(f"{r['delta']:g}", (c, w), fontsize=7, xytext=(3, 3),
                             textcoords="offset points")
    front, best = [], math.inf
    for c, w, r in sorted(pts, key=lambda t: t[0]):
        if w < best:
            front.append((c, w, r))
            best = w
    ax2.step([c for c, _, _ in front], [w for _, w, _ in front], where="post", color="k",
             lw=1, label="Pareto front")
    ax2.axhline(0.01, color="k", lw=0.8, ls=":", label="1 %")
    ax2.set(xscale="log", yscale="log", xlabel="cost: wall s per simulated s (column, 400 disks)",
            ylabel="worst deterministic error", title="worst error vs cost (labels: delta)")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)

    print("Pareto front (cost s/s, worst error, setting):")
    for c, w, r in front:
        print(f"  {c:8.3g}  {w:9.3e}  {r['scheme']} delta={r['delta']:g}")
    ok = [(c, w, r) for c, w, r in pts if w < 0.01]
    if ok:
        c, w, r = min(ok, key=lambda t: t[0])
        print(f"cheapest with every deterministic error < 1 %: {r['scheme']} delta={r['delta']:g}"
              f" (worst {w:.2e}, cost {c:.3g} s/s)")
    else:
        print("no measured setting keeps every deterministic error < 1 %")
    for r in rows:
        if r.get("status") == "unstable":
            print(f"unstable: {r['scheme']} delta={r['delta']:g}: {r.get('failure', '')[:90]}")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
