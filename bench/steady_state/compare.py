#!/usr/bin/python3
"""Issue 13: does the steady-state protocol reproduce the published one? Reads `campaign analyze
--json` of the two stores of bench/steady_state (published.toml, steady.toml) and prints, per
outlet, the jam rate and the flow rate of each with their standard errors and the difference in
standard errors (z). The published jam rate is given over the early half of each realization's
discharge (the analysis's early/late split, jammed periods excluded: the hopper is then at least
about half full, the range where the jam rate does not depend on the material left) and over
the whole discharge.  usage: compare.py CAMPAIGN_EXE PUBLISHED.h5 STEADY.h5"""
import json
import math
import subprocess
import sys


def analysis(exe, store):
    out = subprocess.run([exe, "analyze", store, "--json", "--no-write"], check=True,
                         capture_output=True, text=True).stdout
    return {p["D_cm"]: p for p in json.loads(out)["points"]}


def rate(n, exposure):
    return (n / exposure, math.sqrt(n) / exposure) if n > 0 else (float("nan"), float("nan"))


def z(a, b):
    return (a[0] - b[0]) / math.hypot(a[1], b[1])


def main():
    exe, pub_path, st_path = sys.argv[1:4]
    pub, st = analysis(exe, pub_path), analysis(exe, st_path)
    print("%-5s %-34s %-22s %-22s %6s" % ("D_cm", "quantity", "published", "steady state", "z"))
    for D in sorted(set(pub) & set(st)):
        p, s = pub[D], st[D]
        e = p["jam_time_dependence"]
        early = rate(e["n_early"], e["exposure_early"])
        whole = rate(p["n_uncensored"], p["total_observed_time"])
        steady = rate(s["n_uncensored"], s["total_observed_time"])
        flow_p = (p["discharge_rate"], p["discharge_rate_err"])
        flow_s = (s["discharge_rate"], s["discharge_rate_err"])
        rows = [("jam rate 1/s (published: early half)", early, steady),
                ("jam rate 1/s (published: whole run)", whole, steady),
                ("flow rate particles/s", flow_p, flow_s)]
        for name, a, b in rows:
            print("%-5g %-34s %7.3f +- %-9.3f %7.3f +- %-9.3f %+6.2f"
                  % (D, name, a[0], a[1], b[0], b[1], z(a, b)))
        print("%-5s jams: published %d (early half %d) in %d realizations, steady state %d in %d"
              % ("", p["n_uncensored"], e["n_early"], p["realizations"], s["n_uncensored"],
                 s["realizations"]))


if __name__ == "__main__":
    main()
