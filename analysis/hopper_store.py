"""Read a hopper campaign store (STORE.h5) into pandas DataFrames and xarray Datasets.

    import sys; sys.path.insert(0, "analysis")      # or PYTHONPATH=analysis
    from hopper_store import open_store             # installed: from hopper_analysis import ...
    with open_store("build/quickstart.h5") as s:
        s.points          # one row per point: label, D_cm, theta_deg, every scene setting typed
        s.realizations    # one row per stored realization (seed and seed_str, status, jams, ...)
        s.survival        # one row per survival interval: duration (s, > 0), event (1 jam, 0 censored)
        s.events, s.curves, s.jams, s.exits      # the ragged per-realization arrays, long form
        s.analysis        # /analysis/points (after `campaign analyze`; NaN where not computable)
        s.beverloo, s.jam_rate, s.km              # the fits and Kaplan-Meier curves of /analysis
        s.fields()        # {label: xarray.Dataset} merged field maps (/analysis/fields)
        s.varied          # the scene settings whose value differs between points

A point's settings come from the typed /points/parameters (every scene parameter of the scene
schema, in SI, with its unit: docs/store.md), not from its label, so every column has its type
(numbers float64, integers int64, choices str) and a setting that differs between points is found
even when the labels do not show it (a store extended with --allow-mixed). Stores written before
that dataset are read from their canonical scene texts (/points/scene, one `name=value` a line,
the same names and SI values). Numbers in SI as stored,
plus the label's units for the outlet and the angle (D_cm, theta_deg), as the sweep file wrote
them (60, not 59.99999999999999). Seeds are uint64; `seed_str` repeats each as text ('s' and its
digits), which R's read.csv and spreadsheets keep exact where they would round a number above
2^53.

Reading needs Debian's python3-h5py, -numpy and -pandas; fields() also python3-xarray. While a
`campaign run` writes the store (or after a run was killed, before the next one), open_store()
reads a snapshot of it taken from its journal, which holds every realization stored at that
moment (docs/store.md, "Reading a store during a run"): it runs `campaign export STORE
--snapshot` with the executable named by $HOPPER_CAMPAIGN, else `campaign` on PATH, else the
source tree's build/src/cli/campaign. Such a Store is a snapshot: realizations stored after
open_store() returned are not in it (open it again to see them; `s.snapshot` says whether it is
one). The snapshot's temporary directory is removed by close(), by the end of a `with` block, or
when the Store is garbage-collected, without a ResourceWarning.
"""
import contextlib
import fcntl
import math
import os
import shutil
import struct
import subprocess
import tempfile
import weakref

import sys

try:
    import h5py
    import numpy as np
    import pandas as pd
except ImportError as missing:  # another python3 first on PATH (conda, pyenv, a bare venv)
    raise ImportError(
        "hopper_store needs h5py, numpy and pandas, which this Python (%s) cannot import (%s). "
        "Use Debian's /usr/bin/python3 (./install-deps.sh installs python3-h5py, -numpy, "
        "-pandas), e.g. `/usr/bin/python3 script.py`, or a venv made from it: "
        "/usr/bin/python3 -m venv --system-site-packages ENV (README, \"Install and cite\")"
        % (sys.executable, missing), name=getattr(missing, "name", None)) from missing

__all__ = ["open_store", "readable", "writer_active", "Store", "parse_scene", "SETTING_INFO", "setting_text", "varied_settings", "positive_durations"]

# Scene parameter -> (short symbol for legends, unit shown, factor from the stored SI value).
# Parameters not listed are shown by their name and stored value.
SETTING_INFO = {
    "hopper.outlet_m": ("D", "cm", 100.0),
    "hopper.theta_rad": ("\u03b8", "\u00b0", 180.0 / math.pi),
    "hopper.width_m": ("W", "cm", 100.0),
    "hopper.wall_diameter_m": ("d_w", "cm", 100.0),
    "particles.count": ("N", "", 1.0),
    "particles.small_fraction": ("f_small", "", 1.0),
    "particles.d_small_m": ("d_s", "cm", 100.0),
    "particles.d_large_m": ("d_l", "cm", 100.0),
    "material.e_n": ("e", "", 1.0),
    "material.mu": ("\u03bc", "", 1.0),
    "walls.e_n": ("e_w", "", 1.0),
    "walls.mu": ("\u03bc_w", "", 1.0),
    "material.kt_over_kn": ("k_t/k_n", "", 1.0),
    "material.collision_time_s": ("\u03c4_c", "s", 1.0),
    "integrator.scheme": ("", "", 1.0),
    "integrator.steps_per_collision": ("\u03b4", "", 1.0),
    "protocol.shake_direction_rad": ("shake", "\u00b0", 180.0 / math.pi),
}


