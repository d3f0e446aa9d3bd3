#!/usr/bin/python3
"""The figure files of analysis/plots.py as a journal and a reader get them, on a synthetic store
shaped like the survival study (campaigns/paper/survival.toml) with the awkward cases added: an
outlet without jams, one with a single jam, avalanche sizes and arches of 5, 6, 7 and 9 disks
(none of 8). Fails on
- a PDF font that is not TrueType (matplotlib's default Type 3 is refused by journals),
- a creation date in a PDF or SVG, or a figure whose PDF, SVG or PNG bytes differ when it is
  drawn again,
- a colour drawn for data that no key (legend) shows (where more than one colour is drawn),
- a survival fit drawn from fewer than plots.MIN_JAMS_FOR_FIT jams, an outlet left out of the
  survival figure without its reason in the key, a 'no jams' bound drawn as a measured point,
  arch sizes joined across an empty size,
- `nothing_to_draw` not refusing a store whose realizations all failed.
usage: test_figure_files.py SOURCE_DIR"""
import io
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

import figure_env

src = figure_env.setup()
import matplotlib  # noqa: E402
import matplotlib.colors as mcolors  # noqa: E402
import matplotlib.lines as mlines  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

import plots  # noqa: E402
import synthetic  # noqa: E402

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)


# ----- the store ------------------------------------------------------------------------------

def awkward_store():
    """survival.toml's synthetic store; in its first group with three outlets the widest has no
    jam and the next one jam; avalanche sizes and arches everywhere."""
    s = synthetic.make_store(src / "campaigns" / "paper" / "survival.toml")
    c = s._cache
    rng = np.random.default_rng(7)
    group, rows = next((g, r) for g, r in s.groups().items() if len(r) >= 3)
    zero, one = rows[-1], rows[-2]
    surv, jams, km, an = c["survival"], c["jams"], c["km"], c["analysis"]
    real = c["realizations"]
    keep = ~surv["point"].isin([zero, one])
    new = []
    for p in (zero, one):
        for k, row in enumerate(real.index[real["point"] == p]):
            if p == one and k == 0:
                new += [(row, p, k, 0, 3.0, 1), (row, p, k, 1, 17.0, 0)]
            else:
                new.append((row, p, k, 0, 20.0, 0))
    surv = pd.concat([surv[keep], pd.DataFrame(new, columns=surv.columns)], ignore_index=True)
    surv["avalanche_size"] = rng.integers(5, 400, len(surv)).astype(float)
    c["survival"] = surv
    c["jams"] = jams[~jams["point"].isin([zero, one])]
    n_one = int((real["point"] == one).sum())
    c["km"] = pd.concat([km[~km["point"].isin([zero, one])],
                         pd.DataFrame([(one, 3.0, 1 - 1 / n_one, 0.1)], columns=km.columns)],
                        ignore_index=True)
    total = 20.0 * n_one
    an.loc[zero, ["tau_mle", "tau_ci95_lo", "tau_ci95_hi", "tau_lower_bound95", "n_jams"]] = \
        [np.nan, np.nan, np.nan, 40.0, 0]
    an.loc[one, ["tau_mle", "tau_ci95_lo", "tau_ci95_hi", "tau_lower_bound95", "n_jams"]] = \
        [total, total / 5, total * 30, np.nan, 1]
    means = surv.groupby("point")["avalanche_size"].mean()
    an["mean_avalanche"] = [means.get(i, np.nan) for i in an.index]
    an["mean_avalanche_ci95_lo"] = an["mean_avalanche"] * 0.8
    an["mean_avalanche_ci95_hi"] = an["mean_avalanche"] * 1.2
    c["avalanche"] = pd.DataFrame({"group": c["beverloo"]["group"], "exp_B": np.nan,
                                   "pow_gamma": np.nan})
    arch = []
    for row, p in zip(real.index, real["point"]):
        for j, n in enumerate((5, 6, 6, 7, 7, 7, 9, 9)):
            arch.append({"row": row, "point": p, "realization": 0, "jam": j, "disks": n})
    c["arches"] = pd.DataFrame(arch)
    return s, group, zero, one


# ----- checks of one figure -------------------------------------------------------------------

def render(fig, fmt):
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, metadata=plots.METADATA.get(fmt))
    return buf.getvalue()


def pdf_font_kinds(data):
    """The /Subtype of every font dictionary of a PDF written by matplotlib (it writes no
    object streams, so the dictionaries are plain text)."""
    kinds = []
    for m in re.finditer(rb"/Type\s*/Font\b(.*?)>>", data, re.S):
        sub = re.search(rb"/Subtype\s*/(\w+)", m.group(1))
        if sub:
            kinds.append(sub.group(1).decode())
    return kinds


def grey(rgba):
    r, g, b, _ = rgba
    return abs(r - g) < 1e-6 and abs(g - b) < 1e-6


