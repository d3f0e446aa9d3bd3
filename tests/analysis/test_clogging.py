#!/usr/bin/python3
"""analysis/clogging.py arrests, levels and question on synthetic stores
(hopper_store.Store.from_frames) whose answers are known by hand (issue 23): arrests counted by
status, tau (censored mean: flow time / jams) and jams per realization by group, and tau per
interval after an ordinary shake and after a grown one, the comparison that does not select
realizations by their number of jams; the published protocol's jams by fill level; the open
question's table (bounds, core-hours, the store's fits in cm); the plan that would decide it
(Poisson decision probabilities, the time to decide beyond D_c).

usage: test_clogging.py SOURCE_DIR     (exit 0 pass, 1 fail, 77 skipped: no pandas/scipy)
"""
import math
import warnings
import os
import sys

try:
    import numpy as np
    import pandas as pd
    from scipy import stats
except ImportError:
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hand_checks import Checks, analysis_on_path  # noqa: E402

analysis_on_path()
import clogging  # noqa: E402
from hopper_store import Store  # noqa: E402

check = Checks("clogging")


# Realization 0: two jams, each cleared by one shake; intervals 2 s, 3 s, then 5 s censored.
# Realization 1: three jams, the second needing 3 shakes; intervals 1, 4, 2 s, then 6 s censored.
# Realization 2: arrested after its only jam (10 shakes): one interval of 7 s.
realizations = pd.DataFrame({"point": [0, 0, 0], "realization": [0, 1, 2],
                             "status": ["complete", "complete", "arrested"],
                             "n_jams": [2, 3, 1]})
rows = [(0, 0, 0, 2.0, 1), (0, 0, 1, 3.0, 1), (0, 0, 2, 5.0, 0),
        (0, 1, 0, 1.0, 1), (0, 1, 1, 4.0, 1), (0, 1, 2, 2.0, 1), (0, 1, 3, 6.0, 0),
        (0, 2, 0, 7.0, 1)]
survival = pd.DataFrame(rows, columns=["point", "realization", "interval", "duration", "event"])
jams = pd.DataFrame({"point": [0] * 6, "realization": [0, 0, 1, 1, 1, 2],
                     "shakes": [1, 1, 1, 3, 1, 10]})
store = Store.from_frames("synthetic", {"realizations": realizations, "survival": survival,
                                        "jams": jams, "arches": pd.DataFrame(),
                                        "points": pd.DataFrame()})
r = clogging.arrest_summary(store, "synthetic")

check(r["by_status"] == {"complete": 2, "arrested": 1}, "statuses: %s" % r["by_status"])
check(r["shakes_needed"] == {1: 4, 3: 1, 10: 1}, "shakes per jam: %s" % r["shakes_needed"])
g = r["groups"]
# all: 30 s of flow, 6 jams -> 5.0 s; no grown shake: realization 0 alone, 10 s / 2 jams -> 5.0;
# grown shake: realizations 1 and 2, 20 s / 4 jams -> 5.0.
check(abs(g["all"]["tau"]["mean"] - 30.0 / 6) < 1e-12, "tau of all: %s" % g["all"]["tau"])
check(g["all"]["arrested"] == 1, "one arrested")
check(g["no grown shake"]["realizations"] == 1 and g["grown shake"]["realizations"] == 2,
      "groups by realization: %s" % {k: v["realizations"] for k, v in g.items()})
check(abs(g["grown shake"]["jams_per_realization"] - 2.0) < 1e-12, "jams per grown realization")
# Per interval: after one shake, intervals (r0, 1) 3 s, (r0, 2) 5 s censored, (r1, 1) 4 s,
# (r1, 3) 6 s censored -> 18 s / 2 jams = 9.0 s; after a grown shake, (r1, 2) 2 s -> 2.0 s.
# The arrested realization's jam restarted nothing, so no interval follows it.
iv = r["intervals"]
check(iv["after one shake"]["intervals"] == 4 and
      abs(iv["after one shake"]["tau"]["mean"] - 9.0) < 1e-12,
      "tau after one shake: %s" % iv.get("after one shake"))
