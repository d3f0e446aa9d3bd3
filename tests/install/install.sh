#!/bin/bash
# What a user installs (README, "Install"), installed into a scratch prefix and used from outside:
# - `cmake --install BUILD --prefix P` puts campaign, the layers' static libraries and headers,
#   hopperConfig.cmake (+ version file), the analysis scripts, the sweep files, LICENSE and
#   CITATION.cff under P;
# - the installed campaign names the release (project() of CMakeLists.txt) and runs the
#   installed analysis scripts, not the source tree's;
# - the C++ example of the docs (docs/examples/cpp, a project outside hopper) finds it with
#   find_package(hopper 0.4), links hopper::engine and runs one tiny realization; the README's
#   own find_package line is accepted by the installed version file, and it names the release's
#   major.minor, as the example does;
# - the Python module hopper_engine, where it was built, imports from P/lib/python3.X/*-packages;
# - `pip install ./analysis` into a venv made with --system-site-packages (Debian's numpy,
#   pandas, h5py, matplotlib; setuptools and wheel from Debian, no network) gives the package
#   hopper_analysis and the hopper-plot command.
# Environment: EXE, SRC, WORK, PY (as the other scripts), BUILD (the build tree), RELEASE.
source "$SRC/tests/campaign/lib.sh"
P=$WORK/prefix
run_expect 0 install cmake --install "$BUILD" --prefix "$P"
for f in bin/campaign include/hopper/engine/realization.hpp include/hopper/core/units.hpp \
         lib/libhopper_engine.a lib/libhopper_core.a lib/cmake/hopper/hopperConfig.cmake \
         lib/cmake/hopper/hopperConfigVersion.cmake lib/cmake/hopper/hopperTargets.cmake \
         share/hopper/analysis/plots.py share/hopper/analysis/hopper_store.py \
         share/hopper/campaigns/quickstart.toml share/doc/hopper/LICENSE \
         share/doc/hopper/CITATION.cff; do
    [ -e "$P/$f" ] || fail "cmake --install did not install $f"
done

