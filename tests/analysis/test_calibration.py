#!/usr/bin/python3
"""analysis/calibration.py on small synthetic stores whose answers are known by construction
(issue 24, item 4): the Beverloo fit recovers A and k of rates made exactly from W = A (D - k d)^1.5;
the targets table gives each published empty time's ratio for stores whose empty times are the
published ones times a known factor; the sensitivity table gives each choice's rate change against
the reference and the seed noise; the flow curves per candidate give each outlet's rate against the
published mean rate and recover A, k and C phi; the rate profile of a discharge gives each tenth's
rate on the flowing clock (a jammed period left out); bad arguments exit 2 with a message.

usage: test_calibration.py SOURCE_DIR     (exit 0 pass, 1 fail, 77 skipped: no h5py/scipy)
"""
import math
import os
import re
import subprocess
import sys
import tempfile

try:
    import h5py
    import numpy as np
    import scipy  # noqa: F401
except ImportError:
    sys.exit(77)

SRC = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")
CAL = os.path.join(SRC, "analysis", "calibration.py")
failures = []
checks = [0]


def check(cond, what):
    checks[0] += 1
    if not cond:
        failures.append(what)
        print("FAIL: " + what)


def scene(**kv):
    base = {"hopper.theta_rad": math.pi / 4, "hopper.outlet_m": 0.045,
            "particles.small_fraction": 0.5, "particles.d_small_m": 0.006,
            "particles.d_large_m": 0.008, "material.e_n": 0.5, "material.mu": 0.8,
            "walls.e_n": 0.5, "walls.mu": 0.8, "particles.count": 8750}
    base.update(kv)
    return "".join("%s=%r\n" % (k, v) for k, v in base.items())


def make_store(path, points):
    """points: [(label, scene text, [(seed, rate or None, empty time or None), ...])]."""
    with h5py.File(path, "w") as f:
        f.create_dataset("points/label", data=[p[0] for p in points], dtype=h5py.string_dtype())
        f.create_dataset("points/scene", data=[p[1] for p in points], dtype=h5py.string_dtype())
        rows = [(i, s, r, e) for i, p in enumerate(points) for (s, r, e) in p[2]]
        r = f.create_group("realizations")
        r["point"] = np.array([x[0] for x in rows], np.int32)
        r["seed"] = np.array([x[1] for x in rows], np.uint64)
        r["has_discharge_rate"] = np.array([x[2] is not None for x in rows], np.uint8)
        r["discharge_rate"] = np.array([x[2] or 0.0 for x in rows])
        r["has_empty_time"] = np.array([x[3] is not None for x in rows], np.uint8)
        r["empty_time"] = np.array([x[3] or 0.0 for x in rows])
        r["task_seconds"] = np.ones(len(rows))
        r["diagnostics/wall_seconds"] = np.ones(len(rows))