check(iv["after a grown shake"]["intervals"] == 1 and
      abs(iv["after a grown shake"]["tau"]["mean"] - 2.0) < 1e-12,
      "tau after a grown shake: %s" % iv.get("after a grown shake"))
se = math.hypot(iv["after one shake"]["tau"]["se"], iv["after a grown shake"]["tau"]["se"])
check(abs(r["z_tau_after_shake"] - (2.0 - 9.0) / se) < 1e-9, "z per interval")

# Fill levels: one realization whose curve holds 1000, 800, 500, 200 particles on [0,1), [1,2),
# [2,3), [3,4) and 0 at t = 4; jams at t = 1.5 (interval of 1.5 s: [0, 1.5]) and 3.5 (1.9 s:
# [1.6, 3.5]; 1.5-1.6 is the detection window), then 0.4 s censored ([3.6, 4]). Bins 0, 300,
# 700, 1500: 700-1500 gets 1.0 + 0.5 + 0.4 = 1.9 s and the jam at 1.5 (800 in the hopper);
# 300-700 1.0 s, no jam; 0-300 0.5 + 0.4 = 0.9 s and the jam at 3.5 (200).
curves = pd.DataFrame({"point": [0] * 5, "realization": [0] * 5,
                       "time": [0.0, 1.0, 2.0, 3.0, 4.0], "in_hopper": [1000, 800, 500, 200, 0]})
lv_store = Store.from_frames("levels", {
    "survival": pd.DataFrame({"point": [0] * 3, "realization": [0] * 3, "interval": [0, 1, 2],
                              "duration": [1.5, 1.9, 0.4], "event": [1, 1, 0]}),
    "jams": pd.DataFrame({"point": [0, 0], "realization": [0, 0], "onset": [1.5, 3.5],
                          "shakes": [1, 1]}),
    "curves": curves, "points": pd.DataFrame(), "realizations": pd.DataFrame()})
lv = clogging.fill_levels(lv_store, [0, 300, 700, 1500])["levels"]
want = [(0.9, 1), (1.0, 0), (1.9, 1)]
for row, (t, k) in zip(lv, want):
    check(abs(row["flow_time"] - t) < 1e-12 and row["jams"] == k,
          "level %s-%s: %s s, %s jams (want %s, %s)" % (row["from"], row["to"], row["flow_time"],
                                                         row["jams"], t, k))
check(abs(lv[2]["tau"]["mean"] - 1.9) < 1e-12 and lv[1]["tau"]["mean"] is None,
      "tau by level: %s" % [row["tau"]["mean"] for row in lv])

# question: the open question's table. Point 0 (D = 3.1 cm, listed first) has no jam: 80 s of
# flow in 2 realizations of 1800 s worker time each, so tau > 80 / (chi2_0.95(2) / 2) = 26.70 s
# and 1 core-hour; point 1 (D = 2.7 cm): intervals 2 and 4 s ended by jams and 6 s censored,
# tau = 12 / 2 = 6 s, its 95 % interval 24 / chi2_{0.975,0.025}(4) = [2.1538, 49.544] s, a
# relative half-width of 3.9492; <s> = (100 + 300 + 200) / 2 = 300; 720 s = 0.2 core-hours,
# 0.1 per jam. The fits are the store's, reported in cm, not refitted.
q_store = Store.from_frames("question", {
    "points": pd.DataFrame({"label": ["D_cm=3.1", "D_cm=2.7"], "D_cm": [3.1, 2.7]}),
    "realizations": pd.DataFrame({"point": [0, 0, 1], "realization": [0, 1, 0],
                                  "status": ["complete"] * 3,
                                  "task_seconds": [1800.0, 1800.0, 720.0]}),
    "survival": pd.DataFrame({"point": [0, 0, 1, 1, 1], "realization": [0, 1, 0, 0, 0],
                              "interval": [0, 0, 0, 1, 2], "duration": [30.0, 50.0, 2.0, 4.0, 6.0],
                              "event": [0, 0, 1, 1, 0],
                              "avalanche_size": [900.0, 1100.0, 100.0, 300.0, 200.0]}),
    "analysis": pd.DataFrame(),
    "jam_rate": pd.DataFrame({"group": ["theta_deg=45"], "n_points": [5], "exp_B": [200.0],
                              "exp_B_err": [10.0], "exp_ln_A": [1.0], "exp_aic": [5.0],
                              "pow_Dc": [0.04], "pow_gamma": [3.0], "pow_ln_A": [float("nan")],
                              "pow_aic": [8.0], "preferred": ["exponential"],
                              "decision": ["exponential preferred"]}),
    "avalanche": pd.DataFrame({"group": ["theta_deg=45"], "n_points": [1], "exp_B": [float("nan")],
                               "preferred": ["undecided"],
                               "decision": ["too few points to decide (1 < 5)"]})})
