#!/usr/bin/python3
"""Render one particle snapshot written by `campaign simulate --snapshots DIR` as a PNG.

    analysis/render_snapshot.py DIR/hopper.000010.dump --out frame.png [--color speed|type]

Reads one frame of a LAMMPS-style text dump (the format is documented in
src/cli/snapshot_writer.hpp: ITEM: TIMESTEP, optional ITEM: TIME, ITEM: NUMBER OF ATOMS,
ITEM: BOX BOUNDS, ITEM: ATOMS with at least the columns id type x y radius). Disks are drawn to
scale; wall particles (type 2) in grey; mobile particles coloured by speed (a colour bar in m/s)
or, with --color type, in one colour. Axes are in cm.

Needs Debian's python3-numpy and python3-matplotlib. Exits with status 2 and a message naming
the file and line when the dump is malformed.
"""

import argparse
import sys

try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")  # files only, no display needed
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle
except ImportError as exc:  # pragma: no cover - depends on the machine
    sys.exit(f"render_snapshot.py: error: {exc} (install python3-numpy and python3-matplotlib)")

WALL_TYPE = 2
REQUIRED_COLUMNS = ("id", "type", "x", "y", "radius")


class DumpError(Exception):
    """A malformed dump file."""


def read_dump(path):
    """Returns (header, columns) of the first frame: header has 'timestep', 'time' (or None),
    'natoms', 'box'; columns maps a column name to a numpy array."""
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise DumpError(f"cannot read {path}: {exc}") from exc

    header = {"timestep": None, "time": None, "natoms": None, "box": None}
    i = 0

    def value_line(what):
        nonlocal i
        if i + 1 >= len(lines):
            raise DumpError(f"{path}: line {i + 1}: {what} has no value line")
        i += 1
        return lines[i]

    def number(text, kind, what):
        try:
            return kind(text.split()[0])
        except (ValueError, IndexError) as exc:
            raise DumpError(f"{path}: line {i + 1}: invalid {what}: {text!r}") from exc

    while i < len(lines):
        line = lines[i].strip()
        if not line:
            i += 1
            continue
        if not line.startswith("ITEM:"):
            raise DumpError(f"{path}: line {i + 1}: expected an 'ITEM:' line, got {line!r}")
        item = line[len("ITEM:"):].strip()
        if item == "TIMESTEP":
            header["timestep"] = number(value_line("TIMESTEP"), int, "timestep")
        elif item == "TIME":
            header["time"] = number(value_line("TIME"), float, "time")
        elif item == "NUMBER OF ATOMS":
            header["natoms"] = number(value_line("NUMBER OF ATOMS"), int, "number of atoms")
            if header["natoms"] < 0:
                raise DumpError(f"{path}: line {i + 1}: negative number of atoms")
        elif item.startswith("BOX BOUNDS"):
            box = []
            for _ in range(3):
                text = value_line("BOX BOUNDS")
                try:
                    lo, hi = (float(v) for v in text.split()[:2])
                except ValueError as exc:
                    raise DumpError(f"{path}: line {i + 1}: invalid box bounds {text!r}") from exc
                box.append((lo, hi))
            header["box"] = box
        elif item.startswith("ATOMS"):
            names = item.split()[1:]
            missing = [c for c in REQUIRED_COLUMNS if c not in names]
            if missing:
                raise DumpError(f"{path}: line {i + 1}: ITEM: ATOMS lacks column(s) "
                                f"{', '.join(missing)}")
            if header["natoms"] is None:
                raise DumpError(f"{path}: ITEM: ATOMS before ITEM: NUMBER OF ATOMS")
            n = header["natoms"]
            rows = lines[i + 1:i + 1 + n]
            if len(rows) < n:
                raise DumpError(f"{path}: expected {n} particle lines after line {i + 1}, "
                                f"found {len(rows)}")
            data = np.empty((n, len(names)))
            for k, row in enumerate(rows):
                fields = row.split()
                if len(fields) != len(names):
                    raise DumpError(f"{path}: line {i + 2 + k}: expected {len(names)} values, "
                                    f"got {len(fields)}")
                try:
                    data[k] = [float(v) for v in fields]
                except ValueError as exc:
                    raise DumpError(f"{path}: line {i + 2 + k}: not a number in {row!r}") from exc
            if not np.all(np.isfinite(data)):
                raise DumpError(f"{path}: non-finite value in the particle lines")
            return header, {name: data[:, c] for c, name in enumerate(names)}
        else:
            # Unknown sections are skipped up to the next ITEM (as OVITO does).
            i += 1
            while i < len(lines) and not lines[i].startswith("ITEM:"):
                i += 1
            continue
        i += 1
    raise DumpError(f"{path}: no 'ITEM: ATOMS' section")


def render(path, out, color):
    header, cols = read_dump(path)
    cm = 100.0  # metres -> cm
    x, y, r = cols["x"] * cm, cols["y"] * cm, cols["radius"] * cm
    wall = cols["type"] == WALL_TYPE
    mobile = ~wall

    fig, ax = plt.subplots(figsize=(7, 8))
    if np.any(wall):
        walls = PatchCollection([Circle((a, b), c) for a, b, c in zip(x[wall], y[wall], r[wall])],
                                facecolor="0.55", edgecolor="0.35", linewidth=0.3)
        ax.add_collection(walls)
    if np.any(mobile):
        disks = PatchCollection(
            [Circle((a, b), c) for a, b, c in zip(x[mobile], y[mobile], r[mobile])],
            edgecolor="black", linewidth=0.2)
        if color == "speed" and "vx" in cols and "vy" in cols:
            speed = np.hypot(cols["vx"][mobile], cols["vy"][mobile])
            disks.set_array(speed)
            disks.set_cmap("viridis")
            disks.set_clim(0.0, max(float(speed.max()), 1e-6))
            ax.add_collection(disks)
            fig.colorbar(disks, ax=ax, label="speed (m/s)", shrink=0.8)
        else:
            if color == "speed":
                print(f"render_snapshot.py: warning: {path} has no vx/vy columns; "
                      "colouring by type", file=sys.stderr)
            disks.set_facecolor("tab:orange")
            ax.add_collection(disks)

    pad = float(r.max()) if len(r) else 1.0
    if len(x):
        ax.set_xlim(float(x.min()) - pad, float(x.max()) + pad)
        ax.set_ylim(float(y.min()) - pad, float(y.max()) + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    title = f"frame {header['timestep']}" if header["timestep"] is not None else str(path)
    if header["time"] is not None:
        title += f", t = {header['time']:.3f} s since the fill"
    title += f", {int(mobile.sum())} particles"
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(out, dpi=150)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description="Render one hopper snapshot dump as a PNG.")
    parser.add_argument("dump", help="a dump file written by campaign simulate --snapshots")
    parser.add_argument("--out", required=True, help="output image (PNG)")
    parser.add_argument("--color", choices=("speed", "type"), default="speed",
                        help="colour mobile particles by speed (default) or by type")
    args = parser.parse_args(argv)
    try:
        render(args.dump, args.out, args.color)
    except DumpError as exc:
        print(f"render_snapshot.py: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"render_snapshot.py: error: cannot write {args.out}: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