def colours_of(artist):
    out = []
    if isinstance(artist, mlines.Line2D):
        if artist.get_linestyle() not in ("None", "none", "") and artist.get_linewidth() > 0:
            out.append(artist.get_color())
        if artist.get_marker() not in (None, "None", "none", ""):
            out += [artist.get_markeredgecolor(), artist.get_markerfacecolor()]
    elif isinstance(artist, matplotlib.patches.Rectangle):
        out.append(artist.get_facecolor())
    elif isinstance(artist, matplotlib.collections.LineCollection):
        out += list(artist.get_colors())
    keys = set()
    for c in out:
        if isinstance(c, str) and c.lower() == "none":
            continue
        rgba = mcolors.to_rgba(c)
        if rgba[3] == 0 or grey(rgba):
            continue
        keys.add(tuple(round(x, 3) for x in rgba[:3]))
    return keys


def unkeyed_colours(fig):
    """Colours drawn for data (lines, markers, bars, error bars; not colour maps, which have
    their colour bars) that no legend of the figure shows."""
    legends = fig.findobj(matplotlib.legend.Legend)
    keyed = set()
    for lg in legends:
        for h in lg.legendHandles:
            keyed |= colours_of(h)
        for h in lg.findobj(mlines.Line2D) + lg.findobj(matplotlib.collections.LineCollection):
            keyed |= colours_of(h)
    drawn = set()
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>" or not ax.axison:
            continue
        for a in ax.lines + ax.patches + ax.collections:
            drawn |= colours_of(a)
    if len(drawn) == 1 and not legends:  # one series: its axis labels say what it is
        return set()
    return drawn - keyed


# ----- the figures ----------------------------------------------------------------------------

store, group, zero, one = awkward_store()
D_zero = float(store.points.at[zero, "D_cm"])
D_one = float(store.points.at[one, "D_cm"])
names = []
first_run = {}
for width in ("page", "column"):
    for name, fig in plots.figures(store, plots.WIDTHS[width]):
        tag = "%s/%s" % (width, name)
        names.append(name)
        pdf = render(fig, "pdf")
        first_run[tag] = {"pdf": pdf}
        kinds = pdf_font_kinds(pdf)
        check(kinds, "%s: no font found in the PDF" % tag)
        check("Type3" not in kinds, "%s: Type 3 fonts in the PDF (fonts: %s)" % (tag, kinds))
        check(b"/CreationDate" not in pdf, "%s: the PDF has a CreationDate" % tag)
        svg = render(fig, "svg")
        check(b"<dc:date>" not in svg, "%s: the SVG has a date" % tag)
        first_run[tag].update(svg=svg, png=render(fig, "png"))
        lost = unkeyed_colours(fig)
        check(not lost, "%s: colours drawn that no key shows: %s" % (tag, sorted(lost)))
        texts = [t.get_text() for lg in fig.findobj(matplotlib.legend.Legend)
                 for t in lg.get_texts()]
        if name == "survival":
            g_ax = next(ax for ax in fig.axes if ax.get_title() == group)
            g_legend = g_ax.get_legend()
            g_texts = [t.get_text() for t in g_legend.get_texts()] if g_legend else []
            check(g_texts, "%s: the panel has no key of its outlets' jams" % tag)
            check(any(("%g cm" % D_zero) in t and "0 jams" in t and "no curve" in t
                      for t in g_texts), "%s: the no-jam outlet is not named: %s" % (tag, g_texts))
            check(any(("%g cm" % D_one) in t and "1 jam" in t and "no fit" in t
                      for t in g_texts), "%s: the one-jam outlet's missing fit is not named: %s"
                  % (tag, g_texts))
            c_one = mcolors.to_rgba(plots.Study(store).D_colour[D_one])
            dashed = [ln for ln in g_ax.lines if ln.get_linestyle() == "--"
                      and mcolors.to_rgba(ln.get_color()) == c_one]
            check(not dashed, "%s: a fit drawn from one jam" % tag)
            check(all(re.search(r"\d+ jams?", t) for t in g_texts),
                  "%s: a curve without its jam count: %s" % (tag, g_texts))
        if name == "jam_rate":
            check(any("bound" in t for t in texts), "%s: no key entry for the bound" % tag)
            ax_t = fig.axes[0]
            at_bound = [ln for ln in ax_t.lines
                        if D_zero in list(np.asarray(ln.get_xdata(), float))]
            arrows = [ln for ln in at_bound if ln.get_marker() in (mlines.CARETUP,
                                                                   mlines.CARETUPBASE)]
            check(arrows, "%s: the no-jam outlet's bound has no arrow head" % tag)
            opened = [ln for ln in at_bound if str(ln.get_markerfacecolor()).lower() == "none"]
            filled = [ln for ln in at_bound if ln.get_marker() in tuple("osD^v<>ph*")
                      and str(ln.get_markerfacecolor()).lower() != "none"]
            check(opened and not filled,
                  "%s: the bound is drawn with a filled marker, as a measurement" % tag)
        if name == "arch_sizes":
            for ax in fig.axes:
                if not ax.axison:
                    continue
                joined = [ln for ln in ax.lines if len(ln.get_xdata()) > 1
                          and ln.get_linestyle() not in ("None", "none", "")]
                check(not joined, "%s: arch sizes drawn as a line across sizes" % tag)
                xs = [p.get_x() + p.get_width() / 2 for p in ax.patches]
                check(xs and not any(abs(x - 8) < 0.45 for x in xs),
                      "%s: a bar at the empty size 8 (or no bars): %s" % (tag, xs))
        plt.close(fig)
