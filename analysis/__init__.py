"""hopper's Python analysis: read a campaign store into pandas and xarray (hopper_store), draw its
figures (plots), export it (export). Installed by `pip install ./analysis` as the package
hopper_analysis; the files are also run as scripts by `campaign plot` and `campaign export`.

    from hopper_analysis import open_store
    with open_store("quickstart.h5") as s:
        s.realizations.query("theta_deg == 60")
"""
from .hopper_store import Store, open_store, parse_scene, setting_text  # noqa: F401

__version__ = "0.4.0"  # the project's release (CMakeLists.txt project(), CHANGELOG.md)
__all__ = ["Store", "open_store", "parse_scene", "setting_text"]
