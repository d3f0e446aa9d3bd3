"""What every figure test does first: the source tree from argv[1] on sys.path (analysis/ and
tests/analysis/), a skip (exit 77) without python3-matplotlib, -pandas or -xarray, and
matplotlib's Agg backend. usage (the test's own folder is on sys.path when it runs):
    import figure_env
    src = figure_env.setup()"""
import pathlib
import sys


def setup():
    src = pathlib.Path(sys.argv[1])
    sys.path.insert(0, str(src / "analysis"))
    sys.path.insert(0, str(src / "tests" / "analysis"))
    try:
        import matplotlib
        import pandas  # noqa: F401
        import xarray  # noqa: F401
    except ImportError as e:
        print("SKIP: %s (install python3-matplotlib, -pandas, -xarray: ./install-deps.sh)" % e)
        sys.exit(77)
    matplotlib.use("Agg")
    return src
