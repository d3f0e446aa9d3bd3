#!/usr/bin/python3
"""bench/engine_change_compare.py (issue 25, part 2) on synthetic JSON lines with answers by hand.

    test_engine_change.py PROJECT_SOURCE_DIR

1. Two builds with the same per-seed values: every z is 0, exit 0.
2. A jamming scene whose new build has 60 jams in 60 s of flow against 30 jams in 60 s (tau 1.0
   against 2.0 s): z on ln tau = (ln 1 - ln 2) / sqrt(1/30 + 1/60) = -3.10, exit 1.
3. phi: old 0.80, 0.82 (mean 0.81, se 0.01), new 0.83, 0.85 (0.84, 0.01): z = +2.12, printed.
4. A failed realization or different seeds: exit 1 with the problem named.
5. Shakes (issue 41): 2 of 20 jams needed more than one shake against 10 of 20, z of two
   proportions = 0.4 / sqrt(0.3 * 0.7 * (1/20 + 1/20)) = +2.76; one of the new build's two
   realizations arrested (an outcome of the protocol, not a problem): 0 of 2 against 1 of 2,
   z = 0.5 / sqrt(0.25 * 0.75 * 1) = +1.15; exit 0.
6. Whole realizations (`campaign simulate --json` files, issue 41), old seeds 1-2 and new seeds
   5, 7: old survival times 1, 2, 3 + 4 censored (3 jams in 10 s) twice, new 2, 4 + 4 censored
   (2 jams in 10 s), one new window arrested (1 + 9 uncensored: 2 jams): tau 20/6 = 3.333
   against 20/4 = 5.000, z = ln(1.5) / sqrt(1/6 + 1/4) = +0.63; rates 100, 110 against 120,
   130: z = 20 / hypot(5, 5) = +2.83; a stopped window (time_limit) and an arrest are outcomes,
   the seeds differ and that is allowed: exit 0. A file that is not such an output: exit 1,
   named.
   Arrests per jam, with the exact conditional 95 % interval of their ratio new/old: given the
   k arrests of both sides, the new side's count is Binomial(k, pi), pi = R n_new / (n_old +
   R n_new). Case 6: 0 of 6 jams against 1 of 4: k = 1, pi's Clopper-Pearson interval is
   [0.025, 1] (P(X >= 1) = pi), so R lies in [0.025 / 0.975 * 6 / 4 = 0.0385, inf].
7. One arrest of 2 jams on each side: ratio 1.00; k = 2, x = 1: 1 - (1 - pi)^2 = 0.025 and
   pi^2 = 0.975 give pi in [1 - sqrt(0.975), sqrt(0.975)] = [0.01258, 0.98742], R in
   [0.01274, 78.5].
"""
import json
import math
import os
import subprocess
import sys
import tempfile

src = sys.argv[1]
tool = os.path.join(src, "bench", "engine_change_compare.py")
fails = 0


def check(cond, what):
    global fails
    print(("ok   " if cond else "FAIL ") + what)
    fails += 0 if cond else 1


def row(scene, seed, phi, jams=0, flow=0.0, rate=None, status="complete"):
    return {"scene": scene, "setting": "published", "seed": seed, "status": status, "phi": phi,
            "rate": rate, "jams": jams, "flow_time": flow, "discharged": 100, "cpu_s": 1.0}


def run(old, new):
    with tempfile.TemporaryDirectory() as d:
        paths = []
        for name, rows in (("old", old), ("new", new)):
            p = os.path.join(d, name + ".jsonl")
            with open(p, "w") as f:
                for r in rows:
                    f.write(json.dumps(r) + "\n")
            paths.append(p)
        r = subprocess.run([sys.executable, tool] + paths, capture_output=True, text=True)
        return r.returncode, r.stdout, r.stderr


def z_in(out, observable):
    for line in out.splitlines():
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 3 and cells[3] == observable:
            return float(cells[-2])
    return None


# 1. identical
same = [row("jamming", 1, 0.80, 10, 20.0), row("jamming", 2, 0.82, 20, 40.0)]
rc, out, err = run(same, same)
check(rc == 0, "identical builds exit 0 (rc %d)" % rc)
check(z_in(out, "phi") == 0.0 and z_in(out, "tau (s)") == 0.0, "identical builds: z = 0")

# 2. tau halved
old = [row("jamming", 1, 0.81, 15, 30.0), row("jamming", 2, 0.81, 15, 30.0)]
new = [row("jamming", 1, 0.81, 30, 30.0), row("jamming", 2, 0.81, 30, 30.0)]
rc, out, err = run(old, new)
want = (math.log(1.0) - math.log(2.0)) / math.sqrt(1 / 30 + 1 / 60)
check(rc == 1, "tau halved: exit 1 (rc %d)" % rc)
check(abs(z_in(out, "tau (s)") - want) < 0.01, "tau halved: z %.2f (by hand %.2f)" % (z_in(out, "tau (s)"), want))

# 3. phi by hand
old = [row("discharge", 1, 0.80, rate=100.0), row("discharge", 2, 0.82, rate=100.0)]
new = [row("discharge", 1, 0.83, rate=100.0), row("discharge", 2, 0.85, rate=100.0)]
rc, out, err = run(old, new)
want = 0.03 / math.hypot(0.01, 0.01)
check(abs(z_in(out, "phi") - want) < 0.01, "phi: z %.2f (by hand %.2f)" % (z_in(out, "phi"), want))
check(rc == 0, "phi z below 3: exit 0 (rc %d)" % rc)