# the same figures drawn again from the start (as a second `campaign plot` does): the same bytes
# (one width: the check is about the files' metadata, not the layout)
for width in ("column",):
    for name, fig in plots.figures(store, plots.WIDTHS[width]):
        tag = "%s/%s" % (width, name)
        for fmt in ("pdf", "svg", "png"):
            check(render(fig, fmt) == first_run[tag][fmt],
                  "%s: the %s differs from the first drawing's" % (tag, fmt))
        plt.close(fig)
for n in ("survival", "jam_rate", "avalanche", "arch_sizes"):
    check(n in names, "no %s figure drawn" % n)

# the check of keys can fail: a figure with two colours and no legend
with plt.rc_context(plots.STYLE):
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], color="C0")
    ax.plot([0, 1], [1, 0], color="C1")
    assert len(unkeyed_colours(fig)) == 2
    ax.legend(["a", "b"])
    assert not unkeyed_colours(fig)
    plt.close(fig)

# pdffonts (poppler-utils), where installed, agrees: no Type 3 in a figure written by save()
if shutil.which("pdffonts"):
    with tempfile.TemporaryDirectory() as d:
        for name, fig in plots.figures(store, plots.WIDTHS["column"]):
            if name not in ("survival", "jam_rate"):
                plt.close(fig)
                continue
            path = plots.save(fig, d, name, ["pdf"])[0]
            out = subprocess.run(["pdffonts", path], capture_output=True, text=True).stdout
            print(out)
            check("Type 3" not in out and "TrueType" in out,
                  "pdffonts %s.pdf:\n%s" % (name, out))

# issue 43, item 4: the Beverloo figure's key names a fit only where one is drawn, the empty
# times are not joined with the fit's solid line, and k_theta of one angle shows that angle
# (matplotlib's default axis was 0-1 deg). Two outlets at one angle: no fit.
def beverloo_checks(st, tag, with_fit):
    with plt.rc_context(plots.STYLE):
        fig = plots.plot_beverloo(plots.Study(st), plots.WIDTHS["column"])
    texts = [t.get_text() for lg in fig.legends + [a.get_legend() for a in fig.axes if
             a.get_legend()] for t in lg.get_texts()]
    check(("Beverloo fit" in texts) == with_fit,
          "%s: 'Beverloo fit' in the key %s, a fit drawn: %s" % (tag, texts, with_fit))
    ax_e = fig.axes[1]
    solid = [ln for ln in ax_e.lines if len(ln.get_xdata()) > 1 and ln.get_linestyle() == "-"]
    check(not solid, "%s: empty times joined with the fit's solid line" % tag)
    plt.close(fig)


with tempfile.TemporaryDirectory() as d:
    two = pathlib.Path(d) / "two.toml"
    two.write_text('[hopper]\nwidth_cm = 12\nparticles = 500\n[campaign]\nname = "two"\n'
                   'realizations = 3\n[sweep]\nD_cm = [2.5, 3.0]\ntheta_deg = [45]\n')
    small = synthetic.make_store(two)
check(small.beverloo["C"].isna().all(), "the two-outlet store has no Beverloo fit")
beverloo_checks(small, "two outlets", False)
beverloo_checks(store, "survival study", True)
with plt.rc_context(plots.STYLE):
    fig = plots.plot_k_theta(plots.Study(small), plots.WIDTHS["column"])
lo, hi = fig.axes[0].get_xlim()
check(lo < 45 < hi and hi - lo >= 10, "k_theta of one angle (45): x axis %g-%g deg" % (lo, hi))
plt.close(fig)

# a store whose realizations all failed: nothing to draw, said so
failed = synthetic.make_store(src / "campaigns" / "paper" / "survival.toml")
failed._cache["realizations"]["status"] = "failed"
failed._cache["realizations"]["message"] = "overlap at step 1"
why = plots.nothing_to_draw(failed)
check(why is not None and "every realization" in why and "overlap at step 1" in why,
      "a store whose realizations all failed is not refused: %r" % why)
check(plots.nothing_to_draw(store) is None, "a good store refused")

for f in failures:
    print("FAIL: " + f)
print("test_figure_files: %d figures, %d problems" % (len(names), len(failures)))
sys.exit(1 if failures else 0)
