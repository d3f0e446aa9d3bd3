#!/usr/bin/python3
"""Jams of full-size windows split by onset: at the opening (onset < CUT s of discharge) or later.

    jams_by_onset.py "OLD_GLOB" "NEW_GLOB" [CUT]

For each side (`campaign simulate --json` files): windows, jams at the opening and later, the
shakes each needed (max_shakes, 10, also when the last of them cleared the jam) and the arrests
in each group (the jam that ended its window arrested).
Issue 41 asks whether corrected Verlet at delta 25 arrests more often than gear4 at 50; the
arrests of the first windows came at the opening more often with the former.
"""
import collections
import glob
import json
import sys


def side(pattern, cut):
    windows, groups = 0, {"opening": [], "later": []}
    for path in sorted(glob.glob(pattern)):
        d = json.load(open(path))
        windows += 1
        for onset, shakes in zip(d["jam_onsets"], d["shakes_per_jam"]):
            last = d["status"] == "arrested" and onset == d["jam_onsets"][-1]
            groups["opening" if onset < cut else "later"].append((shakes, last))
    return windows, groups


def main():
    cut = float(sys.argv[3]) if len(sys.argv) > 3 else 0.1
    for label, pattern in (("old", sys.argv[1]), ("new", sys.argv[2])):
        windows, groups = side(pattern, cut)
        print(f"{label}: {windows} windows ({pattern})")
        for name, jams in groups.items():
            counts = collections.Counter(s for s, _ in jams)
            arrests = sum(a for _, a in jams)
            print(f"  {name:8s} jams {len(jams):4d}, arrested {arrests:3d}, shakes needed: "
                  + ", ".join(f"{k}: {counts[k]}" for k in sorted(counts)))


if __name__ == "__main__":
    main()