# the Python module, where the build has it (pybind11 found): installed beside Python's packages
# (docs/usage.md, "The engine from Python"), it imports from there and reads an installed sweep
if compgen -G "$BUILD/src/python/hopper_engine.*.so" >/dev/null; then
    site=$(ls -d "$P"/lib/python3*/*-packages 2>/dev/null | head -1)
    [ -n "$site" ] && compgen -G "$site/hopper_engine.*.so" >/dev/null ||
        fail "cmake --install did not install the Python module hopper_engine"
    run_expect 0 pymodule env PYTHONPATH="$site" "$PY" -c \
        'import sys, hopper_engine; print(hopper_engine.__file__, hopper_engine.points(sys.argv[1]))' \
        "$P/share/hopper/campaigns/tiny.toml"
    expect_in pymodule.out "$site/hopper_engine."
    expect_in pymodule.out "'D_cm=3 theta_deg=60', 'D_cm=4.5 theta_deg=60'"
fi

# the release number, beside the commit
run_expect 0 version "$P/bin/campaign" --version
expect_in version.out "campaign (hopper) $RELEASE"
grep -q "version: $RELEASE" "$SRC/CITATION.cff" || fail "CITATION.cff does not name release $RELEASE"
grep -q "^version = \"$RELEASE\"" "$SRC/analysis/pyproject.toml" ||
    fail "analysis/pyproject.toml does not name release $RELEASE"
grep -q "^## \[$RELEASE\]" "$SRC/CHANGELOG.md" || fail "CHANGELOG.md has no section for $RELEASE"

# the installed campaign runs the installed scripts: a store whose realizations all fail (two
# overlapping particles; tests/campaign/failures.sh), plotted with a marked copy of plots.py
run_expect 3 run "$P/bin/campaign" run "$DATA/failing.toml" --store "$WORK/f.h5" --progress-interval 0
sed -i '1a print("installed plots.py")' "$P/share/hopper/analysis/plots.py"
run_expect 3 plot "$P/bin/campaign" plot "$WORK/f.h5" --out "$WORK/f_plots"
expect_in plot.out "installed plots.py"
expect_in plot.err "every realization of"
expect_in plot.err "nothing to draw"

# an outside project, the docs' example: find_package(hopper), hopper::engine, one realization
run_expect 0 consumer_cmake cmake -S "$SRC/docs/examples/cpp" -B "$WORK/consumer" \
    -DCMAKE_PREFIX_PATH="$P" -DCMAKE_BUILD_TYPE=Release
run_expect 0 consumer_build cmake --build "$WORK/consumer"
run_expect 0 consumer_run "$WORK/consumer/one_realization"
expect_in consumer_run.out "status "
expect_in consumer_run.out " particles 60 "
# the README's find_package line, as written, against this release (issue 43: it said 0.3, which
# the version file of 0.4.0 refuses)
readme_line=$(grep -o 'find_package(hopper [0-9.]* REQUIRED)' "$SRC/README.md" | head -1)
[ -n "$readme_line" ] || fail "README.md has no find_package(hopper X.Y REQUIRED) line"
example_line=$(grep -o 'find_package(hopper [0-9.]* REQUIRED)' "$SRC/docs/examples/cpp/CMakeLists.txt")
[ "$readme_line" = "$example_line" ] || fail "README: '$readme_line', docs/examples/cpp: '$example_line'"
[ "$readme_line" = "find_package(hopper ${RELEASE%.*} REQUIRED)" ] ||
    fail "README's '$readme_line' does not name release ${RELEASE%.*}"
mkdir -p "$WORK/readme_line"
printf 'cmake_minimum_required(VERSION 3.25)\nproject(t LANGUAGES CXX)\n%s\n' "$readme_line" \
    >"$WORK/readme_line/CMakeLists.txt"
run_expect 0 readme_line cmake -S "$WORK/readme_line" -B "$WORK/readme_line/build" -DCMAKE_PREFIX_PATH="$P"
# a release it does not have is refused by the version file
mkdir -p "$WORK/too_new"
printf 'cmake_minimum_required(VERSION 3.25)\nproject(t LANGUAGES CXX)\nfind_package(hopper 9.0 REQUIRED)\n' \
    >"$WORK/too_new/CMakeLists.txt"
run_expect 1 too_new cmake -S "$WORK/too_new" -B "$WORK/too_new/build" -DCMAKE_PREFIX_PATH="$P"
expect_in too_new.err "were considered but not accepted"

# the Python package, from a copy of analysis/ (the build writes beside its sources)
"$PY" -m venv --help >/dev/null 2>&1 || fail "no python3 venv module (install-deps.sh installs python3-venv)"
run_expect 0 venv "$PY" -m venv --system-site-packages "$WORK/venv"
cp -r "$SRC/analysis" "$WORK/analysis-copy"
rm -rf "$WORK/analysis-copy/__pycache__"
run_expect 0 pip "$WORK/venv/bin/pip" install --no-build-isolation --no-index "$WORK/analysis-copy"
cd "$WORK" || exit 1
run_expect 0 import "$WORK/venv/bin/python" -c "
import hopper_analysis
from hopper_analysis import open_store
assert hopper_analysis.__file__.startswith('$WORK/venv/'), hopper_analysis.__file__
assert hopper_analysis.__version__ == '$RELEASE', hopper_analysis.__version__
with open_store('$WORK/f.h5') as s:
    print(len(s.realizations), 'realizations', sorted(set(s.realizations['status'])))
"
expect_in import.out "2 realizations ['failed']"
run_expect 3 hopper_plot "$WORK/venv/bin/hopper-plot" "$WORK/f.h5" --out "$WORK/venv_plots"
expect_in hopper_plot.err "nothing to draw"
echo "install.sh: passed"
