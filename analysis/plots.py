#!/usr/bin/python3
"""Figures of a campaign store (after `campaign analyze`, which `campaign run` does at the end).

usage: /usr/bin/python3 analysis/plots.py STORE.h5 --out DIR

Writes into DIR (created if needed):
  survival.png     survival-time distribution per point: Kaplan-Meier curve (log scale) with its
                   Greenwood band and the fitted exponential exp(-t/tau), tau the censored MLE
  jam_onsets.png   every jam's onset (discharge time) per realization, per wall angle, with the
                   early/late test's p-value per outlet
  beverloo.png     mass flow rate versus outlet D with the Beverloo fits, and k versus theta
  in_hopper.png    particles in the hopper versus discharge time, per wall angle
  fields_*.png     field maps, only when the store has a /fields group (see plot_fields)
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


def plot_fields(st, out):
    """Hook for the fields issue: field maps (e.g. velocity, packing fraction) per point.

    Draws nothing and returns [] while the store has no /fields group. The fields issue fills
    this in: read /fields, write one fields_<name>.png per map into `out`, return their paths.
    """
    if "fields" not in st.f:
        return []
    return []


def main(argv=None):
    ap = argparse.ArgumentParser(description="Figures of a campaign store (after analyze).")
    ap.add_argument("store", help="the store (STORE.h5)")
    ap.add_argument("--out", required=True, help="directory for the PNG files")
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
    for p in written:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
