#!/usr/bin/python3
"""Export a campaign store for other tools (`campaign export` calls this).

usage: /usr/bin/python3 analysis/export.py STORE.h5 [--csv DIR] [--vtk DIR]

--csv DIR  one CSV file per table of hopper_store (columns as there, SI units, the label's D_cm
           and theta_deg on every row): points, realizations, survival (duration > 0, event: for
           lifelines or R's Surv and survreg; duration_stored the store's value, 0.0 for a jam at
           the opening: hopper_store.Store.survival), events, curves, jams, exits, arches (one
           row per jam; the disks' ids, x and y as space-separated lists); after `campaign
           analyze` also analysis, beverloo, jam_rate, km, avalanche (the <s>(D) fits, for
           stores with avalanche sizes) and, with fields, fields (one row per point and cell,
           long form).
--vtk DIR  the merged field maps of every point with fields as VTK image data
           (fields_<label>.vti: cells of the grid, mean and std of vx, vy, speed, pressure,
           windows; NaN where no window reached a cell) that ParaView opens natively.

Prints the files it wrote. Exit codes: 0 written, 2 bad arguments or nothing to export (no
/analysis for --vtk), 1 other errors (unreadable store, unwritable directory).
"""
import argparse
import base64
import os
import sys

import numpy as np

if __package__:  # imported from the installed package (pip install ./analysis)
    from .hopper_store import open_store
else:  # run as a script: campaign runs analysis/export.py by its path
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from hopper_store import open_store  # noqa: E402

TABLES = ["points", "realizations", "survival", "events", "curves", "jams", "exits", "arches"]
ANALYSIS_TABLES = ["analysis", "beverloo", "jam_rate", "km", "avalanche"]
LIST_COLUMNS = {"arches": ["ids", "x", "y"]}  # a list per row, written space-separated


def file_part(label):
    return "".join(c if c.isalnum() or c in "._=-" else "_" for c in label)


def export_csv(s, out):
    os.makedirs(out, exist_ok=True)
    written = []
    names = TABLES + (ANALYSIS_TABLES if s.has_analysis else [])
    for name in names:
        if name == "avalanche" and "avalanche" not in s._f["analysis"]:
            continue  # analyzed before avalanche sizes existed
        df = getattr(s, name)
        if name in LIST_COLUMNS:
            df = df.copy()
            for c in LIST_COLUMNS[name]:
                df[c] = [" ".join(repr(v) if isinstance(v, float) else str(v) for v in values)
                         for values in df[c]]
        path = os.path.join(out, name + ".csv")
        df.to_csv(path, index=name in ("points", "realizations", "analysis"))
        written.append(path)
    if s.has_analysis:
        import pandas as pd
        parts = []
        for label, ds in s.fields().items():
            df = ds.drop_vars(["outline_x", "outline_y"]).to_dataframe().reset_index()
            df.insert(0, "label", label)
            parts.append(df)
        if parts:
            path = os.path.join(out, "fields.csv")
            pd.concat(parts, ignore_index=True).to_csv(path, index=False)
            written.append(path)
    return written


def vtk_array(name, values, components=1):
    """A DataArray in VTK's inline base64 binary form (UInt32 byte count, then the data)."""
    raw = np.ascontiguousarray(values, dtype="<f8").tobytes()
    payload = base64.b64encode(np.uint32(len(raw)).tobytes() + raw).decode("ascii")
    return ('        <DataArray type="Float64" Name="%s" NumberOfComponents="%d" '
            'format="binary">%s</DataArray>\n' % (name, components, payload))


def write_vti(path, ds):
    """One point's field maps as VTK XML ImageData: one cell per grid cell (z = 0 plane)."""
    nx, ny = ds.sizes["x"], ds.sizes["y"]
    cell = float(ds.attrs["cell"])
    x0, y0 = float(ds.attrs["x0"]), float(ds.attrs["y0"])
    names = [v for v in ds.data_vars if ds[v].dims == ("y", "x")]
    with open(path, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="ImageData" version="1.0" '
                'byte_order="LittleEndian" header_type="UInt32">\n')
        f.write('  <ImageData WholeExtent="0 %d 0 %d 0 0" Origin="%.17g %.17g 0" '
                'Spacing="%.17g %.17g 1">\n' % (nx, ny, x0, y0, cell, cell))
        f.write('    <Piece Extent="0 %d 0 %d 0 0">\n      <CellData Scalars="mean_speed">\n'
                % (nx, ny))
        for n in names:
            # VTK's cell order: x fastest, then y (the maps are ny x nx, row j = y)
            f.write(vtk_array(n, ds[n].values.ravel()))
        f.write("      </CellData>\n    </Piece>\n  </ImageData>\n</VTKFile>\n")


def export_vtk(s, out):
    if not s.has_analysis:
        raise LookupError("'%s' has no /analysis group: run `campaign analyze %s` first"
                          % (s.path, s.path))
    fields = s.fields()
    if not fields:
        raise LookupError("'%s' has no field maps (a sweep with [fields] enabled = true has them)"
                          % s.path)
    os.makedirs(out, exist_ok=True)
    written = []
    for label, ds in fields.items():
        path = os.path.join(out, "fields_%s.vti" % file_part(label))
        write_vti(path, ds)
        written.append(path)
    return written


def main(argv=None):
    ap = argparse.ArgumentParser(prog="campaign export",
                                 description="Export a store as CSV tables and VTK field maps.")
    ap.add_argument("store")
    ap.add_argument("--csv", metavar="DIR", help="write one CSV file per table into DIR")
    ap.add_argument("--vtk", metavar="DIR", help="write the field maps as .vti files into DIR")
    args = ap.parse_args(argv)
    if not args.csv and not args.vtk:
        print("campaign export: error: nothing to do: give --csv DIR and/or --vtk DIR",
              file=sys.stderr)
        return 2
    if not os.path.exists(args.store):
        print("campaign export: error: no store at '%s'" % args.store, file=sys.stderr)
        return 2
    try:
        with open_store(args.store) as s:
            written = []
            if args.csv:
                written += export_csv(s, args.csv)
            if args.vtk:
                written += export_vtk(s, args.vtk)
    except LookupError as e:
        print("campaign export: error: %s" % e.args[0], file=sys.stderr)
        return 2
    except (OSError, ValueError) as e:
        print("campaign export: error: %s" % e, file=sys.stderr)
        return 1
    for p in written:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
