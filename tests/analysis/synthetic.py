"""Synthetic stores with the label shapes of the paper studies (campaigns/paper/*.toml), for the
figure tests: the points each sweep file expands to (its [sweep] product and [[points]], with the
base [hopper] D and theta), and made-up but plausible statistics for them (exponential survival
times whose mean falls with D, Beverloo flow rates, discharge curves, jams, field maps). Only the
shapes matter here: how many points, groups and outlets, which settings vary and how long the
labels are."""
import itertools
import math
import tomllib

import numpy as np
import pandas as pd

import hopper_store

# sweep-file key -> (scene column, factor to SI)
KEYS = {"D_cm": ("hopper.outlet_m", 0.01), "theta_deg": ("hopper.theta_rad", math.pi / 180),
        "width_cm": ("hopper.width_m", 0.01)}
BASE = {"hopper.width_m": 0.43, "hopper.outlet_m": 0.045, "hopper.theta_rad": math.pi / 3,
        "particles.count": 8750, "material.e_n": 0.5, "material.mu": 0.8,
        "material.kt_over_kn": 0.8, "integrator.scheme": "gear4"}


def scene_name(section, key):
    if section == "hopper" and key in KEYS:
        return KEYS[key]
    return ("%s.%s" % (section, key), 1.0)


def expand(path):
    """[(settings {sweep-file name: value}, scene {column: SI value}, realizations)]."""
    doc = tomllib.load(open(path, "rb"))
    hop = doc.get("hopper", {})
    base = dict(BASE)
    for section in ("hopper", "material", "walls"):
        for k, v in doc.get(section, {}).items():
            col, f = scene_name(section, k)
            base[col] = v * f if isinstance(v, (int, float)) and not isinstance(v, bool) else v
    n_real = doc.get("campaign", {}).get("realizations", 1)
    sweep = {}
    for k, v in doc.get("sweep", {}).items():  # TOML dotted keys arrive as nested tables
        if isinstance(v, dict):
            sweep.update({"%s.%s" % (k, kk): vv for kk, vv in v.items()})
        else:
            sweep[k] = v
    entries = []
    axes = sorted(sweep, key=lambda k: (k not in ("D_cm", "theta_deg"), k != "D_cm", k))
    if sweep or not doc.get("points"):  # neither [sweep] nor [[points]]: the base scene
        for combo in itertools.product(*(sweep[a] for a in axes)):
            entries.append((dict(zip(axes, combo)), n_real))
    for p in doc.get("points", []):
        s = {}
        for k, v in p.items():
            if isinstance(v, dict):
                s.update({"%s.%s" % (k, kk): vv for kk, vv in v.items()})
            elif k != "realizations":
                s[k] = v
        entries.append((s, p.get("realizations", n_real)))
    out = []
    for s, n in entries:
        s = dict(s)
        s.setdefault("D_cm", hop.get("D_cm", 4.5))
        s.setdefault("theta_deg", hop.get("theta_deg", 60))
        scene = dict(base)
        for k, v in s.items():
            if k in KEYS:
                col, f = KEYS[k]
            else:
                section, _, key = k.partition(".")
                col, f = scene_name(section, key)
            scene[col] = v * f if isinstance(v, (int, float)) else v
        for w in ("e_n", "mu"):  # walls follow the material unless given
            if "walls." + w not in s and w not in doc.get("walls", {}):
                scene["walls." + w] = scene["material." + w]
        out.append((s, scene, max(2, min(n, 6))))  # enough to draw, few enough to be quick
    return out, bool(doc.get("fields", {}).get("enabled", False))


def label_of(settings):
    names = ["D_cm", "theta_deg"] + sorted(k for k in settings if k not in ("D_cm", "theta_deg"))
    return " ".join("%s=%g" % (k, settings[k]) if isinstance(settings[k], (int, float))
                    else "%s=%s" % (k, settings[k]) for k in names)