def _typed(text):
    """A scene value as int, float, None ('unset') or str."""
    if text == "unset":
        return None
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def as_written(si, unit):
    """A value in the sweep file's unit as the file wrote it: the shortest decimal x with
    x * unit == si (the sweep file's value, converted to SI once by the config layer, comes back
    as 60, not as the quotient 59.99999999999999), else the plain quotient."""
    si = float(si)
    for digits in range(1, 18):
        x = float("%.*g" % (digits, si / unit))
        if x * unit == si:
            return x
    return si / unit


# Sweep-file units of the label's settings (the same factors as hopper::core, units.hpp).
CM = 1e-2
DEG = math.pi / 180.0


def parse_scene(text):
    """A point's canonical scene text -> {name: typed value}, in the text's order."""
    out = {}
    for line in text.splitlines():
        name, eq, value = line.partition("=")
        if eq:
            out[name] = _typed(value)
    return out


def setting_text(name, value):
    """Short legend text of one setting: 'D = 2.7 cm', 'theta = 45 deg', 'mu = 0.5', 'gear4'."""
    symbol, unit, factor = SETTING_INFO.get(name, (name, "", 1.0))
    if isinstance(value, str) or value is None:
        return ("%s = %s" % (symbol, value)) if symbol else str(value)
    v = float(value) * factor
    num = "%.4g" % v
    if unit == "\u00b0":
        return "%s = %s%s" % (symbol, num, unit)
    return "%s = %s%s" % (symbol, num, (" " + unit) if unit else "")


def _same_partition(a, b):
    """True when two columns split the rows into the same groups."""
    ka = pd.factorize(a.astype(str))[0]
    kb = pd.factorize(b.astype(str))[0]
    return bool(np.array_equal(ka, kb))


def varied_settings(points, scene_columns):
    """The scene settings whose value differs between points, without those that only follow
    another (walls.mu that follows material.mu): the outlet and the angle first, then the
    others in scene-text order."""
    order = [c for c in ("hopper.outlet_m", "hopper.theta_rad") if c in scene_columns]
    order += [c for c in scene_columns if c not in order]
    kept = []
    for c in order:
        col = points[c]
        if col.astype(str).nunique(dropna=False) < 2:
            continue
        if any(_same_partition(points[k], col) for k in kept):
            continue
        kept.append(c)
    return kept


DETECTOR_INTERVAL_S = 1e-4  # engine default (protocol.detector_interval_s) for old stores


def positive_durations(survival, points):
    """The survival table's durations with every 0.0 (a jam at the opening, or a censored
    interval of no length) replaced by half its point's detector interval: see Store.survival."""
    d = survival["duration"].to_numpy(float).copy()
    if "protocol.detector_interval_s" in points:
        half = 0.5 * points["protocol.detector_interval_s"].astype(float).fillna(
            DETECTOR_INTERVAL_S).to_numpy()[survival["point"].to_numpy()] if len(d) else d
    else:
        half = np.full(len(d), 0.5 * DETECTOR_INTERVAL_S)
    zero = d <= 0
    d[zero] = half[zero]
    return d


