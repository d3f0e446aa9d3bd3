#!/usr/bin/python3
"""Figures of a campaign store (after `campaign analyze`, which `campaign run` does at the end).

usage: /usr/bin/python3 analysis/plots.py STORE.h5 --out DIR
           [--compare LABEL_A LABEL_B [--field vx|vy|speed|pressure] [--compare-out PATH]]

Writes into DIR (created if needed):
  survival.png     survival-time distribution per point: Kaplan-Meier curve (log scale) with its
                   Greenwood band and the fitted exponential exp(-t/tau), tau the censored MLE
  jam_onsets.png   every jam's onset (discharge time) per realization, per wall angle, with the
                   early/late test's p-value per outlet
  beverloo.png     mass flow rate versus outlet D with the Beverloo fits, and k versus theta
  in_hopper.png    particles in the hopper versus discharge time, per wall angle
  fields_<label>.png  per point with fields (/analysis/fields): the mean and the fluctuation
                   (standard deviation over windows) of vx, vy, speed and pressure, walls drawn,
                   cells without data white
  fields_compare.png  with --compare A B: one field (--field, default speed) of points A and B
                   side by side on shared colour scales (e.g. the cell and the Gaussian kernel)
and prints the files it wrote. Reads the raw realizations from /realizations and /ragged and the
fits from /analysis (README, "Analysis"). Needs Debian's python3-h5py, -numpy and -matplotlib.
Exit codes: 0 figures written, 2 bad arguments or a store without /analysis, 1 other errors.
"""
import argparse
import os
import sys

import h5py
import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

G = 9.80665  # m/s^2, as hopper::core::standard_gravity


def fail(msg, code=2):
    print("plots.py: error: " + msg, file=sys.stderr)
    sys.exit(code)


class Store:
    """The parts of a store the figures need."""

    def __init__(self, path):
        self.f = h5py.File(path, "r")
        f = self.f
        if "analysis" not in f or "points" not in f["analysis"]:
            fail("'%s' has no /analysis group: run `campaign analyze %s` first" % (path, path))
        self.name = f.attrs.get("campaign_name", "")
        self.a = f["analysis"]
        ap = self.a["points"]
        self.labels = list(ap["label"].asstr()[:])
        self.groups = list(ap["group"].asstr()[:])
        self.D = ap["D_cm"][:]
        self.theta = ap["theta_deg"][:]
        self.col = {k: ap[k][:] for k in ap if k not in ("label", "group")}
        # /analysis/points rows are in /points order: map the store's point index to them.
        store_labels = list(f["points/label"].asstr()[:])
        row = {lab: i for i, lab in enumerate(self.labels)}
        self.point_row = np.array([row.get(lab, -1) for lab in store_labels])
        r = f["realizations"]
        self.r_point = self.point_row[r["point"][:]] if r["point"].shape[0] else np.zeros(0, int)
        status = h5py.check_enum_dtype(r["status"].dtype)
        names = {v: k for k, v in status.items()}
        self.r_status = np.array([names[s] for s in r["status"][:]])
        self.r_rate_kg = r["discharge_rate_mass"][:]
        self.r_has_rate = r["has_discharge_rate"][:].astype(bool)
        self.r_particles = r["particles"][:]

    def ragged(self, family, name, i):
        r = self.f["realizations"]
        s, n = r[family + "_start"][i], r[family + "_length"][i]
        return self.f["ragged/" + name][s:s + n]

    def get(self, key, i):
        """Value of /analysis/points/<key> for row i, or None when has_<key> is FALSE."""
        if "has_" + key in self.col and not self.col["has_" + key][i]:
            return None
        return self.col[key][i]

    def realizations_of(self, i):
        return [k for k in range(len(self.r_point)) if self.r_point[k] == i and
                self.r_status[k] != "failed"]

    def group_order(self):
        """Groups (theta and other varied settings) in order of first appearance."""
        seen = []
        for g in self.groups:
            if g not in seen:
                seen.append(g)
        return seen