q = clogging.question_summary(q_store, "synthetic")
p27, p31 = q["points"]
check(p27["D_cm"] == 2.7 and p31["D_cm"] == 3.1, "points in order of D: %s, %s"
      % (p27["D_cm"], p31["D_cm"]))
check(p27["tau"]["jams"] == 2 and abs(p27["tau"]["mean"] - 6.0) < 1e-12
      and abs(p27["tau"]["lo"] - 2.15376) < 1e-4 and abs(p27["tau"]["hi"] - 49.544) < 1e-2,
      "tau at 2.7 cm: %s" % p27["tau"])
check(abs(p27["tau_rel_half_width"] - 3.9492) < 1e-3, "half-width %s" % p27["tau_rel_half_width"])
check(abs(p27["mean_s"]["mean"] - 300.0) < 1e-12, "<s> at 2.7 cm: %s" % p27["mean_s"])
check(abs(p27["core_hours"] - 0.2) < 1e-12 and abs(p27["core_hours_per_jam"] - 0.1) < 1e-12,
      "core-hours at 2.7 cm: %s, per jam %s" % (p27["core_hours"], p27["core_hours_per_jam"]))
check(p31["tau"]["mean"] is None and abs(p31["tau"]["lo"] - 26.704) < 1e-3
      and p31["flow_time"] == 80.0 and p31["core_hours_per_jam"] is None
      and p31["tau_rel_half_width"] is None, "bound at 3.1 cm: %s" % p31)
check(abs(q["core_hours"] - 1.2) < 1e-12, "core-hours in all: %s" % q["core_hours"])
fit = q["fits"]["jam_rate"][0]
check(fit["pow_ln_A"] is None and fit["exp_B"] == 200.0, "NaN fit values become None: %s" % fit)
md = clogging.question_markdown(q)
for want in ("> 26.7 (no jam)", "| 2.7 | 1 | 12 | 2 | 6 +- 4.2 [2.15, 49.5] | 395 % |",
             "B = 2 +- 0.1 per cm", "D_c = 4 cm, gamma = 3",
             "AIC power law - exponential = +3.00", "preferred: exponential",
             "too few points to decide", "Core-hours in all (worker time): 1.20."):
    check(want in md, "markdown has %r:\n%s" % (want, md))

# plan: one outlet observed for T = 3 s with rates 2/s (exponential) and 1/s (power law): the
# log-likelihood ratio n ln 2 - 3 exceeds 1 for n >= 6 and falls below -1 for n <= 2, so
# P(Poisson(6) >= 6) = 1 - e^-6 (1 + 6 + 18 + 36 + 54 + 64.8) = 0.554320 and
# P(Poisson(3) <= 2) = e^-3 (1 + 3 + 4.5) = 0.423190.
p_e, p_p = clogging.decision_probabilities(3.0, 2.0, 1.0)
check(abs(p_e - 0.554320) < 1e-5 and abs(p_p - 0.423190) < 1e-5, "decision probabilities %s %s"
      % (p_e, p_p))
# Laws: ln lambda = 1 - 200 D, and (D_c - D)^3 with D_c = 4 cm; at 3 cm e^-5 and 1e-6; none
# beyond D_c. There one jam decides: the exponential is favoured with probability 0.95 once
# 1 - e^{-T/tau} >= 0.95, T = ln 20 tau, tau = e^7.2 = 1339.43 s at 4.1 cm: 4012.5 s (grid 1 %).
law = {"exp_ln_A": 1.0, "exp_B": 200.0, "pow_ln_A": 0.0, "pow_Dc": 0.04, "pow_gamma": 3.0}
r_e, r_p = clogging.law_rates(law, 0.03)
check(abs(r_e - math.exp(-5)) < 1e-15 and abs(r_p - 1e-6) < 1e-18, "rates at 3 cm %s %s"
      % (r_e, r_p))
