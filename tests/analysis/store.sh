#!/bin/bash
# The Python access and the `plot` and `export` commands on a real store: mini_fields.toml (2 wall
# angles x 3 outlets x 2 realizations, fields on; a few seconds), then
# - test_hopper_store.py: every table of analysis/hopper_store.py against the raw datasets and
#   the C++ analysis, and the CSV export;
# - `campaign plot` in three formats, its figures checked for overlapping or clipped text;
# - `campaign export --vtk`: one .vti per point; bad arguments exit 2 with a message;
# - the README's Python example runs, and its sweep file passes `campaign run --dry-run`.
source "$SRC/tests/campaign/lib.sh"
for m in matplotlib pandas xarray h5py; do
    "$PY" -c "import $m" 2>/dev/null || { echo "SKIP: python3-$m is missing (./install-deps.sh)"; exit 77; }
done
STORE=$WORK/mf.h5
# campaign run draws the figures at its end
HOPPER_PLOTS=1 run_expect 0 run "$EXE" run "$DATA/mini_fields.toml" --store "$STORE" --progress-interval 0 --threads 2
expect_in run.out "figures (campaign plot $STORE --out $WORK/mf_plots):"
expect_in run.out "$WORK/mf_plots/survival.png"
[ -s "$WORK/mf_plots/jam_rate.png" ] || fail "campaign run did not draw jam_rate.png"
run_expect 0 export "$EXE" export "$STORE" --csv "$WORK/csv" --vtk "$WORK/vtk"
HOPPER_CAMPAIGN="$EXE" "$PY" "$SRC/tests/analysis/test_hopper_store.py" "$SRC" "$STORE" "$WORK/csv" ||
    fail "test_hopper_store.py"
[ "$(ls "$WORK"/vtk/*.vti | wc -l)" -eq 6 ] || fail "export --vtk wrote $(ls "$WORK"/vtk | wc -l) files, not 6"

run_expect 0 plot "$EXE" plot "$STORE" --out "$WORK/plots" --format png,pdf,svg
for fig in survival jam_rate beverloo k_theta in_hopper jam_onsets; do
    for fmt in png pdf svg; do
        [ -s "$WORK/plots/$fig.$fmt" ] || fail "campaign plot did not write $fig.$fmt"
    done
done
# plots.py (hopper-plot) without --out draws where `campaign plot` does: STORE_plots (issue 43)
rm -rf "$WORK/mf_plots"
run_expect 0 hopper_plot "$PY" "$SRC/analysis/plots.py" "$STORE"
expect_in hopper_plot.out "$WORK/mf_plots/survival.png"
[ -s "$WORK/mf_plots/survival.png" ] || fail "plots.py without --out did not write mf_plots/survival.png"
head -c 4 "$WORK/plots/survival.pdf" | grep -q '%PDF' || fail "survival.pdf is not a PDF"
"$PY" - "$SRC" "$STORE" <<'PYEOF' || fail "figures of the real store have layout problems"
import sys
sys.path[:0] = [sys.argv[1] + "/analysis", sys.argv[1] + "/tests/analysis"]
import plots, layout_check, hopper_store, matplotlib.pyplot as plt
bad = []
with hopper_store.open_store(sys.argv[2]) as s:
    for width in plots.WIDTHS.values():
        for name, fig in plots.figures(s, width):
            bad += layout_check.problems(fig, name)
            plt.close(fig)
print("\n".join(bad))
sys.exit(1 if bad else 0)
PYEOF

# the README's Python example runs as printed (on this store instead of the quickstart's)
awk '/^<!-- example: tests\/analysis\/store.sh runs this block -->/ {on = 1; next}
     on && /^```python/ {inside = 1; next} inside && /^```/ {exit} inside {print}' \
    "$SRC/README.md" >example.py
[ -s example.py ] || fail "no Python example found in README.md"
sed -i "s|\"build/quickstart.h5\"|\"$STORE\"|; s|sys.path.insert(0, \"analysis\")|sys.path.insert(0, \"$SRC/analysis\")|" example.py
rm -f survival.png
"$PY" example.py || fail "the README's Python example failed"
[ -s survival.png ] || fail "the README's Python example wrote no survival.png"

# the README's 10-line sweep file is a valid campaign (checked, not run)
awk '/^## A sweep file/ {on = 1} on && /^```toml/ {inside = 1; next} inside && /^```/ {exit}
     inside {print}' "$SRC/README.md" >first.toml
[ "$(wc -l <first.toml)" -ge 5 ] || fail "no sweep file found in README.md"
run_expect 0 first "$EXE" run first.toml --threads 2 --dry-run
expect_in first.out "D_cm=3 theta_deg=60"

run_expect 2 badfmt "$EXE" plot "$STORE" --format png,gif
expect_in badfmt.err "unknown format 'gif'"
run_expect 2 nothing "$EXE" export "$STORE"
expect_in nothing.err "nothing to export"
run_expect 2 nostore "$EXE" plot "$WORK/none.h5"
expect_in nostore.err "no store at"
echo "store.sh: all checks passed"