# 4. failed realization, other seeds
bad = [row("jamming", 1, 0.80, 10, 20.0, status="failed"), row("jamming", 2, 0.82, 20, 40.0)]
rc, out, err = run(same, bad)
check(rc == 1 and "seed 1: failed" in err, "a failed realization: exit 1, named")
other = [row("jamming", 3, 0.80, 10, 20.0), row("jamming", 2, 0.82, 20, 40.0)]
rc, out, err = run(same, other)
check(rc == 1 and "different seeds" in err, "different seeds: exit 1, named")

# 5. shakes and arrests
def shaken(seed, jams, shakes, multi, status="complete"):
    r = row("jamming", seed, 0.81, jams, 20.0, status=status)
    r.update(shakes=shakes, multi_shake=multi)
    return r


old = [shaken(1, 10, 11, 1), shaken(2, 10, 11, 1)]
new = [shaken(1, 10, 20, 5), shaken(2, 10, 25, 5, status="arrested")]
rc, out, err = run(old, new)
want = 0.4 / math.sqrt(0.3 * 0.7 * (1 / 20 + 1 / 20))
got = z_in(out, "jams needing more than one shake")
check(got is not None and abs(got - want) < 0.01, "multi-shake jams: z %s (by hand %.2f)" % (got, want))
got = z_in(out, "arrested realizations")
check(got is not None and abs(got - 0.5 / math.sqrt(0.1875)) < 0.01,
      "arrested realizations: z %s (by hand %.2f)" % (got, 0.5 / math.sqrt(0.1875)))
check("2.250" in out and "1.100" in out, "shakes per jam 1.100 and 2.250")
check(rc == 0 and "arrested" not in err, "an arrested realization is counted, not a problem (rc %d)" % rc)

# 6. whole realizations
def realization(seed, survival, censored, rate, status="time_limit", shakes=None):
    return {"status": status, "D_cm": 2.7, "theta_deg": 45, "seed": seed, "survival_times": survival,
            "censored": censored, "discharge_rate": rate, "n_jams": sum(not c for c in censored),
            "n_shakes": shakes if shakes is not None else sum(not c for c in censored),
            "n_jams_multi_shake": 0, "wall_seconds": 100.0}


def run_dirs(old, new):
    with tempfile.TemporaryDirectory() as d:
        paths = []
        for name, docs in (("old", old), ("new", new)):
            p = os.path.join(d, name)
            os.mkdir(p)
            for doc in docs:
                with open(os.path.join(p, "r-%s.json" % doc.get("seed", "x")), "w") as f:
                    json.dump(doc, f)
            paths.append(p)
        r = subprocess.run([sys.executable, tool] + paths, capture_output=True, text=True)
        return r.returncode, r.stdout, r.stderr


old = [realization(s, [1.0, 2.0, 3.0, 4.0], [False, False, False, True], 100.0 + 10 * (s - 1)) for s in (1, 2)]
new = [realization(5, [2.0, 4.0, 4.0], [False, False, True], 120.0),
       realization(7, [1.0, 9.0], [False, False], 130.0, status="arrested", shakes=11)]
rc, out, err = run_dirs(old, new)
want = math.log(1.5) / math.sqrt(1 / 6 + 1 / 4)
got = z_in(out, "tau (s)")
check(got is not None and abs(got - want) < 0.01, "realizations: tau z %s (by hand %.2f)" % (got, want))
got = z_in(out, "rate")
check(got is not None and abs(got - 20 / math.hypot(5, 5)) < 0.01,
      "realizations: rate z %s (by hand %.2f)" % (got, 20 / math.hypot(5, 5)))
check("3.333" in out and "5.000" in out and "| 1-2 | 5, 7 |" in out, "realizations: tau values and seed sets")
check(rc == 0 and not err, "realizations: time_limit, arrest and other seeds accepted (rc %d, %s)" % (rc, err.strip()))
check("| arrests per jam | 0 of 6 | 1 of 4 | 2 / 2 | new/old inf (95 % 0.0385-inf) |" in out,
      "realizations: arrests per jam and the interval of their ratio")
rc, out, err = run_dirs(old, [{"seed": 3, "status": "complete"}])
check(rc != 0 and "not a campaign simulate --json output" in err, "realizations: a wrong file named (rc %d)" % rc)

# 7. one arrest of two jams on each side
one = [realization(9, [1.0, 2.0], [False, False], 100.0, status="arrested", shakes=11)]
rc, out, err = run_dirs(one, [dict(one[0], seed=10)])
lo = (1 - math.sqrt(0.975)) / math.sqrt(0.975)
check("| arrests per jam | 1 of 2 | 1 of 2 | 1 / 1 | new/old 1.00 (95 %% %.3g-%.3g) |" % (lo, 1 / lo) in out,
      "one arrest each: ratio 1.00, interval [%.4f, %.1f] by hand" % (lo, 1 / lo))

print("%d failed" % fails)
sys.exit(1 if fails else 0)
