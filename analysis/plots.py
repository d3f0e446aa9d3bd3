#!/usr/bin/python3
"""Figures of a campaign store for papers (`campaign plot` calls this; after `campaign analyze`,
which `campaign run` does at its end).

usage: /usr/bin/python3 analysis/plots.py STORE.h5 [--out DIR] [--format png,pdf,svg]
           [--width column|page]
           [--compare LABEL_A LABEL_B [--field vx|vy|speed|pressure] [--compare-out PATH]]

Points are grouped by the settings that vary between them other than the outlet D (the wall
angle, a material setting, ...; read from each point's scene text, so settings that differ
without being in the labels count too); legends and titles name only those settings. Writes
into DIR, in every format asked for (default png):
  survival     per group, the Kaplan-Meier survival function of every outlet overlaid (log
               scale), its jam count in the panel's key, and its exponential fit exp(-t/tau)
               (tau the censored MLE) from MIN_JAMS_FOR_FIT jams on; outlets without a curve
               (no jam) or a fit are named in the key with the reason
  jam_rate     tau (with its 95 % interval) and the jam rate 1/tau versus D per group, with the
               exponential and power-law fits of the rate where the analysis has them; an
               outlet without jams as its 95 % lower bound of tau (an open marker and an arrow)
  beverloo     mass flow rate versus D with the Beverloo fit per group, and the empty time
               versus D
  k_theta      the Beverloo k versus the wall angle (one series per other varied setting)
  in_hopper    particles in the hopper versus discharge time per group, coloured by D
  jam_onsets   every jam's onset versus elapsed discharge time per group and outlet
  avalanche    (stores with avalanche sizes) <s> versus D, and the size distribution per
               outlet (coloured by D, in the key)
  arch_sizes   (stores with arches) the fraction of arches of each size, bars per outlet
  fields_<label>  per point with fields: mean and fluctuation maps of vx, vy, speed, pressure
  fields_compare  with --compare A B: one field of two points side by side on shared scales
and prints the files it wrote. Sizes: --width page (7 in, two journal columns; default) or
column (3.4 in); text 7-8 pt at that size. PDF and PostScript embed TrueType (Type 42) fonts;
a figure is byte-identical from run to run (no dates in its metadata). Needs Debian's
python3-h5py, -numpy, -pandas, -matplotlib (and -xarray for fields). Exit codes: 0 figures
written, 2 bad arguments or a store without /analysis, 3 no realization to draw (none stored, or
every one failed), 1 other errors.
"""
import argparse
import math
import os
import sys

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

if __package__:  # imported from the installed package (pip install ./analysis)
    from .hopper_store import open_store, setting_text
else:  # run as a script: campaign runs analysis/plots.py by its path
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from hopper_store import open_store, setting_text  # noqa: E402

G = 9.80665  # m/s^2, as hopper::core::standard_gravity
WIDTHS = {"page": 7.0, "column": 3.4}  # inches: two journal columns, one
FORMATS = ("png", "pdf", "svg")
STYLE = {"font.size": 8, "axes.titlesize": 8, "axes.labelsize": 8, "xtick.labelsize": 7,
         "ytick.labelsize": 7, "legend.fontsize": 7, "figure.titlesize": 9,
         "legend.frameon": False, "axes.spines.top": False, "axes.spines.right": False,
         "savefig.dpi": 200, "lines.linewidth": 1.2, "lines.markersize": 4,
         # Journals take TrueType (Type 42) fonts in PDF and PostScript, not matplotlib's
         # default Type 3; SVG's ids from a fixed salt, so that a figure is byte-identical
         # from run to run (with the dates left out: save()).
         "pdf.fonttype": 42, "ps.fonttype": 42, "svg.hashsalt": "hopper"}
# Metadata that would change from run to run: none (no creation date in PDF, no date in SVG).
METADATA = {"pdf": {"CreationDate": None, "Producer": None},
            "svg": {"Date": None}, "png": {"Software": None}}
# A survival curve's exponential fit is drawn from this many jams on (below it tau is a guess:
# the panel says which outlets have no fit and why).
MIN_JAMS_FOR_FIT = 3


def fail(msg, code=2):
    print("plots.py: error: " + msg, file=sys.stderr)
    sys.exit(code)


# ----- the study: points grouped by their varied settings -------------------------------------

class Study:
    """What every figure needs: the points grouped by the settings that vary other than D, one
    colour per outlet D (the same in every figure) and per group, and the analysis rows."""

    def __init__(self, store):
        self.s = store
        self.points = store.points
        self.groups = store.groups()  # {group text: [points by D]}
        self.a = store.analysis
        self.Ds = sorted(set(float(d) for d in self.points["D_cm"]))
        cmap = plt.get_cmap("viridis")
        n = len(self.Ds)
        self.D_colour = {d: cmap(0.85 * k / max(1, n - 1)) for k, d in enumerate(self.Ds)}
        self.group_colour = {g: "C%d" % (k % 10) for k, g in enumerate(self.groups)}
        self.group_marker = {g: "osD^v<>ph*"[k % 10] for k, g in enumerate(self.groups)}
        # /analysis fits are per the analysis's own group (from the labels): the row of each
        # of our groups is that of its first point
        self.analysis_group = {g: str(self.a.at[rows[0], "group"]) if rows[0] in self.a.index
                               else "" for g, rows in self.groups.items()}

    def get(self, point, key):
        """An /analysis/points value, or None when missing."""
        if point not in self.a.index or key not in self.a:
            return None
        v = self.a.at[point, key]
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return None
        return v

    def fit_row(self, table, group):
        df = getattr(self.s, table)
        rows = df.index[df["group"] == self.analysis_group[group]]
        return df.loc[rows[0]] if len(rows) else None

    def title(self, group):
        return group or self.s.name