def grid(n, width=4.2, height=3.4, max_cols=4):
    cols = max(1, min(max_cols, n))
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(width * cols, height * rows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return fig, list(axes.flat[:n])


def plot_survival(st, out):
    n = len(st.labels)
    fig, axes = grid(n)
    km = st.a["km"]
    for i, ax in enumerate(axes):
        s0, ln = st.col["km_start"][i], st.col["km_length"][i]
        t, surv, se = km["time"][s0:s0 + ln], km["survival"][s0:s0 + ln], km["std_err"][s0:s0 + ln]
        tau, lo, hi = st.get("tau_mle", i), st.get("tau_ci95_lo", i), st.get("tau_ci95_hi", i)
        p, jams = st.get("gof_p", i), int(st.col["n_jams"][i])
        tmax = st.col["total_observed_time"][i]
        # the longest observed interval bounds where S_KM is known
        longest = 0.0
        for k in st.realizations_of(i):
            x = st.ragged("survival", "survival_times", k)
            if len(x):
                longest = max(longest, float(np.max(x)))
        if ln:
            ts = np.concatenate([[0.0], t, [max(longest, t[-1])]])
            ss = np.concatenate([[1.0], surv, [surv[-1]]])
            ok = ss > 0
            ax.step(ts[ok], ss[ok], where="post", color="C0", label="Kaplan-Meier")
            band_lo = np.clip(surv - 1.96 * se, 1e-6, None)
            band_hi = np.clip(surv + 1.96 * se, None, 1.0)
            ax.fill_between(t, band_lo, band_hi, step="post", color="C0", alpha=0.2,
                            label="95 % Greenwood band")
        if tau is not None:
            tt = np.linspace(0, max(longest, 1e-9), 200)
            ax.plot(tt, np.exp(-tt / tau), "C3--",
                    label=r"exp($-t/\tau$), $\tau$ = %.3g s [%.3g, %.3g]" % (tau, lo, hi))
        else:
            bound = st.get("tau_lower_bound95", i)
            msg = "no jams in %.3g s of flow" % tmax
            if bound is not None:
                msg += "\n" + r"$\tau$ > %.3g s (95 %%)" % bound
            ax.text(0.5, 0.5, msg, transform=ax.transAxes, ha="center", va="center")
        ax.set_yscale("log")
        ax.set_ylim(bottom=max(1e-3, 0.5 / max(1, int(st.col["n_intervals"][i]))), top=1.5)
        ax.set_xlabel("survival time t (s of discharge)")
        ax.set_ylabel("S(t), fraction still flowing")
        ptxt = "p = %.3f" % p if p is not None else "p: too few jams"
        ax.set_title("%s\n%d jams, %d realizations, GoF %s" % (
            st.labels[i], jams, int(st.col["realizations"][i]), ptxt), fontsize=9)
        if ln or tau is not None:
            ax.legend(fontsize=7, loc="lower left")
    fig.suptitle("Survival-time distributions (%s)" % st.name)
    fig.tight_layout()
    path = os.path.join(out, "survival.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_jam_onsets(st, out):
    groups = st.group_order()
    fig, axes = grid(len(groups), width=6.0, height=4.0, max_cols=2)
    for ax, g in zip(axes, groups):
        rows = [i for i in range(len(st.labels)) if st.groups[i] == g]
        rows.sort(key=lambda i: st.D[i])
        yticks, ylabels = [], []
        for y, i in enumerate(rows):
            reals = st.realizations_of(i)
            for j, k in enumerate(reals):
                yy = y + (j + 0.5) / max(1, len(reals)) * 0.8 - 0.4
                end = 0.0
                ev_t = st.ragged("event", "event_time", k)
                if len(ev_t):
                    end = float(np.max(ev_t))
                ax.plot([0, end], [yy, yy], color="0.85", lw=1, zorder=1)
                on = st.ragged("jam", "jam_onsets", k)
                ax.plot(on, np.full(len(on), yy), "v", color="C3", ms=5, zorder=2)
            p = st.get("early_late_p", i)
            yticks.append(y)
            ylabels.append("D = %g cm\n%d jams%s" % (st.D[i], int(st.col["n_jams"][i]),
                                                    ", early/late p = %.2f" % p if p is not None
                                                    else ""))
        ax.set_yticks(yticks)
        ax.set_yticklabels(ylabels, fontsize=7)
        ax.set_xlabel("elapsed discharge time at jam onset (s; shaking excluded)")
        ax.set_title("Jam onsets, %s (grey: each realization's discharge)" % g, fontsize=9)
        ax.set_ylim(-0.6, len(rows) - 0.4)
    fig.suptitle("Jam onsets versus elapsed time (%s)" % st.name)
    fig.tight_layout()
    path = os.path.join(out, "jam_onsets.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_beverloo(st, out):
    b = st.a["beverloo"]
    groups = list(b["group"].asstr()[:])
    fig, (ax, axk) = plt.subplots(1, 2, figsize=(11, 4.2))
    for gi, g in enumerate(groups):
        color = "C%d" % (gi % 10)
        rows = [i for i in range(len(st.labels)) if st.groups[i] == g]
        # each realization
        for i in rows:
            ks = [k for k in st.realizations_of(i) if st.r_has_rate[k]]
            ax.plot(np.full(len(ks), st.D[i]), st.r_rate_kg[ks] * 1e3, ".", color=color,
                    alpha=0.35, ms=4)
        Ds = np.array([st.D[i] for i in rows if st.get("discharge_rate_kg_s", i) is not None])
        W = np.array([st.get("discharge_rate_kg_s", i) for i in rows
                      if st.get("discharge_rate_kg_s", i) is not None])
        We = np.array([st.get("discharge_rate_kg_s_err", i) or 0.0 for i in rows
                       if st.get("discharge_rate_kg_s", i) is not None])
        ax.errorbar(Ds, W * 1e3, yerr=We * 1e3, fmt="o", color=color, capsize=3,
                    label="%s: mean +- s.e." % g)
        if b["has_C"][gi]:
            C, k, rho_b, d = b["C"][gi], b["k"][gi], b["rho_b"][gi], b["d"][gi]
            lo = max(k * d * 100 * 1.001, 0.0)
            DD = np.linspace(lo, max(Ds.max() * 1.1, lo * 1.5), 200)
            WW = C * rho_b * np.sqrt(G) * np.clip(DD / 100 - k * d, 0, None) ** 1.5
            ax.plot(DD, WW * 1e3, "-", color=color,
                    label="Beverloo C = %.3f +- %.2g, k = %.2f +- %.2g" % (
                        C, b["C_err"][gi], k, b["k_err"][gi]))
        else:
            ax.plot([], [], " ", label="%s: no fit (%s)" % (g, b["reason"].asstr()[gi]))
    ax.set_xlabel("outlet width D (cm)")
    ax.set_ylabel("mass flow rate W (g/s, per disk layer)")
    rho = b["rho_b"][0] if len(groups) else 0.0
    ax.set_title("Flow rate vs D; rho_b = %.3g kg/m$^2$ (estimate: 0.82 x rho h)" % rho,
                 fontsize=9)
    ax.legend(fontsize=7)
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    th = b["theta_deg"][:]
    ok = b["has_k"][:].astype(bool)
    if ok.any():
        axk.errorbar(th[ok], b["k"][ok], yerr=b["k_err"][ok], fmt="o-", capsize=3)
    if (~ok).any():
        axk.text(0.5, 0.5, "no Beverloo fit at theta = %s deg\n(%s)" % (
            ", ".join("%g" % t for t in th[~ok]), b["reason"].asstr()[np.argmax(~ok)]),
            transform=axk.transAxes, ha="center", va="center", fontsize=8)
    axk.set_xlabel("wall angle theta (deg)")
    axk.set_ylabel("Beverloo k (in mean diameters d = %.3g mm)" % (
        b["d"][0] * 1e3 if len(groups) else 0.0))
    axk.set_title("k versus theta", fontsize=9)
    fig.suptitle("Beverloo fits (%s)" % st.name)
    fig.tight_layout()
    path = os.path.join(out, "beverloo.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_in_hopper(st, out):
    groups = st.group_order()
    fig, axes = grid(len(groups), width=6.0, height=4.0, max_cols=2)
    for ax, g in zip(axes, groups):
        rows = sorted([i for i in range(len(st.labels)) if st.groups[i] == g],
                      key=lambda i: st.D[i])
        for ci, i in enumerate(rows):
            color = "C%d" % (ci % 10)
            for j, k in enumerate(st.realizations_of(i)):
                t = st.ragged("curve", "curve_time", k)
                c = st.ragged("curve", "curve_in_hopper", k)
                ax.plot(t, c, color=color, lw=1, alpha=0.7,
                        label="D = %g cm" % st.D[i] if j == 0 else None)
        ax.set_xlabel("discharge time (s; shaking excluded)")
        ax.set_ylabel("particles in the hopper")
        ax.set_title("Particles in the hopper, %s (one line per realization)" % g, fontsize=9)
        ax.set_ylim(bottom=0)
        ax.set_xlim(left=0)
        ax.legend(fontsize=7)
    fig.suptitle("Discharge curves (%s)" % st.name)
    fig.tight_layout()
    path = os.path.join(out, "in_hopper.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# ----- coarse-grained fields (issue 7) ------------------------------------------------------------

# name in /analysis/fields, symbol, colour map of the mean, its scale: "centred" (diverging,
# symmetric about 0), "log" (sequential, logarithmic: the outlet jet is ~10x faster than the bulk)
# or "linear" (sequential from 0). Fluctuations: sequential from 0.
FIELDS = [("vx", r"$v_x$", "RdBu_r", "centred"), ("vy", r"$v_y$", "RdBu_r", "centred"),
          ("speed", r"$|v|$", "viridis", "log"), ("pressure", "pressure", "magma", "linear")]
FIELD_NAMES = [f[0] for f in FIELDS]
STD_CMAP = "plasma"


def scene_value(scene, key):
    for line in scene.splitlines():
        if line.startswith(key + "="):
            try:
                return float(line[len(key) + 1:])
            except ValueError:
                return None
    return None


class PointFields:
    """One point's merged fields from /analysis/fields/<label> (lengths in cm)."""

    def __init__(self, g, scene):
        self.label = g.attrs["label"]
        self.kernel = g.attrs["kernel"]
        self.cell = float(g.attrs["cell"]) * 100
        self.kernel_width = float(g.attrs["kernel_width"]) * 100
        self.x0, self.y0 = float(g.attrs["x0"]) * 100, float(g.attrs["y0"]) * 100
        self.nx, self.ny = int(g.attrs["nx"]), int(g.attrs["ny"])
        self.realizations = int(g.attrs["realizations"])
        self.total_windows = int(g.attrs["total_windows"])
        self.wall = float(g.attrs["wall_diameter"]) * 100
        self.window = scene_value(scene, "fields.window_s")
        self.xe = self.x0 + self.cell * np.arange(self.nx + 1)  # cell edges
        self.ye = self.y0 + self.cell * np.arange(self.ny + 1)
        windows = g["windows"][:]
        self.empty = windows == 0  # cells without data hold 0: masked (drawn white)
        self.ox, self.oy = g["outline_x"][:] * 100, g["outline_y"][:] * 100
        # Cells whose centre lies beyond the wall particles' centre line (above the outlet) are
        # outside the container: a kernel wider than a cell reaches them from inside; mask them.
        if len(self.ox) >= 2:
            xc = 0.5 * (self.xe[:-1] + self.xe[1:])
            yc = 0.5 * (self.ye[:-1] + self.ye[1:])
            wall_x = np.interp(yc, self.oy, self.ox)
            outside = (yc[:, None] > 0) & (np.abs(xc)[None, :] > wall_x[:, None])
            self.empty = self.empty | outside
        self.maps = {}
        for name in FIELD_NAMES:
            for stat in ("mean", "std"):
                self.maps[stat, name] = np.ma.masked_where(self.empty, g["%s_%s" % (stat, name)][:])
        self.units = {name: g["mean_" + name].attrs["units"] for name in FIELD_NAMES}
        # The view: the grid's width and the walls (centre line +- half a wall particle); from the
        # bottom of the grid to two cells above the highest cell with data (the walls above the
        # fill show nothing).
        reach = float(np.max(np.abs(self.ox))) + 0.5 * self.wall if len(self.ox) else 0.0
        half = max(abs(self.xe[0]), abs(self.xe[-1]), reach)
        rows = np.nonzero((~self.empty).any(axis=1))[0]
        top = self.ye[rows[-1] + 1] + 2 * self.cell if len(rows) else self.ye[-1]
        self.xlim = (-half, half)
        self.ylim = (self.ye[0], min(top, max(self.ye[-1], float(np.max(self.oy, initial=0)))))

    def aspect(self):
        return (self.ylim[1] - self.ylim[0]) / (self.xlim[1] - self.xlim[0])

    def kernel_text(self):
        if self.kernel == "gaussian":
            return "Gaussian kernel, width %.3g cm" % self.kernel_width
        return "cell kernel"


def read_fields(st):
    """The points with fields, in /points order ([] when the analysis has none)."""
    if "fields" not in st.a:
        if "fields" in st.f:
            print("plots.py: the store has fields but /analysis has none: run `campaign analyze`",
                  file=sys.stderr)
        return []
    g = st.a["fields"]
    scenes = dict(zip(st.f["points/label"].asstr()[:], st.f["points/scene"].asstr()[:]))
    return [PointFields(g[label.replace("/", "_")], scenes.get(label, ""))
            for label in g["labels"].asstr()[:] if label.replace("/", "_") in g]


def colour_label(symbol, unit, stat):
    text = "%s (%s)" % (symbol, unit)
    return "std " + text if stat == "std" else text


def norm_for(values, scale, stat):
    """Colour limits from the unmasked values."""
    data = np.ma.compressed(values)
    data = data[np.isfinite(data)]
    top = float(np.max(np.abs(data))) if data.size else 1.0
    top = top if top > 0 else 1.0
    if stat == "mean" and scale == "centred":
        return matplotlib.colors.Normalize(-top, top)
    if stat == "mean" and scale == "log":
        positive = data[data > 0]
        low = float(np.min(positive)) if positive.size else top / 100
        return matplotlib.colors.LogNorm(max(low, top / 300), top)
    return matplotlib.colors.Normalize(0.0, top)


def draw_map(ax, pf, values, norm, cmap):
    cm = plt.get_cmap(cmap).copy()
    cm.set_bad("white")
    cm.set_under(cm(0.0))
    mesh = ax.pcolormesh(pf.xe, pf.ye, values, cmap=cm, norm=norm, shading="flat",
                         rasterized=True)
    ax.set_aspect("equal")
    ax.set_xlim(*pf.xlim)
    ax.set_ylim(*pf.ylim)
    ax.set_facecolor("white")
    ax.tick_params(labelsize=7)
    return mesh


def draw_walls(fig, axes_and_points):
    """Both walls (the outline and its mirror) as lines as thick as the wall particles.

    Call once the layout is final: the line width in points comes from the axes' scale."""
    fig.canvas.draw()
    for ax, pf in axes_and_points:
        if len(pf.ox) == 0:
            continue
        x0, _ = ax.transData.transform((0.0, 0.0))
        x1, _ = ax.transData.transform((1.0, 0.0))
        lw = max(0.5, abs(x1 - x0) * pf.wall * 72.0 / fig.dpi)
        for sign in (1.0, -1.0):
            ax.plot(sign * pf.ox, pf.oy, color="0.55", lw=lw, solid_capstyle="round",
                    solid_joinstyle="round", zorder=3)


def colour_bar(fig, mesh, ax, label):
    cb = fig.colorbar(mesh, ax=ax, fraction=0.08, pad=0.02, shrink=0.95)
    norm = mesh.norm
    if isinstance(norm, matplotlib.colors.LogNorm):
        # plain numbers at 1-2-5 steps (a range under a decade would show one power of ten)
        ticks = [k * 10.0 ** e for e in range(-6, 4) for k in (1, 2, 5)]
        ticks = [t for t in ticks if norm.vmin <= t <= norm.vmax]
        cb.ax.minorticks_off()
        cb.set_ticks(ticks)
        cb.set_ticklabels(["%g" % t for t in ticks])
    cb.set_label(label, fontsize=8)
    cb.ax.tick_params(labelsize=7)
    return cb


def file_part(label):
    return "".join(c if c.isalnum() or c in "._=-" else "_" for c in label)


def windows_text(pf):
    return "%d windows of %g s" % (pf.total_windows, pf.window) if pf.window else \
        "%d windows" % pf.total_windows


def plot_fields(st, out):
    """One figure per point with fields: for vx, vy, speed and pressure the mean map (top row)
    and the fluctuation map (bottom row: standard deviation over windows), the hopper's walls
    drawn, cells without data white. Returns the paths written ([] when there are no fields)."""
    written = []
    for pf in read_fields(st):
        map_w = 2.2  # inches per map; each column also holds its colour bar
        fig, axes = plt.subplots(2, 4, figsize=(4 * (map_w + 1.05),
                                                2 * (map_w * pf.aspect() + 0.55) + 0.45),
                                 squeeze=False, layout="constrained")
        placed = []
        for col, (name, symbol, cmap, scale) in enumerate(FIELDS):
            for row, stat in enumerate(("mean", "std")):
                ax = axes[row][col]
                values = pf.maps[stat, name]
                mesh = draw_map(ax, pf, values, norm_for(values, scale, stat),
                                cmap if stat == "mean" else STD_CMAP)
                colour_bar(fig, mesh, ax, colour_label(symbol, pf.units[name], stat))
                ax.set_title(("mean " if stat == "mean" else "fluctuation ") + symbol, fontsize=9)
                if row == 1:
                    ax.set_xlabel("x (cm)", fontsize=8)
                if col == 0:
                    ax.set_ylabel("y (cm)", fontsize=8)
                placed.append((ax, pf))
        fig.suptitle("%s: %d realizations, %s, %s, cells of %.3g cm; white: no data"
                     % (pf.label, pf.realizations, windows_text(pf), pf.kernel_text(), pf.cell),
                     fontsize=10)
        draw_walls(fig, placed)
        path = os.path.join(out, "fields_%s.png" % file_part(pf.label))
        fig.savefig(path, dpi=130)
        plt.close(fig)
        written.append(path)
    return written


def plot_fields_comparison(st, labels, field, path):
    """Two points side by side (e.g. the cell and the Gaussian kernel of one D and theta): one
    field's mean (top row) and fluctuation (bottom row), each row on one colour scale."""
    by_label = {pf.label: pf for pf in read_fields(st)}
    missing = [lab for lab in labels if lab not in by_label]
    if missing:
        fail("no fields for point(s) %s in /analysis/fields (points with fields: %s)" % (
            ", ".join(repr(m) for m in missing), ", ".join(repr(k) for k in by_label) or "none"))
    name, symbol, cmap, scale = FIELDS[FIELD_NAMES.index(field)]
    pfs = [by_label[lab] for lab in labels]
    # one view for both (the union of their extents)
    xlim = (min(pf.xlim[0] for pf in pfs), max(pf.xlim[1] for pf in pfs))
    ylim = (min(pf.ylim[0] for pf in pfs), max(pf.ylim[1] for pf in pfs))
    for pf in pfs:
        pf.xlim, pf.ylim = xlim, ylim
    # the settings both labels share go into the title, the others above each column
    settings = [lab.split() for lab in labels]
    common = [x for x in settings[0] if x in settings[1]]
    map_w = 2.8
    fig, axes = plt.subplots(2, 2, figsize=(2 * map_w + 1.5, 2 * (map_w * pfs[0].aspect() + 0.5)
                                            + 0.5), squeeze=False, layout="constrained")
    placed = []
    for row, stat in enumerate(("mean", "std")):
        both = np.ma.concatenate([pf.maps[stat, name].ravel() for pf in pfs])
        norm = norm_for(both, scale, stat)
        for col, pf in enumerate(pfs):
            ax = axes[row][col]
            mesh = draw_map(ax, pf, pf.maps[stat, name], norm, cmap if stat == "mean" else STD_CMAP)
            own = " ".join(x for x in settings[col]
                           if x not in common and not x.startswith("fields.kernel="))
            if row == 0:
                ax.set_title("%s\n(%s)" % (pf.kernel_text(), own) if own else pf.kernel_text(),
                             fontsize=9)
            if row == 1:
                ax.set_xlabel("x (cm)", fontsize=8)
            ax.set_ylabel("y (cm)" if col == 0 else "", fontsize=8)
            placed.append((ax, pf))
        colour_bar(fig, mesh, list(axes[row]),
                   ("mean " if stat == "mean" else "fluctuation, ")
                   + colour_label(symbol, pfs[0].units[name], stat))
    fig.suptitle("%s\n%d + %d realizations (%s + %s); white: no data" % (
        " ".join(common), pfs[0].realizations, pfs[1].realizations, windows_text(pfs[0]),
        windows_text(pfs[1])), fontsize=9)
    draw_walls(fig, placed)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(description="Figures of a campaign store (after analyze).")
    ap.add_argument("store", help="the store (STORE.h5)")
    ap.add_argument("--out", required=True, help="directory for the PNG files")
    ap.add_argument("--compare", nargs=2, metavar="LABEL",
                    help="also draw one field of two points side by side (e.g. the cell and the "
                         "Gaussian kernel of one D and theta) into OUT/fields_compare.png")
    ap.add_argument("--field", default="speed", choices=FIELD_NAMES,
                    help="the field --compare draws (default speed)")
    ap.add_argument("--compare-out", metavar="PATH",
                    help="where --compare writes its figure (default OUT/fields_compare.png)")
    args = ap.parse_args(argv)
    if not os.path.exists(args.store):
        fail("no store at '%s'" % args.store)
    try:
        st = Store(args.store)
    except OSError as e:
        fail("cannot read '%s': %s" % (args.store, e))
    os.makedirs(args.out, exist_ok=True)
    written = [plot_survival(st, args.out), plot_jam_onsets(st, args.out),
               plot_beverloo(st, args.out), plot_in_hopper(st, args.out)]
    written += plot_fields(st, args.out)
    if args.compare:
        written.append(plot_fields_comparison(
            st, args.compare, args.field,
            args.compare_out or os.path.join(args.out, "fields_compare.png")))
    for p in written:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