def make_store(path, seed=1):
    rng = np.random.default_rng(seed)
    expanded, has_fields = expand(path)
    cols = sorted({c for _, sc, _ in expanded for c in sc})
    points = pd.DataFrame({
        "label": [label_of(s) for s, _, _ in expanded],
        "D_cm": [float(s["D_cm"]) for s, _, _ in expanded],
        "theta_deg": [float(s["theta_deg"]) for s, _, _ in expanded],
    })
    for c in cols:
        points[c] = [sc.get(c) for _, sc, _ in expanded]
    points.index.name = "point"
    groups = {}
    for i, (s, _, _) in enumerate(expanded):
        key = label_of({k: v for k, v in s.items() if k != "D_cm"} | {"D_cm": 0}).split(" ", 1)[1]
        groups.setdefault(key, []).append(i)
    real, surv, curves, jams, events, km, an = [], [], [], [], [], [], []
    row = 0
    for i, (s, sc, n) in enumerate(expanded):
        D = float(s["D_cm"])
        tau = 0.5 * math.exp(2.0 * (D - 2.7))
        total, r_jams, durations = 0.0, 0, []
        for k in range(n):
            T = 20.0
            t, onsets = 0.0, []
            while True:
                x = rng.exponential(tau)
                if t + x > T:
                    durations.append((T - t, 0))
                    break
                t += x
                onsets.append(t)
                durations.append((x, 1))
            for j, (d, e) in enumerate(durations[-(len(onsets) + 1):]):
                surv.append((row, i, k, j, d, e))
            for o in onsets:
                jams.append((row, i, k, o, 1))
            events.append((row, i, k, "stop", T, T + 2, 0))
            rate = 2.0 * (D / 100 - 0.012) ** 1.5 * 1000 * (1 + 0.05 * rng.standard_normal())
            real.append((row, i, k, "complete", len(onsets), T, rate))
            for tt in np.linspace(0, T, 20):
                curves.append((row, i, k, tt, int(8750 * max(0.0, 1 - tt / T))))
            r_jams += len(onsets)
            total += T
            row += 1
        d_sorted = sorted(d for d, _ in durations)
        surv_curve = np.linspace(1, 1.0 / len(d_sorted), len(d_sorted))
        start = len(km)
        km += [(i, t, sv, 0.05) for t, sv in zip(d_sorted, surv_curve)]
        tau_hat = total / r_jams if r_jams else np.nan
        an.append({"label": points.at[i, "label"], "group": "", "tau_mle": tau_hat,
                   "tau_ci95_lo": tau_hat * 0.7, "tau_ci95_hi": tau_hat * 1.5,
                   "tau_lower_bound95": total / 3.0 if not r_jams else np.nan,
                   "n_jams": r_jams, "km_start": start, "km_length": len(d_sorted),
                   "discharge_rate_kg_s": 2.0 * (D / 100 - 0.012) ** 1.5,
                   "discharge_rate_kg_s_err": 1e-4, "empty_time_mean": 30.0 / D,
                   "empty_time_err": 0.5})
    gtext = {}
    for g, rows in groups.items():
        for i in rows:
            an[i]["group"] = g
    analysis = pd.DataFrame(an)
    analysis.index.name = "point"
    bev, jr = [], []
    for g, rows in groups.items():
        ok = len(rows) >= 3
        th = float(points.at[rows[0], "theta_deg"])
        bev.append({"group": g, "theta_deg": th, "C": 0.6 if ok else np.nan,
                    "C_err": 0.02, "k": 1.4 + th / 100 if ok else np.nan, "k_err": 0.1,
                    "rho_b": 2.6, "d": 0.0067, "reason": "" if ok else "fewer than 3 outlets"})
        jr.append({"group": g, "theta_deg": th, "exp_ln_A": 6.0 if ok else np.nan,
                   "exp_B": 200.0 if ok else np.nan, "pow_ln_A": np.nan, "pow_gamma": np.nan,
                   "pow_Dc": np.nan})
    frames = {
        "points": points, "scene_columns": cols,
        "realizations": pd.DataFrame(real, columns=["row", "point", "realization", "status",
                                                    "n_jams", "empty_time",
                                                    "discharge_rate_mass"]).set_index("row"),
        "survival": pd.DataFrame(surv, columns=["row", "point", "realization", "interval",
                                                "duration", "event"]),
        "jams": pd.DataFrame(jams, columns=["row", "point", "realization", "onset", "shakes"]),
        "events": pd.DataFrame(events, columns=["row", "point", "realization", "kind", "time",
                                                "sim_time", "in_hopper"]),
        "curves": pd.DataFrame(curves, columns=["row", "point", "realization", "time",
                                                "in_hopper"]),
        "km": pd.DataFrame(km, columns=["point", "time", "survival", "std_err"]),
        "analysis": analysis, "beverloo": pd.DataFrame(bev), "jam_rate": pd.DataFrame(jr),
    }
    frames["realizations"]["discharge_rate_mass"] /= 1000
    fields = {}
    if has_fields:
        for i in points.index:
            fields[points.at[i, "label"]] = synthetic_fields(rng)
    return hopper_store.Store.from_frames(path.stem, frames, fields)


def synthetic_fields(rng):
    """A 43 cm x 60 cm grid of 1.54 cm cells with a funnel-shaped outline."""
    import xarray as xr
    cell, nx, ny = 0.0154, 28, 40
    x = -nx / 2 * cell + cell * (np.arange(nx) + 0.5)
    y = -0.03 + cell * (np.arange(ny) + 0.5)
    X, Y = np.meshgrid(x, y)
    speed = 0.02 + 0.8 * np.exp(-(X ** 2 + (Y + 0.01) ** 2) / 0.002)
    data = {"windows": (("y", "x"), np.full((ny, nx), 50.0))}
    for stat, f in (("mean", 1.0), ("std", 0.2)):
        data[stat + "_vx"] = (("y", "x"), f * 0.1 * X / 0.2 * speed, {"units": "m/s"})
        data[stat + "_vy"] = (("y", "x"), -f * speed, {"units": "m/s"})
        data[stat + "_speed"] = (("y", "x"), f * speed, {"units": "m/s"})
        data[stat + "_pressure"] = (("y", "x"), f * np.clip(0.5 - Y, 0, None) * 40, {"units": "1"})
    ds = xr.Dataset(data, coords={"x": x, "y": y},
                    attrs={"cell": cell, "x0": -nx / 2 * cell, "y0": -0.03, "kernel": "cell",
                           "kernel_width": 0.0, "realizations": 3, "wall_diameter": 0.0077})
    ds["outline_x"] = ("outline", np.array([0.025, 0.2, 0.215, 0.215]))
    ds["outline_y"] = ("outline", np.array([0.0, 0.3, 0.3, 0.6]))
    return ds