class Store:
    """An open store; DataFrames are read on first use and kept. Use as a context manager or
    call close()."""

    def __init__(self, path):
        self.path = str(path)
        try:
            self._f = h5py.File(self.path, "r")
        except OSError as e:
            raise OSError("cannot read store '%s': %s (is a `campaign run` writing it?)"
                          % (self.path, e)) from e
        if self._f.attrs.get("format", "") != "hopper campaign store":
            self._f.close()
            raise ValueError("'%s' is not a hopper campaign store" % self.path)
        self.name = str(self._f.attrs.get("campaign_name", ""))
        self._cache = {}
        self._fields = None

    @classmethod
    def from_frames(cls, name, frames, fields=None):
        """A Store over given tables instead of a file (synthetic data for tests and figure
        previews): `frames` maps points (with a 'label', 'D_cm', 'theta_deg' and scene columns),
        scene_columns (their names), and any of realizations, survival, events, curves, jams,
        exits, analysis, beverloo, jam_rate, km to DataFrames shaped as the properties return;
        `fields` is what fields() returns."""
        s = cls.__new__(cls)
        s.path, s._f, s.name = "<%s>" % name, None, name
        s._cache = dict(frames)
        s._fields = fields or {}
        return s

    # --- housekeeping -----------------------------------------------------------------------
    def close(self):
        if self._f is not None:
            self._f.close()
            self._f = None
        snapshot = getattr(self, "_snapshot_dir", None)
        if snapshot is not None:
            snapshot.cleanup()
            self._snapshot_dir = None

    @property
    def snapshot(self):
        """Whether this Store reads a snapshot of the journal taken by open_store() (the store
        was being written, or not in step): later realizations are not in it."""
        return getattr(self, "_is_snapshot", False)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _cached(self, key, make):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    @property
    def has_analysis(self):
        if self._f is None:
            return "analysis" in self._cache
        return "analysis" in self._f and "points" in self._f["analysis"]

    # --- points -------------------------------------------------------------------------------
    @property
    def points(self):
        """One row per point (index: the point's row in /points)."""
        return self._cached("points", self._read_points)

    @property
    def scene_columns(self):
        self.points
        return self._cache["scene_columns"]

    @property
    def varied(self):
        """Scene settings that differ between points (see varied_settings)."""
        return self._cached("varied", lambda: varied_settings(self.points, self.scene_columns))

    @property
    def group_settings(self):
        """The varied settings other than the outlet: a 'group' is one value of each."""
        return [c for c in self.varied if c != "hopper.outlet_m"]

    def _read_points(self):
        p = self._f["points"]
        labels = p["label"].asstr()[:]
        values, names, stored_kind = self._point_parameters(p)
        # D and theta as the sweep file wrote them, from the scene's SI values (stores written
        # before the plan kept the written value hold the quotient in /points)
        D = [as_written(v, CM) if v is not None else float(w)
             for v, w in zip(values.get("hopper.outlet_m", [None] * len(labels)), p["D_cm"][:])]
        theta = [as_written(v, DEG) if v is not None else float(w)
                 for v, w in zip(values.get("hopper.theta_rad", [None] * len(labels)),
                                 p["theta_deg"][:])]
        df = pd.DataFrame({
            "label": labels,
            "D_cm": np.array(D, dtype=float),
            "theta_deg": np.array(theta, dtype=float),
            "particles": p["particles"][:].astype(np.int64),
            "realizations_planned": p["realizations"][:].astype(np.int64),
            "physics_hash": p["physics_hash"].asstr()[:] if h5py.check_string_dtype(
                p["physics_hash"].dtype) else p["physics_hash"][:],
        })
        for n in names:
            col = values[n]
            kinds = {type(v) for v in col if v is not None}
            if stored_kind.get(n) == "f":  # a number column of /points/parameters stays float
                kinds |= {float}
            if kinds <= {int}:
                col = pd.array(col, dtype="Int64") if None in col else np.array(col, dtype=np.int64)
            elif kinds <= {int, float}:
                col = np.array([np.nan if v is None else float(v) for v in col])
            else:
                col = np.array(["" if v is None else str(v) for v in col], dtype=object)
            df[n] = col
        df.index.name = "point"
        self._cache["scene_columns"] = names
        return df

    @staticmethod
    def _point_parameters(p):
        """{name: [value per point]} and the names in order: from the typed /points/parameters
        (every scene parameter in SI, docs/store.md) where the store has it; for stores written
        before it, and for a point it could not type, from the scene text (the legacy path)."""
        n = p["label"].shape[0]
        values, names, kinds = {}, [], {}
        typed = [False] * n
        if "parameters" in p and isinstance(p["parameters"], h5py.Dataset):
            rec = p["parameters"][:]
            typed = [bool(t) for t in rec["typed"]] if "typed" in rec.dtype.names else [True] * n
            members = rec.dtype.names
            for name in members:
                if name == "typed" or (name.startswith("has_") and name[4:] in members):
                    continue
                col = rec[name]
                if col.dtype.kind in "OSU":
                    vals = [v.decode() if isinstance(v, bytes) else str(v) for v in col]
                elif col.dtype.kind in "iu":
                    vals = [int(v) for v in col]
                else:
                    vals = [float(v) for v in col]
                if "has_" + name in members:  # an optional parameter: unset where its flag is off
                    vals = [v if h else None for v, h in zip(vals, rec["has_" + name])]
                values[name] = [v if t else None for v, t in zip(vals, typed)]
                names.append(name)
                kinds[name] = col.dtype.kind
        if not all(typed):
            scenes = p["scene"].asstr()[:]
            for i in range(n):
                if typed[i]:
                    continue
                for k, v in parse_scene(scenes[i]).items():
                    if k not in values:
                        values[k] = [None] * n
                        names.append(k)
                    values[k][i] = v
        return values, names, kinds

    def group_of(self, point):
        """Short text of a point's group (its varied settings other than D), e.g. 'theta = 45'."""
        row = self.points.loc[point]
        return ", ".join(setting_text(c, row[c]) for c in self.group_settings)

    def groups(self):
        """{group text: [point rows sorted by D]} in order of first appearance."""
        out = {}
        for i in self.points.index:
            out.setdefault(self.group_of(i), []).append(i)
        return {g: sorted(rows, key=lambda i: self.points.at[i, "D_cm"]) for g, rows in out.items()}

    # --- realizations -------------------------------------------------------------------------
    @property
    def realizations(self):
        """One row per stored realization (index: its row in /realizations)."""
        return self._cached("realizations", self._read_realizations)

    def _read_realizations(self):
        r = self._f["realizations"]
        n = r["point"].shape[0]
        cols = {}
        for k in r:
            d = r[k]
            if not isinstance(d, h5py.Dataset) or d.shape != (n,):
                continue
            enum = h5py.check_enum_dtype(d.dtype)
            if enum is not None and set(enum) != {"FALSE", "TRUE"}:
                names = {v: key for key, v in enum.items()}
                cols[k] = np.array([names[v] for v in d[:]], dtype=object)
            elif h5py.check_string_dtype(d.dtype):
                cols[k] = d.asstr()[:]
            else:
                cols[k] = d[:]
        df = pd.DataFrame(cols)
        if "seed" in df:
            # R's read.csv and spreadsheets read integers above 2^53 as doubles (a seed above
            # 2^63 no longer reproduces its realization): the seed as text as well, with a
            # letter so that no reader takes it for a number
            df.insert(list(df.columns).index("seed") + 1, "seed_str",
                      np.array(["s%d" % v for v in df["seed"].to_numpy()], dtype=object))
        for name in ("empty_time", "discharge_rate"):
            if "has_" + name in df:
                df[name] = df[name].where(df["has_" + name].astype(bool))
                df = df.drop(columns="has_" + name)
        if "discharge_rate_mass" in df and "discharge_rate" in df:
            df["discharge_rate_mass"] = df["discharge_rate_mass"].where(df["discharge_rate"].notna())
        p = self.points
        df.insert(1, "label", p["label"].to_numpy()[df["point"].to_numpy()] if n else [])
        df.insert(2, "D_cm", p["D_cm"].to_numpy()[df["point"].to_numpy()] if n else [])
        df.insert(3, "theta_deg", p["theta_deg"].to_numpy()[df["point"].to_numpy()] if n else [])
        first = ["point", "label", "D_cm", "theta_deg", "realization", "seed", "seed_str",
                 "status", "message"]
        df = df[[c for c in first if c in df] + [c for c in df if c not in first]]
        df.index.name = "row"
        return df

    def _ragged(self, family, names, rename=None):
        """Long form of a ragged family: one row per value, with the realization's row, point
        and index."""
        r = self._f["realizations"]
        start = r[family + "_start"][:].astype(np.int64)
        length = r[family + "_length"][:].astype(np.int64)
        rows = np.repeat(np.arange(len(start)), length)
        idx = np.concatenate([np.arange(s, s + n) for s, n in zip(start, length)]) \
            if len(start) else np.zeros(0, np.int64)
        real = self.realizations
        cols = {"row": rows, "point": real["point"].to_numpy()[rows],
                "realization": real["realization"].to_numpy()[rows]}
        for name in names:
            d = self._f["ragged/" + name]
            enum = h5py.check_enum_dtype(d.dtype)
            values = d[:][idx] if len(idx) else d[:0]
            if enum is not None and set(enum) != {"FALSE", "TRUE"}:
                inv = {v: key for key, v in enum.items()}
                values = np.array([inv[v] for v in values], dtype=object)
            cols[(rename or {}).get(name, name)] = values
        return pd.DataFrame(cols)

    @property
    def survival(self):
        """One row per survival interval: row, point, realization, label, D_cm, theta_deg,
        interval (0-based within the realization), duration (s of discharge time), event (1: ended
        by a jam, 0: right-censored), avalanche_size (grains that crossed the outlet during the
        interval; NaN for realizations stored before avalanche sizes were recorded),
        duration_stored (s: the store's value, which `campaign analyze` uses). Failed
        realizations are left out. Ready for lifelines (KaplanMeierFitter().fit(df.duration,
        df.event), ExponentialFitter, ...) or R's Surv(duration, event) and survreg.

        duration is duration_stored except where that is 0.0: a jam at the opening (the outlet
        region held no particle at any look of the jam detector since the interval began, so the
        jam formed within the first detector interval) or a censored interval of no length.
        Survival tools refuse a time of 0 (R's survreg: "Invalid survival times for this
        distribution"; lifelines' parametric fitters), so such an interval's duration is half
        the point's detector interval (protocol.detector_interval_s, 1e-4 s by default: 5e-5 s,
        the middle of where the jam can lie). No row is dropped; tau from duration differs from
        campaign analyze's by at most that half interval per such row."""
        def make():
            has_sizes = "avalanche_size" in self._f["ragged"]
            df = self._ragged("survival", ["survival_times", "censored"]
                              + (["avalanche_size"] if has_sizes else []),
                              {"survival_times": "duration"})
            df["event"] = (~df.pop("censored").astype(bool)).astype(np.int64)
            known = self.realizations["has_avalanche_sizes"].to_numpy().astype(bool) \
                if has_sizes and "has_avalanche_sizes" in self.realizations else None
            if known is not None and len(df):
                sizes = df.pop("avalanche_size").astype(float)
                df["avalanche_size"] = np.where(known[df["row"].to_numpy()], sizes, np.nan)
            else:
                if "avalanche_size" in df:
                    df = df.drop(columns="avalanche_size")
                df["avalanche_size"] = np.full(len(df), np.nan)
            df = self._add_point_columns(df)
            df.insert(3, "interval", df.groupby("row").cumcount())
            df["duration_stored"] = df["duration"].astype(float)
            df["duration"] = positive_durations(df, self.points)
            ok = self.realizations["status"].to_numpy()[df["row"].to_numpy()] != "failed" \
                if len(df) else np.zeros(0, bool)
            return df[ok].reset_index(drop=True)
        return self._cached("survival", make)

    def _add_point_columns(self, df):
        p = self.points
        pt = df["point"].to_numpy()
        df.insert(3, "label", p["label"].to_numpy()[pt] if len(df) else [])
        df.insert(4, "D_cm", p["D_cm"].to_numpy()[pt] if len(df) else [])
        df.insert(5, "theta_deg", p["theta_deg"].to_numpy()[pt] if len(df) else [])
        return df

    @property
    def events(self):
        """One row per event: kind (settled, opened, jam, shake_start, ...), time (s of discharge
        time), sim_time (s since the fill), in_hopper."""
        return self._cached("events", lambda: self._add_point_columns(self._ragged(
            "event", ["event_kind", "event_time", "event_sim_time", "event_in_hopper"],
            {"event_kind": "kind", "event_time": "time", "event_sim_time": "sim_time",
             "event_in_hopper": "in_hopper"})))

    @property
    def curves(self):
        """Discharge curves: one row per sample, time (s of discharge time) and in_hopper."""
        return self._cached("curves", lambda: self._add_point_columns(self._ragged(
            "curve", ["curve_time", "curve_in_hopper"],
            {"curve_time": "time", "curve_in_hopper": "in_hopper"})))

    def _family_arrays(self, family, known):
        """The /ragged arrays of a family: those whose "family" attribute names it (files from
        issue 42 on: every array the engine describes, later ones included), else `known`."""
        g = self._f["ragged"]
        tagged = [k for k in g if g[k].attrs.get("family") in (family, family.encode())]
        return [k for k in known if k in g] + [k for k in tagged if k not in known]

    def _blank_older_rows(self, df, names):
        """NaN in the arrays a row's result is older than (their "since" attribute above its
        result_version): those rows hold padding there, not values."""
        if "result_version" not in self._f["realizations"] or not len(df):
            return df
        version = self._f["realizations/result_version"][:][df["row"].to_numpy()]
        for name, column in names.items():
            since = int(self._f["ragged/" + name].attrs.get("since", 1))
            if since > 1:
                df[column] = df[column].astype(float).where(version >= since)
        return df

    @property
    def jams(self):
        """One row per jam: onset (s of discharge time), shakes (to restart the flow), and every
        later per-jam observable under its own name (docs/model.md, "Realization protocol",
        step 9; NaN for jams of realizations stored before it existed)."""
        def make():
            rename = {"jam_onsets": "onset", "shakes_per_jam": "shakes"}
            names = self._family_arrays("jam", list(rename))
            df = self._ragged("jam", names, rename)
            df = self._blank_older_rows(df, {n: rename.get(n, n) for n in names})
            return self._add_point_columns(df)
        return self._cached("jams", make)

    @property
    def arches(self):
        """One row per jam of a realization that recorded arches: jam (0-based within the
        realization), disks (0: no arch found), span (m), max_angle (deg), and the disks' ids and
        centres (m) as lists left to right. Empty for stores written before arches existed."""
        def make():
            if "arch_disks" not in self._f["ragged"]:
                return pd.DataFrame(columns=["row", "point", "realization", "label", "D_cm",
                                             "theta_deg", "jam", "disks", "span", "max_angle",
                                             "ids", "x", "y"])
            df = self._ragged("arch", ["arch_disks", "arch_span", "arch_max_angle"],
                              {"arch_disks": "disks", "arch_span": "span",
                               "arch_max_angle": "max_angle"})
            df["max_angle"] = np.degrees(df["max_angle"].astype(float))
            disks = self._ragged("arch_disk", ["arch_disk_id", "arch_disk_x", "arch_disk_y"])
            ids, xs, ys = [], [], []
            at = {}
            for row, group in disks.groupby("row", sort=False):
                at[row] = (group["arch_disk_id"].to_numpy(), group["arch_disk_x"].to_numpy(),
                           group["arch_disk_y"].to_numpy(), 0)
            for row, n in zip(df["row"].to_numpy(), df["disks"].to_numpy()):
                i, x, y, k = at.get(row, (np.zeros(0), np.zeros(0), np.zeros(0), 0))
                ids.append(list(i[k:k + n]))
                xs.append(list(x[k:k + n]))
                ys.append(list(y[k:k + n]))
                if row in at:
                    at[row] = (i, x, y, k + n)
            df["ids"], df["x"], df["y"] = ids, xs, ys
            df = self._add_point_columns(df)
            df.insert(6, "jam", df.groupby("row").cumcount())
            return df
        return self._cached("arches", make)

    @property
    def exits(self):
        """One row per particle that left: time (s of discharge time)."""
        return self._cached("exits", lambda: self._add_point_columns(self._ragged(
            "exit", ["exit_times"], {"exit_times": "time"})))

    # --- /analysis ----------------------------------------------------------------------------
    def _require_analysis(self):
        if not self.has_analysis:
            raise LookupError("'%s' has no /analysis group: run `campaign analyze %s`"
                              % (self.path, self.path))

    def _table(self, group):
        cols = {}
        n = None
        for k in group:
            d = group[k]
            if not isinstance(d, h5py.Dataset) or len(d.shape) != 1:
                continue
            if n is None:
                n = d.shape[0]
            if d.shape[0] != n:
                continue
            cols[k] = d.asstr()[:] if h5py.check_string_dtype(d.dtype) else d[:]
        df = pd.DataFrame(cols)
        # a value whose has_<name> flag is FALSE is missing: NaN
        for k in [c for c in df.columns if c.startswith("has_")]:
            name = k[4:]
            flag = df[k].astype(bool)
            if name in df:
                df[name] = df[name].where(flag)
        return df

    @property
    def analysis(self):
        """/analysis/points: one row per point (index: point), the statistics of `campaign
        analyze`; a value that could not be computed is NaN (its has_ flag is kept)."""
        def make():
            self._require_analysis()
            df = self._table(self._f["analysis/points"])
            row = {lab: i for i, lab in enumerate(self.points["label"])}
            df.index = [row[lab] for lab in df["label"]]
            df.index.name = "point"
            return df
        return self._cached("analysis", make)

    def _group_table(self, name):
        def make():
            self._require_analysis()
            return self._table(self._f["analysis/" + name])
        return self._cached(name, make)

    @property
    def beverloo(self):
        """/analysis/beverloo: one row per group (C, k with errors, rho_b, d, reason)."""
        return self._group_table("beverloo")

    @property
    def avalanche(self):
        """/analysis/avalanche: <s>(D) per group, exponential growth and power-law divergence
        (Zuriguel's form) with the AIC verdict."""
        return self._group_table("avalanche")

    @property
    def jam_rate(self):
        """/analysis/jam_rate: the exponential and power-law fits of the jam rate per group."""
        return self._group_table("jam_rate")

    @property
    def km(self):
        """Kaplan-Meier curves: point, time (s), survival, std_err."""
        def make():
            self._require_analysis()
            a = self.analysis
            k = self._f["analysis/km"]
            t, s, e = k["time"][:], k["survival"][:], k["std_err"][:]
            parts = []
            for i in a.index:
                s0, n = int(a.at[i, "km_start"]), int(a.at[i, "km_length"])
                parts.append(pd.DataFrame({"point": i, "time": t[s0:s0 + n],
                                           "survival": s[s0:s0 + n], "std_err": e[s0:s0 + n]}))
            return pd.concat(parts, ignore_index=True) if parts else \
                pd.DataFrame(columns=["point", "time", "survival", "std_err"])
        return self._cached("km", make)

    def fields(self):
        """{label: xarray.Dataset} of the merged field maps per point (/analysis/fields): data
        variables windows, weight, mean_F and std_F for F in vx, vy, speed (m/s) and pressure
        (m g), on coordinates y, x (m, cell centres); NaN where no window reached a cell.
        Empty when the store has no fields."""
        import xarray as xr
        if self._f is None:
            return self._fields
        self._require_analysis()
        a = self._f["analysis"]
        if "fields" not in a:
            return {}
        g = a["fields"]
        out = {}
        for label in g["labels"].asstr()[:]:
            key = label.replace("/", "_")
            if key not in g:
                continue
            h = g[key]
            nx, ny, cell = int(h.attrs["nx"]), int(h.attrs["ny"]), float(h.attrs["cell"])
            x = float(h.attrs["x0"]) + cell * (np.arange(nx) + 0.5)
            y = float(h.attrs["y0"]) + cell * (np.arange(ny) + 0.5)
            empty = h["windows"][:] == 0
            data = {}
            for k in h:
                d = h[k]
                if isinstance(d, h5py.Dataset) and d.shape == (ny, nx):
                    v = d[:].astype(float)
                    if k.startswith(("mean_", "std_")):
                        v[empty] = np.nan
                    data[k] = (("y", "x"), v, {"units": str(d.attrs.get("units", "")),
                                               "description": str(d.attrs.get("description", ""))})
            attrs = {}
            for k, v in h.attrs.items():
                attrs[k] = v.decode() if isinstance(v, bytes) else v
            ds = xr.Dataset(data, coords={"x": ("x", x, {"units": "m"}),
                                          "y": ("y", y, {"units": "m"})}, attrs=attrs)
            ds["outline_x"] = ("outline", h["outline_x"][:], {"units": "m"})
            ds["outline_y"] = ("outline", h["outline_y"][:], {"units": "m"})
            out[label] = ds
        return out


