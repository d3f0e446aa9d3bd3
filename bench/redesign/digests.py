#!/usr/bin/python3
"""Digest of a store's physics content, for before/after comparisons of a code change that must
not change results (issue 17). Hashes every dataset of the HDF5 view except provenance and
timing (/runs, rank, attempt, task and wall seconds, timestamps), in storage order: run the
campaign with one worker (`--threads 1`) so that the order is the same in both builds.

    /usr/bin/python3 bench/redesign/digests.py [--part results|analysis] STORE.h5
        -> one line "sha256  STORE.h5"
    results: everything but /analysis (the realizations, points, tasks, fields);
    analysis: /analysis only (what `campaign analyze` derived); default: both.
"""
import hashlib
import sys

import h5py
import numpy as np

SKIP_GROUPS = ("/runs",)
SKIP_NAMES = {"rank", "attempt", "task_seconds", "finished_unix", "time_unix", "wall_seconds",
              "ns_per_particle_step", "seconds_forces", "seconds_integration",
              "seconds_neighbors", "seconds_observers"}


def digest(path, part="all"):
    h = hashlib.sha256()
    names = []
    with h5py.File(path, "r") as f:
        f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
        for n in sorted(names):
            full = "/" + n
            if full.startswith(SKIP_GROUPS) or n.rsplit("/", 1)[-1] in SKIP_NAMES:
                continue
            in_analysis = full.startswith("/analysis/")
            if (part == "results" and in_analysis) or (part == "analysis" and not in_analysis):
                continue
            data = f[full][()]
            h.update(full.encode())
            update(h, data)
    return h.hexdigest()


def update(h, data):
    """Hashes a dataset's values: numbers by their bytes, strings by their text. A compound
    (/points/parameters) field by field: its raw bytes would hold the addresses of the Python
    objects that h5py reads variable-length strings into, different at every read."""
    data = np.asarray(data)
    if data.dtype.names:
        for name in data.dtype.names:
            h.update(name.encode())
            update(h, data[name])
    elif data.dtype.kind == "O":
        for x in data.ravel():
            h.update(x if isinstance(x, bytes) else str(x).encode())
            h.update(b"\0")
    else:
        h.update(data.tobytes())


if __name__ == "__main__":
    args = sys.argv[1:]
    part = "all"
    if args[:1] == ["--part"]:
        part, args = args[1], args[2:]
    for p in args:
        print(digest(p, part), p)
