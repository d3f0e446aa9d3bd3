#!/usr/bin/python3
"""The scale benchmark's table and figure (bench/scale.sh, issue 44).

usage: /usr/bin/python3 bench/scale_table.py SCALE.csv [--png FIGURE.png] [--title TEXT]

Prints a Markdown table: per operation and number of realizations the median wall time, CPU
time (user + system) and peak memory (max RSS) over the repeats, and the growth exponent b of time ~ N^b: the
least-squares slope of log(time) against log(N) over every size, and the slope between the two
largest sizes (where the fixed costs of starting a process matter least). --png draws the
medians on log-log axes (wall time solid, CPU time dashed) with a dotted line of slope 1.
"""
import argparse
import collections
import csv
import math
import statistics

ORDER = ["run", "resume_finished", "resume_killed", "status", "analyze", "export", "open_store"]


def slope(xs, ys):
    lx = [math.log(x) for x in xs]
    ly = [math.log(max(y, 1e-3)) for y in ys]
    mx, my = statistics.fmean(lx), statistics.fmean(ly)
    sxx = sum((a - mx) ** 2 for a in lx)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sxx if sxx > 0 else float("nan")


def load(path):
    rows = collections.defaultdict(list)
    loads = []
    with open(path) as f:
        for r in csv.DictReader(f):
            cpu = float(r["cpu_s"]) if "cpu_s" in r else float("nan")
            rows[(r["operation"], int(r["realizations"]))].append(
                (float(r["wall_s"]), float(r["max_rss_kb"]) / 1024.0, cpu))
            loads.append(float(r["load1"]))
    return rows, loads


def medians(rows):
    out = collections.defaultdict(dict)
    for (op, n), vals in rows.items():
        out[op][n] = (statistics.median(v[0] for v in vals),
                      statistics.median(v[1] for v in vals), len(vals),
                      statistics.median(v[2] for v in vals))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--png")
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    rows, loads = load(a.csv)
    med = medians(rows)
    sizes = sorted({n for op in med for n in med[op]})
    ops = [op for op in ORDER if op in med] + sorted(set(med) - set(ORDER))
    head = "| operation | " + " | ".join(f"N = {n:.0e}".replace("e+0", "e") for n in sizes)
    print(head + " | exponent, wall (all; last two) | exponent, CPU (all; last two) |")
    print("|---" * (len(sizes) + 3) + "|")
    for op in ops:
        cells = []
        for n in sizes:
            if n in med[op]:
                t, m, k, c = med[op][n]
                cells.append(f"{t:.3g} s ({c:.3g} s CPU), {m:.0f} MB")
            else:
                cells.append("—")
        ns = sorted(med[op])
        exps = []
        for col in (0, 3):
            ts = [med[op][n][col] for n in ns]
            b_all = slope(ns, ts) if len(ns) > 1 else float("nan")
            b_two = slope(ns[-2:], ts[-2:]) if len(ns) > 1 else float("nan")
            exps.append(f"{b_all:.2f}; {b_two:.2f}")
        print(f"| {op} | " + " | ".join(cells) + f" | {exps[0]} | {exps[1]} |")
    print(f"\nrepeats per cell: {min(len(v) for v in rows.values())}-"
          f"{max(len(v) for v in rows.values())}; load average (1 min) during the runs: "
          f"{min(loads):.1f}-{max(loads):.1f}, median {statistics.median(loads):.1f}")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (ax, am) = plt.subplots(1, 2, figsize=(11, 4.5))
        for op in ops:
            ns = sorted(med[op])
            line, = ax.loglog(ns, [med[op][n][0] for n in ns], "o-", label=op)
            ax.loglog(ns, [med[op][n][3] for n in ns], "x--", color=line.get_color())
            am.loglog(ns, [med[op][n][1] for n in ns], "o-", label=op)
        lo, hi = sizes[0], sizes[-1]
        ax.loglog([lo, hi], [1.0, hi / lo], "k:", label="slope 1")
        ax.set_xlabel("realizations in the store")
        ax.set_ylabel("wall time (s, median; dashed: CPU time)")
        am.set_xlabel("realizations in the store")
        am.set_ylabel("peak memory (MB, max RSS)")
        ax.legend(fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        am.grid(True, which="both", alpha=0.3)
        if a.title:
            fig.suptitle(a.title)
        fig.tight_layout()
        fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
