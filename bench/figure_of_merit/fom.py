#!/usr/bin/python3
"""Issue 13, part 5: jams observed per core-hour, published protocol vs steady state, at full
size (bench/figure_of_merit/README.md). Reads the two stores and a CPU log of the two
`campaign run` processes (poll.sh: one line every 2 s with unix time, pid, utime + stime in clock
ticks, ticks per second, the sweep file), assigns each realization the CPU its process used
between the previous result and its own (finished_unix), and prints:
  - per protocol and outlet: core-seconds, settle share, flowing seconds, jams, shakes;
  - flowing seconds per core-hour (the steady state's with the settle amortised: long runs);
  - the jam rate per flowing second from every jam seen at that outlet in both protocols
    (validated equal in a full hopper: bench/steady_state), with its 95 % Poisson interval;
  - jams per core-hour = rate x flowing seconds per core-hour, for each protocol;
  - the core-hours for a 10 % relative half-width of tau's 95 % interval (390 jams) at
    D = 2.7 ... 3.5 cm, ln(rate) and the cost per flowing second interpolated/extrapolated
    linearly in D from the two measured outlets.
usage: fom.py PUBLISHED.h5 STEADY.h5 CPU.log"""
import math
import sys

import h5py
import numpy as np
from scipy.stats import chi2


def cpu_series(log, tag):
    t, c = [], []
    for line in open(log):
        f = line.split()
        if len(f) >= 5 and f[4].endswith(tag):
            t.append(float(f[0]))
            c.append(int(f[2]) / int(f[3]))
    return np.array(t), np.array(c)


def realizations(path, log, tag):
    t, c = cpu_series(log, tag)
    f = h5py.File(path, "r")
    r, d = f["realizations"], f["realizations/diagnostics"]
    labels = f["points/label"].asstr()[:]
    order = np.argsort(r["finished_unix"][:])
    out, before = [], 0.0
    for i in order:
        done = r["finished_unix"][i]
        cpu = float(np.interp(done, t, c))  # the log's last line is within 2 s of the end
        s, n = r["survival_start"][i], r["survival_length"][i]
        out.append({
            "D": float(labels[r["point"][i]].split()[0].split("=")[1]),
            "cpu": cpu - before, "jams": int(r["n_jams"][i]), "shakes": int(r["n_shakes"][i]),
            "flow": float(f["ragged/survival_times"][s:s + n].sum()),
            "settle_share": d["settle_steps"][i] / d["steps"][i],
            "empty": float(r["empty_time"][i]) if r["has_empty_time"][i] else None,
            "wall": float(r["task_seconds"][i])})
        before = cpu
    return out


def poisson95(n, T):
    lo = chi2.ppf(0.025, 2 * n) / (2 * T) if n > 0 else 0.0
    hi = chi2.ppf(0.975, 2 * n + 2) / (2 * T)
    return lo, hi


def jams_for(rel=0.1):
    r = 1
    while True:
        lo = 2 * r / chi2.ppf(0.975, 2 * r)
        hi = 2 * r / chi2.ppf(0.025, 2 * r)
        if (hi - lo) / 2 <= rel:
            return r
        r += 1


def main():
    pub = realizations(sys.argv[1], sys.argv[3], "published.toml")
    st = realizations(sys.argv[2], sys.argv[3], "steady.toml")
    print("%-10s %5s %9s %8s %9s %5s %6s %9s" % ("protocol", "D_cm", "core-s", "settle",
                                                "flow (s)", "jams", "shakes", "empty (s)"))
    for name, rows in (("published", pub), ("steady", st)):
        for x in rows:
            print("%-10s %5.1f %9.1f %7.0f%% %9.2f %5d %6d %9s" % (
                name, x["D"], x["cpu"], 100 * x["settle_share"], x["flow"], x["jams"],
                x["shakes"], "%.2f" % x["empty"] if x["empty"] else "-"))
    need = jams_for(0.1)
    print("\njams for a 10 %% relative half-width of tau's 95 %% interval: %d" % need)
    Ds = sorted(set(x["D"] for x in pub) & set(x["D"] for x in st))
    fit = {}
    print("\n%5s %28s %14s %14s %24s %24s" % ("D_cm", "jam rate 1/s [95%]", "flow-s/ch pub",
                                             "flow-s/ch ss", "jams/core-h published",
                                             "jams/core-h steady"))
    for D in Ds:
        p = [x for x in pub if x["D"] == D]
        s = [x for x in st if x["D"] == D]
        jams = sum(x["jams"] for x in p + s)
        flow = sum(x["flow"] for x in p + s)
        lam = jams / flow
        lo, hi = poisson95(jams, flow)
        # Published: everything a realization costs (fill, settle, discharge, shakes).
        fpub = sum(x["flow"] for x in p) / (sum(x["cpu"] for x in p) / 3600)
        # Steady state, long runs: the settle amortised, shakes included.
        run_cpu = sum(x["cpu"] * (1 - x["settle_share"]) for x in s)
        fst = sum(x["flow"] for x in s) / (run_cpu / 3600)
        fit[D] = (lam, lo, hi, fpub, fst)
        print("%5.1f %8.3f [%6.3f, %6.3f] (%d) %14.0f %14.0f %8.1f [%5.1f, %6.1f] %8.1f [%5.1f, %6.1f]"
              % (D, lam, lo, hi, jams, fpub, fst, lam * fpub, lo * fpub, hi * fpub, lam * fst,
                 lo * fst, hi * fst))
    if len(Ds) == 2:
        (D1, a), (D2, b) = sorted(fit.items())
        print("\ncore-hours for %d jams (10 %% CI on tau), ln(rate) and cost linear in D "
              "between/beyond %.1f and %.1f cm (rates with 95 %% intervals where measured):"
              % (need, D1, D2))
        print("%5s %12s %20s %20s" % ("D_cm", "rate 1/s", "published core-h", "steady core-h"))
        for D in (2.7, 2.9, 3.1, 3.3, 3.5):
            w = (D - D1) / (D2 - D1)
            if a[0] > 0 and b[0] > 0:
                lam = math.exp((1 - w) * math.log(a[0]) + w * math.log(b[0]))
            else:
                lam = float("nan")
            fpub = (1 - w) * a[3] + w * b[3]
            fst = (1 - w) * a[4] + w * b[4]
            print("%5.1f %12.4g %20.3g %20.3g" % (D, lam, need / (lam * fpub), need / (lam * fst)))


if __name__ == "__main__":
    main()