def D_text(d):
    return "D = %g cm" % d


def layout(study, n_panels, width, panel_h=2.0, max_cols=2, legend_rows=0):
    """A figure of n panels at the requested width and, below them, a strip for a shared legend
    of `legend_rows` rows (an axes without frame, so that the constrained layout makes room)."""
    cols = 1 if width < 5 else max(1, min(max_cols, n_panels))
    rows = (n_panels + cols - 1) // cols
    strip = 0.22 * legend_rows + 0.05 if legend_rows else 0.0
    fig = plt.figure(figsize=(width, rows * panel_h + strip + 0.2), layout="constrained")
    gs = fig.add_gridspec(rows + (1 if strip else 0), cols,
                          height_ratios=[panel_h] * rows + ([strip] if strip else []))
    axes = [fig.add_subplot(gs[k // cols, k % cols]) for k in range(n_panels)]
    if strip:
        fig.legend_ax = fig.add_subplot(gs[rows, :])
        fig.legend_ax.axis("off")
    return fig, axes


def legend_columns(width, labels):
    """Columns of a shared legend whose entries fit the width (7 pt text is about 0.055 in a
    character; the handle and the gap take about 0.45 in)."""
    longest = max((len(str(t)) for t in labels), default=10)
    return max(1, int((width - 0.1) / (0.055 * longest + 0.45)))


def shared_legend(fig, handles, labels, width):
    """One legend for the whole figure, in the strip below the panels."""
    if not handles or not hasattr(fig, "legend_ax"):
        return
    fig.legend_ax.legend(handles, labels, loc="center",
                         ncol=min(len(handles), legend_columns(width, labels)),
                         handlelength=1.6, columnspacing=1.0, borderaxespad=0.0)


def legend_rows(labels, width):
    """Rows the shared legend of these entries takes."""
    n = len(labels)
    return (n + legend_columns(width, labels) - 1) // legend_columns(width, labels)


def D_legend(study, Ds, extra=()):
    hs = [plt.Line2D([], [], color=study.D_colour[d], marker="o", ms=3, lw=1) for d in Ds]
    return hs + [e[0] for e in extra], [D_text(d) for d in Ds] + [e[1] for e in extra]


def save(fig, out, name, formats):
    paths = []
    for fmt in formats:
        path = os.path.join(out, "%s.%s" % (name, fmt))
        fig.savefig(path, metadata=METADATA.get(fmt))
        paths.append(path)
    plt.close(fig)
    return paths


# ----- survival --------------------------------------------------------------------------------

def jam_text(n):
    return "%d jam%s" % (n, "" if n == 1 else "s")


def plot_survival(st, width):
    """Per group, the Kaplan-Meier curve of every outlet with its jam count (in the panel's own
    key); the exponential fit only from MIN_JAMS_FOR_FIT jams on, and the outlets without a curve
    or a fit named with the reason."""
    fig, axes = layout(st, len(st.groups), width, panel_h=2.1, legend_rows=1)
    km = st.s.km
    surv = st.s.survival
    for ax, (g, rows) in zip(axes, st.groups.items()):
        lowest = 1.0
        handles, labels = [], []
        for i in rows:
            d = float(st.points.at[i, "D_cm"])
            c = st.D_colour[d]
            k = km[km["point"] == i]
            mine = surv[surv["point"] == i]
            longest = float(mine["duration"].max()) if len(mine) else 0.0
            jams = int(mine["event"].sum()) if len(mine) else 0
            drawn = False
            if len(k) and jams > 0:
                ts = np.concatenate([[0.0], k["time"], [max(longest, k["time"].iloc[-1])]])
                ss = np.concatenate([[1.0], k["survival"], [k["survival"].iloc[-1]]])
                ok = ss > 0
                ax.step(ts[ok], ss[ok], where="post", color=c)
                if ok.any():
                    lowest = min(lowest, float(ss[ok].min()))
                drawn = True
            tau = st.get(i, "tau_mle")
            fitted = tau is not None and longest > 0 and jams >= MIN_JAMS_FOR_FIT
            if fitted:
                tt = np.linspace(0, longest, 100)
                ax.plot(tt, np.exp(-tt / tau), "--", color=c, lw=0.9)
            if drawn:
                handles.append(plt.Line2D([], [], color=c, lw=1.2))
                labels.append("%g cm: %s%s" % (d, jam_text(jams), "" if fitted else ", no fit"))
            else:  # no jam: no curve to draw, but the outlet is named
                handles.append(plt.Line2D([], [], color=c, lw=0))
                labels.append("%g cm: %s, no curve" % (d, jam_text(jams)))
        ax.set_yscale("log")
        ax.set_ylim(max(1e-3, lowest * 0.5), 1.2)
        ax.set_xlim(left=0)
        ax.set_xlabel("t (s of discharge)")
        ax.set_ylabel("S(t)")
        if g:
            ax.set_title(g)
        ax.legend(handles, labels, loc="lower left", fontsize=6.5, handlelength=1.2,
                  borderaxespad=0.3, labelspacing=0.25, title="D: jams", title_fontsize=6.5)
    shared_legend(fig, [plt.Line2D([], [], color="0.3", lw=1.2),
                        plt.Line2D([], [], color="0.3", ls="--", lw=0.9)],
                  ["Kaplan-Meier", r"exp($-t/\tau$), from %d jams on" % MIN_JAMS_FOR_FIT], width)
    return fig


# ----- tau and the jam rate versus D -----------------------------------------------------------

def plot_jam_rate(st, width):
    extra = 3
    fig, (ax_t, ax_r) = layout(st, 2, width, panel_h=2.3,
                               legend_rows=legend_rows(list(st.groups) + ["no jams: tau > 95 % bound"] * extra,
                                                       width))
    any_fit = {"exp": False, "pow": False}
    bound_handle = None  # the first bound drawn: the key shows it as drawn
    handles, labels = [], []
    lowest_rate = []  # the fits' curves must not stretch the rate axis beyond the data
    for g, rows in st.groups.items():
        c, m = st.group_colour[g], st.group_marker[g]
        D, tau, lo, hi, bound_D, bound = [], [], [], [], [], []
        for i in rows:
            t = st.get(i, "tau_mle")
            if t is not None:
                D.append(float(st.points.at[i, "D_cm"]))
                tau.append(t)
                lo.append(st.get(i, "tau_ci95_lo") or t)
                hi.append(st.get(i, "tau_ci95_hi") or t)
            elif st.get(i, "tau_lower_bound95") is not None:
                bound_D.append(float(st.points.at[i, "D_cm"]))
                bound.append(st.get(i, "tau_lower_bound95"))
        D, tau, lo, hi = map(np.array, (D, tau, lo, hi))
        if len(D):
            ax_t.errorbar(D, tau, yerr=[tau - lo, hi - tau], fmt=m, color=c, capsize=2, ms=3)
            ax_r.errorbar(D, 1 / tau, yerr=[1 / tau - 1 / hi, 1 / lo - 1 / tau], fmt=m, color=c,
                          capsize=2, ms=3)
            lowest_rate.append(float(np.min(1 / hi)))
        if bound:  # no jam at these outlets: only a bound, drawn as one (open, with an arrow)
            bound = np.array(bound)
            drawn = ax_t.errorbar(bound_D, bound, yerr=[np.zeros(len(bound)), bound],
                                  lolims=True, fmt=m, mfc="none", color=c, capsize=2, ms=3)
            bound_handle = bound_handle or drawn
            ax_r.errorbar(bound_D, 1 / bound, yerr=[0.5 / bound, np.zeros(len(bound))],
                          uplims=True, fmt=m, mfc="none", color=c, capsize=2, ms=3)
            lowest_rate.append(float(np.min(0.5 / bound)))
        handles.append(plt.Line2D([], [], color=c, marker=m, ls="none", ms=3))
        labels.append(g or "all points")
        fit = st.fit_row("jam_rate", g) if st.s.has_analysis else None
        Dall = np.array([float(st.points.at[i, "D_cm"]) for i in rows])
        if fit is None or not len(Dall):
            continue
        DD = np.linspace(Dall.min(), Dall.max(), 100)
        if not _missing(fit.get("exp_B")):
            rate = np.exp(fit["exp_ln_A"] - fit["exp_B"] * DD / 100)
            ax_r.plot(DD, rate, "-", color=c, lw=0.9)
            any_fit["exp"] = True
        if not _missing(fit.get("pow_gamma")) and not _missing(fit.get("pow_Dc")):
            DDp = DD[DD / 100 < fit["pow_Dc"]]
            rate = np.exp(fit["pow_ln_A"] + fit["pow_gamma"] * np.log(fit["pow_Dc"] - DDp / 100))
            ax_r.plot(DDp, rate, ":", color=c, lw=1.1)
            any_fit["pow"] = True
    ax_t.set_yscale("log")
    ax_r.set_yscale("log")
    if lowest_rate:
        ax_r.set_ylim(bottom=min(lowest_rate) / 3)
    ax_t.set_xlabel("D (cm)")
    ax_r.set_xlabel("D (cm)")
    ax_t.set_ylabel(r"mean survival time $\tau$ (s)")
    ax_r.set_ylabel(r"jam rate $1/\tau$ (1/s)")
    if any_fit["exp"]:
        handles.append(plt.Line2D([], [], color="0.3", ls="-", lw=0.9))
        labels.append("exponential fit")
    if any_fit["pow"]:
        handles.append(plt.Line2D([], [], color="0.3", ls=":", lw=1.1))
        labels.append("power-law fit")
    if bound_handle is not None:  # an open marker with the arrow, as drawn
        handles.append(bound_handle)
        labels.append(r"no jams: $\tau$ > 95 % bound")
    shared_legend(fig, handles, labels, width)
    return fig


def _missing(v):
    return v is None or (isinstance(v, float) and math.isnan(v))


# ----- flow rate (Beverloo) and empty time versus D -------------------------------------------

def plot_beverloo(st, width):
    """The mass flow rate against D with each group's Beverloo fit (solid lines), and the empty
    time (points joined by dotted lines, a guide for the eye: no fit). "Beverloo fit" is in the
    key only where a fit is drawn (a group needs 3 outlets)."""
    fits = {g: st.fit_row("beverloo", g) if st.s.has_analysis else None for g in st.groups}
    fits = {g: f for g, f in fits.items() if f is not None and not _missing(f.get("C"))}
    fig, (ax_w, ax_e) = layout(st, 2, width, panel_h=2.3,
                               legend_rows=legend_rows(list(st.groups)
                                                       + (["Beverloo fit"] if fits else []), width))
    handles, labels = [], []
    real = st.s.realizations
    for g, rows in st.groups.items():
        c, m = st.group_colour[g], st.group_marker[g]
        D = np.array([float(st.points.at[i, "D_cm"]) for i in rows])
        W = np.array([st.get(i, "discharge_rate_kg_s") or np.nan for i in rows])
        We = np.array([st.get(i, "discharge_rate_kg_s_err") or 0.0 for i in rows])
        E = np.array([st.get(i, "empty_time_mean") or np.nan for i in rows])
        Ee = np.array([st.get(i, "empty_time_err") or 0.0 for i in rows])
        for i in rows:  # each realization, faint
            r = real[(real["point"] == i) & (real["status"] != "failed")]
            ax_w.plot(np.full(len(r), float(st.points.at[i, "D_cm"])),
                      r["discharge_rate_mass"] * 1e3, ".", color=c, alpha=0.3, ms=2)
        ok = np.isfinite(W)
        ax_w.errorbar(D[ok], W[ok] * 1e3, yerr=We[ok] * 1e3, fmt=m, color=c, capsize=2, ms=3)
        ok = np.isfinite(E)
        ax_e.errorbar(D[ok], E[ok], yerr=Ee[ok], fmt=m + ":", color=c, capsize=2, ms=3, lw=0.8)
        handles.append(plt.Line2D([], [], color=c, marker=m, ls="none", ms=3))
        labels.append(g or "all points")
        fit = fits.get(g)
        if fit is not None and len(D):
            C, k, rho_b, d = fit["C"], fit["k"], fit["rho_b"], fit["d"]
            lo = max(k * d * 100 * 1.001, 0.0)
            DD = np.linspace(lo, D.max() * 1.05, 200)
            WW = C * rho_b * np.sqrt(G) * np.clip(DD / 100 - k * d, 0, None) ** 1.5
            ax_w.plot(DD, WW * 1e3, "-", color=c, lw=0.9)
    ax_w.set_xlabel("D (cm)")
    ax_w.set_ylabel("mass flow rate W (g/s)")
    ax_w.set_xlim(left=0)
    ax_w.set_ylim(bottom=0)
    ax_e.set_xlabel("D (cm)")
    ax_e.set_ylabel("empty time (s)")
    ax_e.set_ylim(bottom=0)
    if fits:
        handles.append(plt.Line2D([], [], color="0.3", lw=0.9))
        labels.append("Beverloo fit")
    shared_legend(fig, handles, labels, width)
    return fig


# ----- k versus theta --------------------------------------------------------------------------

def plot_k_theta(st, width):
    """k of each group's Beverloo fit against its wall angle; one series per value of the other
    varied settings."""
    w = min(width, WIDTHS["column"])
    others = [c for c in st.s.group_settings if c != "hopper.theta_rad"]
    series = {}
    missing = []
    for g, rows in st.groups.items():
        p = st.points.loc[rows[0]]
        key = ", ".join(setting_text(c, p[c]) for c in others)
        fit = st.fit_row("beverloo", g) if st.s.has_analysis else None
        theta = float(p["theta_deg"])
        if fit is None or _missing(fit.get("k")):
            missing.append(theta)
            continue
        series.setdefault(key, []).append((theta, fit["k"], fit.get("k_err") or 0.0))
    n_legend = len(series) if len(series) > 1 else 0
    fig, (ax,) = layout(st, 1, w, panel_h=2.3, legend_rows=legend_rows(list(series) if n_legend else [], w))
    handles, labels = [], []
    for n, (key, pts) in enumerate(series.items()):
        pts.sort()
        th, k, ke = map(np.array, zip(*pts))
        h = ax.errorbar(th, k, yerr=ke, fmt="osD^v"[n % 5] + "-", color="C%d" % n, capsize=2,
                        ms=3, lw=0.8)
        handles.append(h)
        labels.append(key)
    if missing:
        ths = sorted(set(missing))
        ax.text(0.5, 0.04 if series else 0.5,
                "no fit at %s = %s\u00b0 (< 3 outlets)" % ("\u03b8", ", ".join("%g" % t for t in ths))
                if len(ths) <= 4 else "no fit for %d angles (< 3 outlets)" % len(ths),
                transform=ax.transAxes, ha="center", va="bottom" if series else "center",
                fontsize=7, color="0.35")
    # the angles' range, at least 20 degrees wide (one angle: 0-1 deg was matplotlib's default)
    angles = [t for pts in series.values() for t, _, _ in pts] + missing
    if angles:
        lo, hi = min(angles), max(angles)
        pad = max(5.0, (20.0 - (hi - lo)) / 2)
        ax.set_xlim(max(0.0, lo - pad), min(90.0, hi + pad))
    ax.set_xlabel(r"wall angle $\theta$ (deg)")
    ax.set_ylabel("Beverloo k")
    if n_legend:
        shared_legend(fig, handles, labels, w)
    return fig


# ----- particles in the hopper and jam onsets --------------------------------------------------

def plot_in_hopper(st, width):
    fig, axes = layout(st, len(st.groups), width, panel_h=1.9,
                       legend_rows=legend_rows([D_text(d) for d in st.Ds], width))
    curves = st.s.curves
    used = set()
    for ax, (g, rows) in zip(axes, st.groups.items()):
        for i in rows:
            d = float(st.points.at[i, "D_cm"])
            cu = curves[curves["point"] == i]
            for _, one in cu.groupby("row"):
                ax.plot(one["time"], one["in_hopper"], color=st.D_colour[d], lw=0.7, alpha=0.8)
                used.add(d)
        ax.set_xlabel("t (s of discharge)")
        ax.set_ylabel("particles in hopper")
        ax.set_xlim(left=0)
        ax.set_ylim(bottom=0)
        if g:
            ax.set_title(g)
    shared_legend(fig, *D_legend(st, [d for d in st.Ds if d in used]), width)
    return fig


def plot_jam_onsets(st, width):
    fig, axes = layout(st, len(st.groups), width, panel_h=1.9,
                       legend_rows=legend_rows([D_text(d) for d in st.Ds], width))
    jams, ev = st.s.jams, st.s.events
    real = st.s.realizations
    ends = ev.groupby("row")["time"].max() if len(ev) else {}
    used = set()
    for ax, (g, rows) in zip(axes, st.groups.items()):
        for y, i in enumerate(rows):
            d = float(st.points.at[i, "D_cm"])
            rs = list(real.index[(real["point"] == i) & (real["status"] != "failed")])
            for j, row in enumerate(rs):
                yy = y + (j + 0.5) / max(1, len(rs)) * 0.8 - 0.4
                end = float(ends.get(row, 0.0)) if len(ev) else 0.0
                ax.plot([0, end], [yy, yy], color="0.85", lw=0.6, zorder=1)
                on = jams.loc[jams["row"] == row, "onset"]
                ax.plot(on, np.full(len(on), yy), "|", color=st.D_colour[d], ms=4, mew=1.0,
                        zorder=2)
                used.add(d)
        ax.set_yticks(range(len(rows)))
        ax.set_yticklabels(["%g" % float(st.points.at[i, "D_cm"]) for i in rows])
        ax.set_ylim(-0.6, len(rows) - 0.4)
        ax.set_ylabel("D (cm)")
        ax.set_xlabel("jam onset (s of discharge)")
        ax.set_xlim(left=0)
        if g:
            ax.set_title(g)
    shared_legend(fig, *D_legend(st, [d for d in st.Ds if d in used]), width)
    return fig


# ----- coarse-grained fields -------------------------------------------------------------------

# name, symbol, colour map of the mean, its scale: "centred" (diverging, symmetric about 0),
# "log" (the outlet jet is ~10x faster than the bulk) or "linear" (from 0).
FIELDS = [("vx", r"$v_x$", "RdBu_r", "centred"), ("vy", r"$v_y$", "RdBu_r", "centred"),
          ("speed", r"$|v|$", "viridis", "log"), ("pressure", "p", "magma", "linear")]
FIELD_NAMES = [f[0] for f in FIELDS]
STD_CMAP = "plasma"
UNIT_TEXT = {"m/s": "m/s", "1": "mg"}


class PointFields:
    """One point's merged fields (an xarray Dataset of hopper_store), lengths in cm."""

    def __init__(self, label, ds):
        self.label = label
        a = ds.attrs
        self.kernel = str(a.get("kernel", "cell"))
        self.cell = float(a["cell"]) * 100
        self.kernel_width = float(a.get("kernel_width", 0.0)) * 100
        x0, y0 = float(a["x0"]) * 100, float(a["y0"]) * 100
        nx, ny = ds.sizes["x"], ds.sizes["y"]
        self.realizations = int(a.get("realizations", 0))
        self.xe = x0 + self.cell * np.arange(nx + 1)
        self.ye = y0 + self.cell * np.arange(ny + 1)
        self.wall = float(a.get("wall_diameter", 0.0)) * 100
        self.ox, self.oy = ds["outline_x"].values * 100, ds["outline_y"].values * 100
        empty = ds["windows"].values == 0
        if len(self.ox) >= 2:  # cells beyond the walls (a wide kernel reaches them): masked
            xc = 0.5 * (self.xe[:-1] + self.xe[1:])
            yc = 0.5 * (self.ye[:-1] + self.ye[1:])
            wall_x = np.interp(yc, self.oy, self.ox)
            empty = empty | ((yc[:, None] > 0) & (np.abs(xc)[None, :] > wall_x[:, None]))
        self.maps, self.units = {}, {}
        for name in FIELD_NAMES:
            for stat in ("mean", "std"):
                v = ds["%s_%s" % (stat, name)].values
                self.maps[stat, name] = np.ma.masked_where(empty | ~np.isfinite(v), v)
            self.units[name] = str(ds["mean_" + name].attrs.get("units", ""))
        reach = float(np.max(np.abs(self.ox))) + 0.5 * self.wall if len(self.ox) else 0.0
        half = max(abs(self.xe[0]), abs(self.xe[-1]), reach)
        rows = np.nonzero((~empty).any(axis=1))[0]
        top = self.ye[rows[-1] + 1] + 2 * self.cell if len(rows) else self.ye[-1]
        self.xlim = (-half, half)
        self.ylim = (self.ye[0], min(top, max(self.ye[-1], float(np.max(self.oy, initial=0)))))

    def aspect(self):
        return (self.ylim[1] - self.ylim[0]) / (self.xlim[1] - self.xlim[0])

    def kernel_text(self):
        if self.kernel == "gaussian":
            return "Gaussian kernel, w = %.2g cm" % self.kernel_width
        return "cell kernel"


def norm_for(values, scale, stat):
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
    for side in ("top", "right"):
        ax.spines[side].set_visible(True)
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(3))
    ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
    return mesh


def draw_walls(fig, axes_and_points):
    """Both walls as lines as thick as the wall particles (once the layout is final)."""
    fig.canvas.draw()
    for ax, pf in axes_and_points:
        if len(pf.ox) == 0:
            continue
        x0, _ = ax.transData.transform((0.0, 0.0))
        x1, _ = ax.transData.transform((1.0, 0.0))
        lw = max(0.5, abs(x1 - x0) * pf.wall * 72.0 / fig.dpi)
        for sign in (1.0, -1.0):
            ax.plot(sign * pf.ox, pf.oy, color="0.55", lw=lw, solid_capstyle="round", zorder=3)


def colour_bar(fig, mesh, ax, label):
    cb = fig.colorbar(mesh, ax=ax, fraction=0.08, pad=0.03, shrink=0.9)
    norm = mesh.norm
    if isinstance(norm, matplotlib.colors.LogNorm):
        ticks = [k * 10.0 ** e for e in range(-6, 4) for k in (1, 2, 5)]
        ticks = [t for t in ticks if norm.vmin <= t <= norm.vmax]
        cb.ax.minorticks_off()
        cb.set_ticks(ticks)
        cb.set_ticklabels(["%g" % t for t in ticks])
    else:
        cb.ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
    cb.set_label(label, fontsize=7)
    cb.ax.tick_params(labelsize=6.5)
    return cb


def file_part(label):
    return "".join(c if c.isalnum() or c in "._=-" else "_" for c in label)


def point_title(st, label):
    i = int(np.nonzero(st.points["label"].to_numpy() == label)[0][0])
    parts = [setting_text(c, st.points.at[i, c]) for c in st.s.varied]
    return ", ".join(parts)


def plot_field_point(st, pf, width):
    cols = 4 if width > 5 else 2
    rows = 2 * (4 // cols)
    map_w = width / cols - 0.75
    fig, axes = plt.subplots(rows, cols, figsize=(width, rows * (map_w * pf.aspect() + 0.45)
                                                  + 0.35), squeeze=False, layout="constrained")
    placed = []
    for k, (name, symbol, cmap, scale) in enumerate(FIELDS):
        for s, stat in enumerate(("mean", "std")):
            r = 2 * (k // cols) + s
            ax = axes[r][k % cols]
            values = pf.maps[stat, name]
            mesh = draw_map(ax, pf, values, norm_for(values, scale, stat),
                            cmap if stat == "mean" else STD_CMAP)
            unit = UNIT_TEXT.get(pf.units[name], pf.units[name])
            colour_bar(fig, mesh, ax, "%s%s (%s)" % ("" if stat == "mean" else "\u03c3 ", symbol,
                                                    unit))
            ax.tick_params(labelsize=6.5)
            ax.set_xlabel("x (cm)", fontsize=7)
            ax.set_ylabel("y (cm)", fontsize=7)
            placed.append((ax, pf))
    fig.suptitle("%s; %d realizations, %s" % (point_title(st, pf.label) or pf.label,
                                              pf.realizations, pf.kernel_text()))
    draw_walls(fig, placed)
    return fig


def plot_fields_comparison(st, fields, labels, field, width):
    missing = [lab for lab in labels if lab not in fields]
    if missing:
        fail("no fields for point(s) %s (points with fields: %s)" % (
            ", ".join(repr(m) for m in missing), ", ".join(repr(k) for k in fields) or "none"))
    name, symbol, cmap, scale = FIELDS[FIELD_NAMES.index(field)]
    pfs = [PointFields(lab, fields[lab]) for lab in labels]
    xlim = (min(pf.xlim[0] for pf in pfs), max(pf.xlim[1] for pf in pfs))
    ylim = (min(pf.ylim[0] for pf in pfs), max(pf.ylim[1] for pf in pfs))
    for pf in pfs:
        pf.xlim, pf.ylim = xlim, ylim
    w = min(width, 5.0)
    map_w = w / 2 - 0.8
    fig, axes = plt.subplots(2, 2, figsize=(w, 2 * (map_w * pfs[0].aspect() + 0.45) + 0.4),
                             squeeze=False, layout="constrained")
    placed = []
    for row, stat in enumerate(("mean", "std")):
        both = np.ma.concatenate([pf.maps[stat, name].ravel() for pf in pfs])
        norm = norm_for(both, scale, stat)
        for col, pf in enumerate(pfs):
            ax = axes[row][col]
            mesh = draw_map(ax, pf, pf.maps[stat, name], norm, cmap if stat == "mean" else STD_CMAP)
            if row == 0:
                ax.set_title(pf.kernel_text() if pfs[0].kernel != pfs[1].kernel
                             else point_title(st, pf.label))
            ax.set_xlabel("x (cm)", fontsize=7)
            ax.set_ylabel("y (cm)" if col == 0 else "", fontsize=7)
            ax.tick_params(labelsize=6.5)
            placed.append((ax, pf))
        unit = UNIT_TEXT.get(pfs[0].units[name], pfs[0].units[name])
        colour_bar(fig, mesh, list(axes[row]), "%s%s (%s)" % (
            "" if stat == "mean" else "\u03c3 ", symbol, unit))
    draw_walls(fig, placed)
    return fig


# ----- avalanche sizes and arches (issue 13) ----------------------------------------------------

def has_avalanches(store):
    try:
        surv = store.survival
    except Exception:  # a store without the ragged data (synthetic stores)
        return False
    return "avalanche_size" in surv and bool(surv["avalanche_size"].notna().any())


def plot_avalanche(st, width):
    fig, (ax_s, ax_d) = layout(st, 2, width, panel_h=2.3,
                               legend_rows=legend_rows(list(st.groups) + ["exponential fit",
                                                                          "power-law fit"]
                                                       + [D_text(d) for d in st.Ds]
                                                       + [r"exp(-s/<s>)"], width))
    surv = st.s.survival
    in_ccdf = []  # outlets drawn in the distribution panel, in their colours
    handles, labels = [], []
    fits = {"exp": False, "pow": False}
    for g, rows in st.groups.items():
        c, m = st.group_colour[g], st.group_marker[g]
        D, s, lo, hi = [], [], [], []
        for i in rows:
            v = st.get(i, "mean_avalanche")
            if v is None:
                continue
            D.append(float(st.points.at[i, "D_cm"]))
            s.append(v)
            lo.append(st.get(i, "mean_avalanche_ci95_lo") or v)
            hi.append(st.get(i, "mean_avalanche_ci95_hi") or v)
        D, s, lo, hi = map(np.array, (D, s, lo, hi))
        if len(D):
            ax_s.errorbar(D, s, yerr=[s - lo, hi - s], fmt=m, color=c, capsize=2, ms=3)
        handles.append(plt.Line2D([], [], color=c, marker=m, ls="none", ms=3))
        labels.append(g or "all points")
        fit = st.fit_row("avalanche", g) if st.s.has_analysis else None
        if fit is not None and len(D):
            DD = np.linspace(D.min(), D.max(), 100)
            if not _missing(fit.get("exp_B")):
                ax_s.plot(DD, np.exp(fit["exp_ln_s0"] + fit["exp_B"] * DD / 100), "-",
                          color=c, lw=0.9)
                fits["exp"] = True
            if not _missing(fit.get("pow_gamma")) and not _missing(fit.get("pow_Dc")):
                DDp = DD[DD / 100 < fit["pow_Dc"]]
                ax_s.plot(DDp, np.exp(fit["pow_ln_s0"]
                                      - fit["pow_gamma"] * np.log(fit["pow_Dc"] - DDp / 100)),
                          ":", color=c, lw=1.1)
                fits["pow"] = True
        # Distribution of s: the fraction of completed avalanches larger than s (descriptive;
        # the censored last avalanche of each realization is left out), and exp(-s/<s>).
        for i in rows:
            sz = np.sort(surv.loc[(surv["point"] == i) & (surv["event"] == 1),
                                  "avalanche_size"].dropna().to_numpy())
            if not len(sz):
                continue
            d = float(st.points.at[i, "D_cm"])
            ccdf = 1.0 - np.arange(len(sz)) / len(sz)
            ax_d.step(sz, ccdf, where="post", color=st.D_colour[d], lw=0.9)
            if d not in in_ccdf:
                in_ccdf.append(d)
            mean = st.get(i, "mean_avalanche")
            if mean:
                ss = np.linspace(0, sz.max(), 50)
                ax_d.plot(ss, np.exp(-ss / mean), "--", color=st.D_colour[d], lw=0.7)
    ax_s.set_yscale("log")
    ax_d.set_yscale("log")
    ax_s.set_xlabel("D (cm)")
    ax_s.set_ylabel(r"mean avalanche size $\langle s\rangle$")
    ax_d.set_xlabel("avalanche size s (grains)")
    ax_d.set_ylabel("P(size > s)")
    if fits["exp"]:
        handles.append(plt.Line2D([], [], color="0.3", ls="-", lw=0.9))
        labels.append("exponential fit")
    if fits["pow"]:
        handles.append(plt.Line2D([], [], color="0.3", ls=":", lw=1.1))
        labels.append("power-law fit")
    # the distribution panel's colours are the outlets'
    d_handles, d_labels = D_legend(st, sorted(in_ccdf))
    handles += d_handles
    labels += d_labels
    if in_ccdf:
        handles.append(plt.Line2D([], [], color="0.3", ls="--", lw=0.7))
        labels.append(r"exp($-s/\langle s\rangle$)")
    shared_legend(fig, handles, labels, width)
    return fig


def plot_arch_sizes(st, width):
    arches = st.s.arches
    fig, axes = layout(st, len(st.groups), width, panel_h=2.1,
                       legend_rows=legend_rows([D_text(d) for d in st.Ds], width))
    used = set()
    for ax, (g, rows) in zip(axes, st.groups.items()):
        # one bar per outlet and size, side by side: a size no arch had is an empty place, not
        # a line drawn across it
        drawn = [i for i in rows if ((arches["point"] == i) & (arches["disks"] > 0)).any()]
        w = 0.8 / max(1, len(drawn))
        for k, i in enumerate(drawn):
            a = arches[(arches["point"] == i) & (arches["disks"] > 0)]
            d = float(st.points.at[i, "D_cm"])
            counts = a["disks"].value_counts().sort_index()
            ax.bar(counts.index.to_numpy() + (k - (len(drawn) - 1) / 2) * w,
                   counts.to_numpy() / len(a), width=w, color=st.D_colour[d], lw=0)
            used.add(d)
        ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
        ax.set_xlabel("disks in the arch")
        ax.set_ylabel("fraction of arches")
        if g:
            ax.set_title(g)
    handles, labels = D_legend(st, [d for d in st.Ds if d in used])
    shared_legend(fig, handles, labels, width)
    return fig


# ----- all figures -----------------------------------------------------------------------------

FIGURES = [("survival", plot_survival), ("jam_rate", plot_jam_rate),
           ("beverloo", plot_beverloo), ("k_theta", plot_k_theta),
           ("in_hopper", plot_in_hopper), ("jam_onsets", plot_jam_onsets)]


def nothing_to_draw(store):
    """Why a store has nothing to draw (no realization, or every one failed), or None."""
    real = store.realizations
    if not len(real):
        return "'%s' holds no realization yet: nothing to draw" % store.path
    failed = real["status"] == "failed"
    if failed.all():
        reasons = real["message"] if "message" in real else []
        first = next((str(m) for m in reasons if str(m)), "")
        return ("every realization of '%s' failed (%d of %d%s): nothing to draw; "
                "`campaign status %s` lists the failures"
                % (store.path, int(failed.sum()), len(real),
                   "; the first: %s" % first if first else "", store.path))
    return None


def figures(store, width=WIDTHS["page"]):
    """Every figure of a store as (name, matplotlib Figure), drawn but not saved (the tests check
    their text layout)."""
    with plt.rc_context(STYLE):
        st = Study(store)
        for name, draw in FIGURES:
            yield name, draw(st, width)
        if has_avalanches(store):
            yield "avalanche", plot_avalanche(st, width)
            yield "arch_sizes", plot_arch_sizes(st, width)
        fields = store.fields()
        for label, ds in fields.items():
            yield "fields_" + file_part(label), plot_field_point(st, PointFields(label, ds), width)


def default_out(store):
    """`campaign plot`'s default directory: the store's path without .h5, plus _plots."""
    root, ext = os.path.splitext(store)
    return (root if ext else store) + "_plots"


def main(argv=None):
    ap = argparse.ArgumentParser(description="Figures of a campaign store (after analyze).")
    ap.add_argument("store", help="the store (STORE.h5)")
    ap.add_argument("--out", help="directory for the figures (default: STORE without .h5, plus "
                    "_plots, as `campaign plot`)")
    ap.add_argument("--format", default="png",
                    help="comma-separated: png, pdf, svg (default png)")
    ap.add_argument("--width", default="page", choices=sorted(WIDTHS),
                    help="page (7 in, default) or column (3.4 in)")
    ap.add_argument("--compare", nargs=2, metavar="LABEL",
                    help="also draw one field of two points side by side into "
                         "OUT/fields_compare.FORMAT")
    ap.add_argument("--field", default="speed", choices=FIELD_NAMES,
                    help="the field --compare draws (default speed)")
    ap.add_argument("--compare-out", metavar="PATH",
                    help="where --compare writes its figure (default OUT/fields_compare.png)")
    args = ap.parse_args(argv)
    formats = args.format.split(",")
    bad = [f for f in formats if f not in FORMATS]
    if bad:
        fail("unknown format '%s' (allowed: %s)" % (bad[0], ", ".join(FORMATS)))
    if not os.path.exists(args.store):
        fail("no store at '%s'" % args.store)
    if args.out is None:
        args.out = default_out(args.store)
    try:
        store = open_store(args.store)
    except (OSError, ValueError) as e:
        fail(str(e), 1)
    if not store.has_analysis:
        fail("'%s' has no /analysis group: run `campaign analyze %s` first"
             % (args.store, args.store))
    nothing = nothing_to_draw(store)
    if nothing:
        fail(nothing, 3)
    os.makedirs(args.out, exist_ok=True)
    width = WIDTHS[args.width]
    written = []
    for name, fig in figures(store, width):
        written += save(fig, args.out, name, formats)
    if args.compare:
        with plt.rc_context(STYLE):
            fig = plot_fields_comparison(Study(store), store.fields(), args.compare, args.field,
                                         width)
            if args.compare_out:
                fig.savefig(args.compare_out, metadata=METADATA.get(
                    os.path.splitext(args.compare_out)[1].lstrip(".").lower()))
                plt.close(fig)
                written.append(args.compare_out)
            else:
                written += save(fig, args.out, "fields_compare", formats)
    store.close()
    for p in written:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