def writer_active(path):
    """Whether a `campaign run` is writing the store: it holds a write lock on the journal (an
    open-file-description lock, asked with F_OFD_GETLK; nothing is locked by asking)."""
    journal = str(path) + ".journal"
    try:
        fd = os.open(journal, os.O_RDONLY)
    except FileNotFoundError:
        return False
    try:
        # struct flock: l_type, l_whence, l_start, l_len, l_pid (0 for OFD locks), padded.
        query = struct.pack("hhqqi4x", fcntl.F_WRLCK, os.SEEK_SET, 0, 0, 0)
        answer = fcntl.fcntl(fd, getattr(fcntl, "F_OFD_GETLK", 36), query)
        return struct.unpack("hhqqi4x", answer)[0] != fcntl.F_UNLCK
    finally:
        os.close(fd)


def _in_step(path):
    """The HDF5 file was closed by its last writer (no run since): it holds the journal."""
    try:
        with h5py.File(str(path), "r") as f:
            return int(f.attrs.get("consistent", 0)) == 1
    except OSError:
        return False


def campaign_executable():
    """The `campaign` executable that takes snapshots: $HOPPER_CAMPAIGN, `campaign` on PATH, or
    the source tree's build/src/cli/campaign; None when there is none."""
    given = os.environ.get("HOPPER_CAMPAIGN")
    if given:
        return given
    found = shutil.which("campaign")
    if found:
        return found
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "build", "src",
                        "cli", "campaign")
    return os.path.normpath(here) if os.access(here, os.X_OK) else None