def run(*args):
    p = subprocess.run(["/usr/bin/python3", CAL] + list(args), capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


work = tempfile.mkdtemp(prefix="test_calibration_")

# --- Beverloo: W = A (D - k d)^1.5 with d the number-mean diameter 0.7 cm, A = 90, k = 1.2; two
# seeds per outlet at +-1 % (their mean is exact; the fit is weighted by their standard error).
A, k, d = 90.0, 1.2, 0.7
pts = []
for i, D in enumerate([2.7, 3.1, 3.5, 4.1, 4.5]):
    W = A * (D - k * d) ** 1.5
    pts.append(("D_cm=%g" % D, scene(**{"hopper.outlet_m": D / 100}),
                [(10 * i + 1, W * 1.01, None), (10 * i + 2, W * 0.99, None)]))
make_store(os.path.join(work, "bev.h5"), pts)
rc, out, err = run("beverloo", os.path.join(work, "bev.h5"), "--out", work)
check(rc == 0, "beverloo exits 0 (got %d: %s)" % (rc, err))
m = re.search(r"A = ([\d.]+) \+- [\d.]+ particles/s/cm\^1.5, k = ([\d.]+) \+-", out)
check(m is not None, "beverloo prints A and k")
if m:
    check(abs(float(m.group(1)) - A) < 0.1, "beverloo A = %s, expected %g" % (m.group(1), A))
    check(abs(float(m.group(2)) - k) < 0.001, "beverloo k = %s, expected %g" % (m.group(2), k))
check(os.path.exists(os.path.join(work, "beverloo.png")), "beverloo writes beverloo.png")
# Two outlets cannot fix two parameters: refused with the reason, exit 2.
make_store(os.path.join(work, "bev2.h5"), pts[:2])
rc, out, err = run("beverloo", os.path.join(work, "bev2.h5"), "--out", work)
check(rc == 2 and "at least 3 outlets" in err, "beverloo on 2 outlets exits 2 (got %d: %s)" %
      (rc, err.strip()))

# --- Targets: the theta = 45 deg targets D = 4.1, 4.3, 4.5 cm (17.27, 15.76, 14.52 s) with
# empty times 1.05 x published (two seeds at 1.04 and 1.06 x: se 0.01 x), and D = 2.7 cm (34.45 s)
# at 1.04 x (two seeds at 1.03 and 1.05 x): within the 5 % of a jamming outlet, not the 3 % above.
published = {2.7: 34.45, 4.1: 17.27, 4.3: 15.76, 4.5: 14.52}
factor = {2.7: 1.04, 4.1: 1.05, 4.3: 1.05, 4.5: 1.05}
pts = []
for i, (D, T) in enumerate(sorted(published.items())):
    f = factor[D]
    pts.append(("D_cm=%g" % D, scene(**{"hopper.outlet_m": D / 100}),
                [(i * 2 + 1, None, T * (f - 0.01)), (i * 2 + 2, None, T * (f + 0.01))]))
make_store(os.path.join(work, "tgt.h5"), pts)
rc, out, err = run("targets", os.path.join(work, "tgt.h5"), "--out", work)
check(rc == 0, "targets exits 0 (got %d: %s)" % (rc, err))
for D, T in published.items():
    f = factor[D]
    row = [l for l in out.splitlines() if l.startswith("| 45 | %g |" % D)]
    check(len(row) == 1, "targets has one row for D = %g" % D)
    if row:
        tol, verdict = ("5 %", "ok") if D < 3.6 else ("3 %", "out")
        want = "| %.2f | %s | %.2f +- %.2f | 2 | %.3f | %+.1f %% %s |" % (
            T, tol, T * f, T * 0.01, f, 100 * (f - 1), verdict)
        check(want in row[0], "targets row for D = %g: want %r in %s" % (D, want, row[0]))
check("4 of 16 targets, largest error 5.0 %, rms 4.8 %, 1 within tolerance" in out,
      "targets summary line: %s" % out.strip().splitlines()[-1])
rc, out, err = run("targets", "mine=" + os.path.join(work, "tgt.h5"), "--out", work)
check(rc == 0 and "| mine (s) | n | ratio | error |" in out and "- mine: 4 of 16" in out,
      "targets names a column NAME=STORE.h5 (got %d: %s)" % (rc, out[:300]))
# The whole-discharge Beverloo fit of the targets' 45-degree outlets: empty times made from
# N / T = A (D - k d)^1.5 (A = 80, k = 0.9, d = 0.7 cm, N = 8750) at five outlets, two seeds at
# +-0.5 % of the rate; the published fit's row beside it (the eight published mean rates: A = 73.0
# and k d = 0.442 cm, so k = 0.631 with this store's d = 0.7 cm, 0.663 with the model's 0.666 cm).
pts = []
for i, D in enumerate([2.7, 2.9, 3.3, 4.1, 4.5]):
    W = 80.0 * (D - 0.9 * 0.7) ** 1.5
    pts.append(("D_cm=%g" % D, scene(**{"hopper.outlet_m": D / 100}),
                [(i * 2 + 1, None, 8750 / (W * 1.005)), (i * 2 + 2, None, 8750 / (W * 0.995))]))
make_store(os.path.join(work, "whole.h5"), pts)
rc, out, err = run("targets", "whole=" + os.path.join(work, "whole.h5"), "--out", work)
row = [l for l in out.splitlines() if l.startswith("| whole | 5 | ")]
check(rc == 0 and len(row) == 1 and row[0].startswith("| whole | 5 | 80.0 +- ") and
      "| 0.900 +- " in row[0], "targets' whole-discharge Beverloo fit recovers A = 80, k = 0.9: %s"
      % row)
check("| published | 8 | 73.0 +- 1.9 | 0.631 +- 0.083 |" in out,
      "targets gives the published whole-discharge fit beside it")
# The theta = 60 deg targets are not in the store: shown as missing, not invented.
row60 = [l for l in out.splitlines() if l.startswith("| 60 | 4.5 | 0.5, 0.5 |")]
check(len(row60) == 1 and row60[0].endswith(" - | 0 | - | - |"), "a missing target shows '-'")

# --- Profile: one emptied realization of 1000 disks at D = 2.7 cm: 500 exits at 100 /s, a jam at
# t = 5 s cleared at t = 6 s (a jammed second that the flowing clock leaves out), then 500 exits at
# 50 /s until t = 16 s. Tenths 1-5 give 100 /s, tenths 6-10 50 /s; N / T = 1000 / 16 = 62.5 /s.
prof = os.path.join(work, "prof.h5")
make_store(prof, [("D_cm=2.7", scene(**{"hopper.outlet_m": 0.027}), [(1, None, 16.0)])])
with h5py.File(prof, "a") as f:
    exits = np.concatenate([np.arange(1, 501) / 100.0, 6.0 + np.arange(1, 501) / 50.0])
    r = f["realizations"]
    for name, start, length in (("exit", 0, 1000), ("jam", 0, 1), ("survival", 0, 2)):
        r[name + "_start"] = np.array([start], np.uint64)
        r[name + "_length"] = np.array([length], np.uint64)
    f["ragged/exit_times"] = exits
    f["ragged/jam_onsets"] = np.array([5.0])
    f["ragged/survival_times"] = np.array([5.0, 10.0])
rc, out, err = run("profile", "x=" + prof, "--out", work)
check(rc == 0, "profile exits 0 (got %d: %s)" % (rc, err))
want = "| x | 45 | 2.7 | 1 | " + " | ".join(["100"] * 5 + ["50"] * 5) + " | 62.5 |"
check(want in out, "profile row: want %r in %s" % (want, out))
rc, out, err = run("profile", prof)
check(rc == 2 and "NAME=STORE.h5" in err, "profile without NAME= exits 2 (got %d: %s)" % (rc, err))

# --- Sensitivity at 45 deg, D = 4.5 cm: the reference with three seeds (rates 500, 510, 520: mean
# 510, sd 10) and one choice with rate 561 (+10 %, +5.1 noise, implied empty time -9.1 %).
ref = scene()
pts = [("reference", ref, [(1, 500.0, None), (2, 510.0, None), (3, 520.0, None)]),
       ("smooth", ref + "hopper.wall_spacing=0.5\n", [(1, 561.0, None)])]
make_store(os.path.join(work, "sens.h5"), pts)
rc, out, err = run("sensitivity", os.path.join(work, "sens.h5"), "--out", work)
check(rc == 0, "sensitivity exits 0 (got %d: %s)" % (rc, err))
check("reference: 3 seeds, 510.0 /s, seed-to-seed sd 10.0 /s = 2.0 %" in out,
      "sensitivity names the reference and its noise")
check("| hopper.wall_spacing=0.5 | 561.0 | +10.0 % | +5.1 | -9.1 % |" in out,
      "sensitivity row of the choice: %s" % [l for l in out.splitlines() if "wall_spacing" in l])

# --- Flow curves per candidate: "fast" has the published mean rates N / T_empty times 1.10 at the
# eight published outlets (two seeds at 1.09 and 1.11 x); "bev" is the Beverloo store above
# (A = 90, k = 1.2 recovered; d = 0.7 cm).
pub = {2.7: 34.45, 2.9: 30.44, 3.1: 27.83, 3.3: 25.25, 3.5: 22.82, 4.1: 17.27, 4.3: 15.76,
       4.5: 14.52}
pts = []
for i, (D, T) in enumerate(sorted(pub.items())):
    pts.append(("D_cm=%g" % D, scene(**{"hopper.outlet_m": D / 100}),
                [(i * 2 + 1, 8750 / T * 1.09, None), (i * 2 + 2, 8750 / T * 1.11, None)]))
make_store(os.path.join(work, "fast.h5"), pts)
rc, out, err = run("curves", "fast=" + os.path.join(work, "fast.h5"),
                   "bev=" + os.path.join(work, "bev.h5"), "--out", work)
check(rc == 0, "curves exits 0 (got %d: %s)" % (rc, err))
for D, T in pub.items():
    row = [l for l in out.splitlines() if l.startswith("| %g | %.1f |" % (D, 8750 / T))]
    check(len(row) == 1 and "(+10.0 %) [2]" in row[0],
          "curves row for D = %g: the candidate 10 %% above the published rate: %s" % (D, row))
bev = [l for l in out.splitlines() if l.startswith("| bev |")]
check(len(bev) == 1 and bev[0].startswith("| bev | 90.0 +- ") and "| 1.200 +- " in bev[0],
      "curves recovers A = 90, k = 1.2 of the Beverloo store: %s" % bev)
# C phi = A <a> / sqrt(g): <a> = pi/4 (0.6^2 + 0.8^2) / 2 cm^2
cphi = 90 * math.pi / 4 * (0.36 + 0.64) / 2 / math.sqrt(981)
check(len(bev) == 1 and ("| %.3f +- " % cphi) in bev[0], "curves gives C phi = %.3f" % cphi)
check(os.path.exists(os.path.join(work, "flow_curves.png")) and
      os.path.exists(os.path.join(work, "flow_curves.json")), "curves writes its figure and JSON")
rc, out, err = run("curves", os.path.join(work, "fast.h5"))
check(rc == 2 and "NAME=STORE.h5" in err, "curves without NAME= exits 2 (got %d: %s)" % (rc, err))
pts60 = [(l, sc.replace("hopper.theta_rad=%r" % (math.pi / 4), "hopper.theta_rad=%r" %
                        (math.pi / 3)), rr) for l, sc, rr in pts]
make_store(os.path.join(work, "sixty.h5"), pts60)
rc, out, err = run("curves", "x=" + os.path.join(work, "sixty.h5"))
check(rc == 2 and "theta = 60" in err, "curves at 60 deg exits 2 (got %d: %s)" % (rc, err))

# --- Bad arguments: a file that is not a store.
bad = os.path.join(work, "not_a_store.h5")
open(bad, "w").write("hello")
rc, out, err = run("targets", bad)
check(rc == 2 and "calibration.py: error" in err, "a non-store exits 2 with a message")
rc, out, err = run("beverloo", os.path.join(work, "missing.h5"))
check(rc == 2 and "no store" in err, "a missing store exits 2 with a message")

print("calibration: %d passed, %d failed" % (checks[0] - len(failures), len(failures)))
sys.exit(1 if failures else 0)