check(clogging.law_rates(law, 0.041)[1] == 0.0, "no power-law jams beyond D_c")
T = clogging.flow_time_to_decide(math.exp(-7.2), 0.0)
check(4012.5 <= T <= 4012.5 * 1.0101, "time to decide beyond D_c: %s" % T)
try:
    clogging.plan_summary(q_store, "synthetic", fit="store")
    check(False, "plan without a power-law fit must fail")
except ValueError as e:
    check("4 outlets with jams" in str(e), "plan's error names the missing fit: %s" % e)
q_store.jam_rate.loc[0, "pow_ln_A"] = 0.0
pl = clogging.plan_summary(q_store, "synthetic", fit="store")
# Cost: 1.2 core-hours over 92 s of flow = 46.957 core-s per flowing second; the default outlets
# are the ten beyond the largest with a jam (2.7 cm): 2.8 ... 3.7.
check(abs(pl["core_s_per_flow_s"] - 1.2 * 3600 / 92) < 1e-9, "cost %s" % pl["core_s_per_flow_s"])
rows = pl["groups"][0]["outlets"]
check([r["D_cm"] for r in rows] == [2.8, 2.9, 3.0, 3.1, 3.2, 3.3, 3.4, 3.5, 3.6, 3.7],
      "default outlets %s" % [r["D_cm"] for r in rows])
r31 = rows[3]
check(r31["flow_measured"] == 80.0 and r31["jams_measured"] == 0
      and abs(r31["core_hours_to_go"] - (r31["flow_time"] - 80.0) * 1.2 / 92) < 1e-9,
      "3.1 cm holds 80 s without a jam: %s" % r31)
pl41 = clogging.plan_summary(q_store, "synthetic", [4.1], fit="store")
r41 = pl41["groups"][0]["outlets"][0]
check(r41["tau_power_law"] is None and 4012.5 <= r41["flow_time"] <= 4012.5 * 1.0101
      and abs(r41["core_hours"] - r41["flow_time"] * 1.2 / 92) < 1e-9
      and r41["core_hours_to_go"] == r41["core_hours"] and r41["flow_measured"] == 0
      and abs(r41["jams_exponential"] - math.log(20)) < 0.02,
      "4.1 cm, beyond D_c: %s" % r41)
md = clogging.plan_markdown(pl)
check("| 80, 0 |" in md and "<- cheapest" in md, "plan's markdown:\n%s" % md)
check("inf (D >= D_c)" in clogging.plan_markdown(pl41), "beyond D_c in the markdown")

# Numbers in the tables: three significant digits without an exponent between 1e-3 and 1e7.
for x, d, want in ((1196.5, 3, "1200"), (144.0, 2, "140"), (5.7369, 3, "5.74"), (6.0, 3, "6"),
                   (9.996, 3, "10"), (15800.0, 3, "15800"), (1.4e7, 3, "1.4e+07"),
                   (0.00469, 3, "0.00469")):
    check(clogging.sig(x, d) == want, "sig(%r, %d) = %r, want %r" % (x, d, clogging.sig(x, d), want))
check("| 300 +- 210 |" in clogging.question_markdown(q), "<s> without an exponent")

# Poisson fit: two outlets with jams and one without. With only the two, the exponential passes
# through both rates: 8 jams in 100 s at 2.7 cm and 2 in 100 s at 3.1 cm give
# B = ln 4 / 0.004 m = 346.57 per m, ln A = ln 0.08 + 2.7 B / 100 (hand).
two = [{"D_cm": 2.7, "flow_time": 100.0, "tau": {"jams": 8}},
       {"D_cm": 3.1, "flow_time": 100.0, "tau": {"jams": 2}}]
