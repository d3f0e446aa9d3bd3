#!/usr/bin/python3
"""Renders every figure of analysis/plots.py for synthetic stores shaped like each paper study
(campaigns/paper/*.toml: their points, groups, outlets and varied settings), at page and column
width, and fails on text that overlaps other text, is clipped by the figure's edge, is smaller
than 6 pt, or on a legend that covers text or another panel. A deliberately bad figure must be
caught (the check can fail). usage: test_figures.py SOURCE_DIR [OUT_DIR]"""
import warnings
import pathlib
import sys

import figure_env

src = figure_env.setup()
import matplotlib.pyplot as plt  # noqa: E402

import layout_check  # noqa: E402
import plots  # noqa: E402
import synthetic  # noqa: E402

out_dir = pathlib.Path(sys.argv[2]) if len(sys.argv) > 2 else None

# The check must see a bad layout: two overlapping titles and a legend across two panels.
with plt.rc_context(plots.STYLE):
    fig, (a, b) = plt.subplots(1, 2, figsize=(3.4, 2))
    a.set_title("a long title that runs into the next panel's title")
    b.set_title("the next panel's title")
    a.plot([0, 1], [0, 1], label="a line")
    a.legend(loc="center left", bbox_to_anchor=(0.5, 0.5))
    found = layout_check.problems(fig, "control")
    plt.close(fig)
assert any("overlaps" in p for p in found), found
assert any("legend" in p for p in found), found
assert any("clipped" in p for p in found), found

failures, drawn = [], 0
studies = sorted((src / "campaigns" / "paper").glob("*.toml"))
assert len(studies) >= 8, studies
if len(sys.argv) > 3:  # only the studies named (while working on a figure)
    studies = [p for p in studies if p.stem in sys.argv[3:]]
for path in studies:
    store = synthetic.make_store(path)
    for width in ("page", "column"):
        for name, fig in plots.figures(store, plots.WIDTHS[width]):
            tag = "%s/%s/%s" % (path.stem, width, name)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                failures += layout_check.problems(fig, tag)
            failures += ["%s: %s" % (tag, w.message) for w in caught]
            w, h = fig.get_size_inches()
            if abs(w - plots.WIDTHS[width]) > 0.01 and name != "k_theta":
                failures.append("%s: %.2f in wide, not %s" % (tag, w, plots.WIDTHS[width]))
            if out_dir is not None:
                out_dir.mkdir(parents=True, exist_ok=True)
                fig.savefig(out_dir / ("%s_%s_%s.png" % (path.stem, width, name)), dpi=80)
            plt.close(fig)
            drawn += 1
    print("%s: %d points, groups %s" % (path.stem, len(store.points), list(store.groups())[:4]))
    # the synthetic stores have the shipped files' point counts (test_sweep.cpp has them too)
    expected = {"single-material": 12, "large-outlet-material": 8, "survival": 11,
                "empty-time": 8, "beverloo-angle": 40, "discharge-curves": 5}
    if path.stem in expected and len(store.points) != expected[path.stem]:
        failures.append("%s: %d points, the sweep file has %d" % (path.stem, len(store.points),
                                                                 expected[path.stem]))
for f in failures:
    print("FAIL: " + f)
print("%d figures drawn, %d layout problems" % (drawn, len(failures)))
sys.exit(1 if failures else 0)