def _snapshot(path):
    """A snapshot of the store's journal in a new temporary directory: (directory, file). The
    caller removes the directory (readable() at the end of its block, a Store at close())."""
    exe = campaign_executable()
    if exe is None:
        raise OSError("'%s' is being written by a `campaign run` (or its last run was "
                      "interrupted): reading it then needs the `campaign` executable to take a "
                      "snapshot of its journal; set HOPPER_CAMPAIGN or put it on PATH" % path)
    tmp = tempfile.mkdtemp(prefix="hopper-view-")
    view = os.path.join(tmp, os.path.basename(path))
    done = subprocess.run([exe, "export", path, "--snapshot", view], capture_output=True,
                          text=True)
    if done.returncode != 0:
        shutil.rmtree(tmp, ignore_errors=True)
        raise OSError("cannot take a snapshot of '%s': %s" % (path, done.stderr.strip()))
    return tmp, view


def _needs_snapshot(path):
    return os.path.exists(path + ".journal") and (writer_active(path) or not _in_step(path))


@contextlib.contextmanager
def readable(path):
    """A path that h5py can open now with the store's content: the store itself, or while a
    `campaign run` writes it (or after a killed run) a snapshot of its journal, removed when
    the block ends. For scripts that read the HDF5 layout directly."""
    path = str(path)
    if not _needs_snapshot(path):
        yield path
        return
    tmp, view = _snapshot(path)
    try:
        yield view
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _remove_snapshot(h5file, directory):
    """Closes the snapshot's HDF5 file and removes its directory (a Store's finalizer: it holds
    no reference to the Store)."""
    try:
        h5file.close()
    except Exception:  # noqa: BLE001 - already closed, or h5py shutting down
        pass
    shutil.rmtree(directory, ignore_errors=True)


class _SnapshotDir:
    """The snapshot's directory, removed once by cleanup() or when its Store is collected."""

    def __init__(self, store, directory):
        self.name = directory
        self._finalizer = weakref.finalize(store, _remove_snapshot, store._f, directory)

    def cleanup(self):
        self._finalizer()


def open_store(path):
    """Opens a store for reading (see the module's help). During a run (or after a killed one,
    before the next run repairs the file) it reads a snapshot of the journal instead of the
    HDF5 file, which the writer holds and which lags behind the journal: the Store then holds
    the realizations stored when open_store() was called, not those stored later (open it again
    for them), and `snapshot` is True. Close it (or use `with`) to remove the snapshot's
    temporary directory at once; otherwise it goes when the Store is garbage-collected."""
    path = str(path)
    if not _needs_snapshot(path):
        return Store(path)
    tmp, view = _snapshot(path)
    try:
        s = Store(view)
    except Exception:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    s.path = path
    s._snapshot_dir = _SnapshotDir(s, tmp)
    s._is_snapshot = True
    return s