check("reason" in clogging.poisson_fits(two), "two outlets are too few")
with_zero = two + [{"D_cm": 3.5, "flow_time": 100.0, "tau": {"jams": 0}}]
pf = clogging.poisson_fits(with_zero)
# The outlet without a jam pulls the law down: B larger than through the two alone, and the
# rate at 3.5 cm below 2 x (1/4) / 100 s (the two-point law's extrapolation).
B2 = math.log(4) / 0.004
check(pf["exp_B"] > B2 and math.exp(pf["exp_ln_A"] - pf["exp_B"] * 0.035) < 0.005,
      "a jamless outlet steepens the fit: B %s against %s" % (pf["exp_B"], B2))
# Exact: for the exponential the score equations are sum n = sum lambda T and
# sum n D = sum lambda T D: 10 jams and 0.027 m x 8 + 0.031 m x 2 = 0.278 m.
lam_t = [math.exp(pf["exp_ln_A"] - pf["exp_B"] * p["D_cm"] / 100) * 100 for p in with_zero]
check(abs(sum(lam_t) - 10) < 1e-5 and
      abs(sum(l * p["D_cm"] / 100 for l, p in zip(lam_t, with_zero)) - 0.278) < 1e-6,
      "score equations: %s" % lam_t)
check(pf["pow_Dc"] > 0.031 and pf["pow_Dc_lower_95"] <= pf["pow_Dc"] and pf["preferred"] in
      ("exponential", "power law", "undecided"), "power law: %s" % pf)
check("those without a jam included" in clogging.poisson_markdown(pf), "Poisson markdown")
pf5 = clogging.poisson_fits(with_zero, dc_fixed_m=0.05)
check(pf5["pow_Dc"] == 0.05 and pf5.get("pow_Dc_fixed") and "D_c fixed at 5 cm" in pf5["decision"]
      and pf5["exp_B"] == pf["exp_B"] and pf5["pow_lnL"] <= pf["pow_lnL"] + 1e-9,
      "power law at a fixed D_c: %s" % pf5)
check("reason" in clogging.poisson_fits(with_zero, dc_fixed_m=0.03), "D_c below a jamming outlet")
# An outlet with no flowing time yet (a campaign in progress) is left out: the same fit, no NaN.
with warnings.catch_warnings():
    warnings.simplefilter("error")
    pf0 = clogging.poisson_fits(with_zero + [{"D_cm": 3.9, "flow_time": 0.0, "tau": {"jams": 0}}])
check(pf0["exp_B"] == pf["exp_B"] and pf0["pow_lnL"] == pf["pow_lnL"] and pf0["n_points"] == 3,
      "an outlet without flowing time changes nothing: %s" % pf0)

# plan --bound: beyond the bound one jam excludes every critical outlet at or below it (a
# power law cannot jam at or beyond its D_c), and no jam there cannot raise the bound (it
# favours the smaller D_c), so at 3.7 cm with the bound at 3.6 cm the probability is
# P(n >= 1) = 1 - exp(-lambda T), lambda the exponential's rate there (to the 1e-4 tail).
lam37 = math.exp(pf["exp_ln_A"] - pf["exp_B"] * 0.037)
check(pf["pow_Dc_lower_95"] * 100 < 3.6, "the points alone leave D_c < 3.6 cm open: %s" % pf)
br = clogging.bound_probabilities(with_zero, pf, [3.7, 3.3], [500.0, 2000.0], 3.6)
check([(r["D_cm"], r["flow_time"]) for r in br] == [(3.7, 500.0), (3.7, 2000.0), (3.3, 500.0),
                                                    (3.3, 2000.0)], "bound rows: %s" % br)
for r in br[:2]:
    want = 1 - math.exp(-lam37 * r["flow_time"])
    check(abs(r["jams_exponential"] - lam37 * r["flow_time"]) < 1e-12
          and abs(r["p_bound_raised"] - want) < 2e-4, "beyond the bound: %s, want %.5f" % (r, want))
check(all(0.0 <= r["p_bound_raised"] <= 1.0 for r in br) and
      br[3]["p_bound_raised"] >= br[2]["p_bound_raised"] - 1e-12,
      "below the bound a probability, not falling with more flow: %s" % br[2:])

for r in br:
    r["core_hours"] = r["flow_time"] / 3600
