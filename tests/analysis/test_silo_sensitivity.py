#!/usr/bin/python3
"""analysis/silo_sensitivity.py (issue 39) with answers by hand: the lever named by a point's
label less its outlet and angle; ln(<s>+1) and its error se/(<s>+1); the difference from the
baseline at the same outlet and its z; a lever's own slope b from points on a known line.

usage: test_silo_sensitivity.py SOURCE_DIR   (exit 0 pass, 1 fail, 77 skipped: no numpy)
"""
import math
import os
import sys

try:
    import numpy  # noqa: F401
    import scipy  # noqa: F401
except ImportError:
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hand_checks import Checks, analysis_on_path  # noqa: E402

analysis_on_path()
import silo_sensitivity as ss  # noqa: E402

check = Checks("silo_sensitivity")

check(ss.lever_of("D_cm=2.695 theta_deg=0 material.mu_r=0.1") == "material.mu_r=0.1", "lever")
check(ss.lever_of("D_cm=2.31 theta_deg=0 material.e_n=0.05 walls.e_n=0.05")
      == "material.e_n=0.05 walls.e_n=0.05", "two-key lever")
check(ss.lever_of("D_cm=2.31 theta_deg=0") == "baseline", "no lever: baseline")
check(ss.lever_of("D_cm=2.31 theta_deg=0", "hopper.width_cm=38.5") == "hopper.width_cm=38.5",
      "a store-wide lever")
check(ss.lever_of("D_cm=2.31 theta_deg=0 material.mu=0.2", "hopper.width_cm=38.5")
      == "hopper.width_cm=38.5 material.mu=0.2", "a store-wide lever before the point's")
check(ss.store_and_lever("w.h5@hopper.width_cm=38.5 hopper.particles=1600")
      == ("w.h5", "hopper.width_cm=38.5 hopper.particles=1600"), "STORE@LEVER")
check(ss.store_and_lever("w.h5") == ("w.h5", ""), "a plain store")

# <s> = 99 +- 9.9 (100 clogs): y = ln 100 = 4.60517, sigma = 9.9/100 = 0.099.
# Baseline at the same outlet: <s> = 332.5 +- 34 -> y = ln 333.5 = 5.80964, sigma = 34/333.5.
row = ss.with_log({"mean_s": 99.0, "se": 9.9, "clogs": 100, "D_over_d": 3.5})
base = ss.with_log({"mean_s": 332.5, "se": 34.0, "D_over_d": 3.5000004})
check(abs(row["y"] - math.log(100)) < 1e-12 and abs(row["y_err"] - 0.099) < 1e-12, "y, sigma")
ss.compare([row], [base])
dy = math.log(100) - math.log(333.5)
z = dy / math.hypot(0.099, 34.0 / 333.5)
check(abs(row["dy"] - dy) < 1e-12, "dy %r against %r" % (row["dy"], dy))
check(abs(row["z"] - z) < 1e-12, "z %r against %r (-8.50)" % (row["z"], z))
# No baseline at that outlet: no difference, no z.
other = ss.with_log({"mean_s": 10.0, "se": 1.0, "clogs": 100, "D_over_d": 2.0})
ss.compare([other], [base])
check(other["dy"] is None and other["z"] is None, "no baseline at D/d 2")

# A lever on the line ln(<s>+1) = 0.5 + 0.3 (D/d)^2 at three outlets (10 clogs each), another at
# two outlets only (no fit).
rows = []
for r_ in (3.0, 3.5, 4.0):
    s = math.exp(0.5 + 0.3 * r_ ** 2) - 1
    rows.append(ss.with_log({"lever": "k", "D_over_d": r_, "mean_s": s, "se": s / math.sqrt(10),
                             "clogs": 10}))
rows += [ss.with_log({"lever": "two", "D_over_d": r_, "mean_s": 5.0, "se": 1.0, "clogs": 10})
         for r_ in (3.0, 3.5)]
fits = ss.lever_fits(rows)
check(set(fits) == {"k"}, "fits for %s" % sorted(fits))
check(abs(fits["k"]["b"] - 0.3) < 1e-9 and abs(fits["k"]["a"] - 0.5) < 1e-9,
      "b, a = %r, %r (0.3, 0.5)" % (fits["k"]["b"], fits["k"]["a"]))
md = ss.markdown([dict(r, realizations=1, core_hours=0.0, base_y=None, dy=None, z=None)
                  for r in rows], fits)
check("| k | 3.0, 3.5, 4.0 | 0.300 +- " in md, "the fit's table row:\n" + md)
# A point with nothing stored yet: no table row, named in the line after the table.
md = ss.markdown([dict(r, realizations=1, core_hours=0.0, base_y=None, dy=None, z=None)
                  for r in rows] + [dict(rows[0], lever="later", realizations=0, clogs=0,
                                         core_hours=0.0, base_y=None, dy=None, z=None)], fits)
check("| later |" not in md and "Nothing stored yet: later at D/d 3.00." in md, md)

# kappa from a collision time: 7.3e3 at the published 7.3e-4 s, x100 at a tenth of it.
check(ss.kappa_label("0.00073").startswith("kappa 7.3e+03"), ss.kappa_label("0.00073"))
check(ss.kappa_label("7.3e-05").startswith("kappa 7.3e+05"), ss.kappa_label("7.3e-05"))

# The figure: one panel per lever family, drawn from the rows above against a baseline.
import tempfile  # noqa: E402
png = os.path.join(tempfile.mkdtemp(), "sens.png")
base_rows = [ss.with_log({"D_over_d": r_, "mean_s": math.exp(1.0 + 0.5 * r_ ** 2) - 1, "se": 1.0,
                          "clogs": 10}) for r_ in (3.0, 3.5, 4.0)]
ss.figure(rows, base_rows, fits, png)
check(os.path.getsize(png) > 10000, "figure %s: %d bytes" % (png, os.path.getsize(png)))
try:
    ss.figure([dict(r, clogs=0) for r in rows], base_rows, {}, png + "2")
    check(False, "a figure without a lever with clogs must refuse")
except SystemExit as e:
    check("no lever with clogs" in str(e), str(e))
check.finish()