bmd = clogging.plan_markdown({"groups": [], "bound": {"bound_cm": 3.6, "lower_95_cm": 3.2,
                                                     "rows": br, "best": br[1]}})
check("| 3.7 | 2000 |" in bmd and "<- best per core-hour" in bmd and "stands at 3.2 cm" in bmd,
      "bound markdown:\n%s" % bmd)

# published (issue 39, part 5): against the published study's jam rate at theta = 45 deg. Point 0
# (D = 2.7 cm): 10 jams in 100 s; the published rate is 261 / (40 x 34.45 s) = 0.189405 /s, so
# 18.9405 expected, ratio 0.52797, p = 2 P(X <= 10) under Poisson(18.9405) (summed here by
# hand). Point 1 (D = 3.5 cm): 1 jam in 50 s against 8 / (40 x 22.82) x 50 = 0.438212 expected,
# p = 2 (1 - e^-0.438212).
# Point 2 (D = 3.1 cm at theta 60) and point 3 (D = 4.0 cm) are not published rows: left out.
# Combined: the two deviances 2 [n ln(n/mu) - (n - mu)] against chi-square with 2 degrees.
pub_store = Store.from_frames("published", {
    "points": pd.DataFrame({"label": ["a", "b", "c", "d"], "D_cm": [2.7, 3.5, 3.1, 4.0],
                            "theta_deg": [45.0, 45.0, 60.0, 45.0]}),
    "realizations": pd.DataFrame({"point": [0, 1, 2, 3], "realization": [0, 0, 0, 0],
                                  "status": ["complete"] * 4, "task_seconds": [1.0] * 4}),
    "survival": pd.DataFrame({"point": [0] * 11 + [1, 1, 2, 3],
                              "realization": [0] * 15,
                              "interval": list(range(11)) + [0, 1, 0, 0],
                              "duration": [9.0] * 10 + [10.0] + [20.0, 30.0, 40.0, 50.0],
                              "event": [1] * 10 + [0] + [1, 0, 1, 1]}),
    "analysis": pd.DataFrame(), "jam_rate": pd.DataFrame(), "avalanche": pd.DataFrame()})
pb = clogging.published_summary(pub_store, "synthetic")
check([r["D_cm"] for r in pb["points"]] == [2.7, 3.5], "published rows: %s" % pb["points"])
a, b = pb["points"]
mu = 261 / (40 * 34.45) * 100
cdf = sum(math.exp(-mu) * mu ** k / math.factorial(k) for k in range(11))
check(a["jams"] == 10 and abs(a["flow_time"] - 100) < 1e-12 and abs(a["expected"] - mu) < 1e-9
      and abs(a["ratio"] - 10 / mu) < 1e-12 and abs(a["p"] - 2 * cdf) < 1e-9,
      "2.7 cm: %s (p by hand %.6g)" % (a, 2 * cdf))
mu_b = 8 / (40 * 22.82) * 50
# one jam where 0.44 are expected: the upper tail P(X >= 1) = 1 - e^-mu is the smaller one
check(b["jams"] == 1 and abs(b["expected"] - mu_b) < 1e-12
      and abs(b["p"] - 2 * (1 - math.exp(-mu_b))) < 1e-12, "3.5 cm: %s" % b)
dev = 2 * (10 * math.log(10 / mu) - (10 - mu)) + 2 * (math.log(1 / mu_b) - (1 - mu_b))
check(pb["combined"]["outlets"] == 2 and abs(pb["combined"]["deviance"] - dev) < 1e-9
      and abs(pb["combined"]["p"] - math.exp(-dev / 2)) < 1e-12,
      "combined: %s (deviance by hand %.6g)" % (pb["combined"], dev))
check("| synthetic | 2.7 | 1 | 10 | 100 |" in clogging.published_markdown([pb]),
      "published markdown:\n%s" % clogging.published_markdown([pb]))

# heads --reference: the published side as numbers; its 95 % interval is the censored MLE's
# chi-square interval for that many jams (here 100 jams of tau 5 s: 500 s of flow).
ref = clogging.reference_row("5,0.5,1000,100,100")
lo = 2 * 500 / stats.chi2.ppf(0.975, 200)
check(ref["tau"]["mean"] == 5 and ref["tau"]["se"] == 0.5 and ref["tau"]["jams"] == 100
      and abs(ref["tau"]["lo"] - lo) < 1e-12 and ref["mean_s"]["mean"] == 1000
      and ref["mean_s"]["se"] == 100, "reference row: %s (lo by hand %.6g)" % (ref, lo))
# a head whose tau is 6 +- 0.5 s lies (6 - 5) / hypot(0.5, 0.5) = 1.414 se above it
check(abs(clogging.z_of({"mean": 6.0, "se": 0.5}, ref["tau"]) - 2 ** 0.5) < 1e-12, "z of a head")
for bad in ("5,0.5,1000,100", "5,0.5,x,100,100", "5,0,1000,100,100"):
    try:
        clogging.reference_row(bad)
        check(False, "reference %r accepted" % bad)
    except SystemExit as e:
        check("--reference" in str(e), "reference %r: %s" % (bad, e))

# heads --reference-point: one point of a store with several is the reference; none or two
# matching is an error that lists the labels.
pts = [{"store": "s.h5", "label": "D_cm=3.1 hopper.particles=1500"},
       {"store": "s.h5", "label": "D_cm=3.1 hopper.particles=500 protocol.lid_gravity=22"}]
check(clogging.pick_reference(pts, "particles=1500") is pts[0], "reference point by label")
# a whole label is that point even where it is part of another's
pts.append({"store": "s.h5", "label": "D_cm=3.1"})
check(clogging.pick_reference(pts, "D_cm=3.1") is pts[2], "reference point by its whole label")
pts.pop()
for bad in ("particles=700", "D_cm=3.1"):
    try:
        clogging.pick_reference(pts, bad)
        check(False, "reference point %r accepted" % bad)
    except SystemExit as e:
        check("--reference-point" in str(e) and "lid_gravity=22" in str(e),
              "reference point %r: %s" % (bad, e))

# lid-stress: the mean pressure over the cells within the half-width of the axis and between the
# outlet and the height; a cell no window reached (NaN) is left out. Cells of 1 cm: centres at
# x = -2.5 ... 2.5 cm, y = -0.5 ... 6.5 cm; pressure = 10 + 100 y (m) + x (m) by hand.
import xarray as xr  # noqa: E402
xs = np.arange(-2.5, 2.6, 1.0) / 100
ys = np.arange(-0.5, 6.6, 1.0) / 100
pressure = 10 + 100 * ys[:, None] + xs[None, :]
pressure[1, 2] = np.nan  # the cell at y = 0.5 cm, x = -0.5 cm: no window
fields = {"D_cm=3.1": xr.Dataset({"mean_pressure": (("y", "x"), pressure)},
                                 coords={"x": xs, "y": ys})}
lid_store = Store.from_frames("synthetic", {
    "realizations": pd.DataFrame({"point": [0, 0], "label": ["D_cm=3.1"] * 2,
                                  "status": ["time_limit", "failed"], "n_jams": [2, 5],
                                  "discharge_rate": [300.0, 1.0]})}, fields=fields)
rows = clogging.lid_stress_summary(lid_store, 0.02, 0.03)
# |x| < 2 cm: x = -1.5, -0.5, 0.5, 1.5 cm; 0 < y < 3 cm: y = 0.5, 1.5, 2.5 cm; one cell missing
want = [10 + 100 * y + x for y in ys[1:4] for x in xs[1:5]
        if not (y == ys[1] and x == xs[2])]
check(len(rows) == 1 and rows[0]["cells"] == 11 and abs(rows[0]["pressure"] - np.mean(want)) < 1e-12
      and rows[0]["discharge_rate"] == 300.0 and rows[0]["jams"] == 2,
      "lid stress: %s (by hand %.6g over 11 cells)" % (rows, np.mean(want)))
try:
    clogging.lid_stress_summary(Store.from_frames("synthetic", {"realizations": pd.DataFrame()}),
                                0.02, 0.03)
    check(False, "a store without fields accepted")
except ValueError as e:
    check("fields" in str(e), "no fields: %s" % e)

check.finish()
