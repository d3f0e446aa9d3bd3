#!/usr/bin/python3
"""Compares two `campaign analyze --json` outputs value by value: the same keys in the same
order, the same strings, and numbers equal or within a relative tolerance. Prints every number
that differs (path, both values, relative difference) and the largest relative difference.

    /usr/bin/python3 bench/redesign/json_diff.py OLD.json NEW.json [--rel 1e-12]
Exit 0 when everything agrees within the tolerance, 1 otherwise.
"""
import json
import math
import sys


def walk(a, b, path, out):
    if isinstance(a, dict) and isinstance(b, dict):
        if list(a) != list(b):
            out.append((path, "keys differ", list(a), list(b)))
            return
        for k in a:
            walk(a[k], b[k], f"{path}/{k}", out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append((path, "lengths differ", len(a), len(b)))
            return
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]", out)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and \
            not isinstance(a, bool) and not isinstance(b, bool):
        if a != b:
            rel = abs(a - b) / max(abs(a), abs(b)) if max(abs(a), abs(b)) > 0 else math.inf
            out.append((path, rel, a, b))
    elif a != b:
        out.append((path, "values differ", a, b))


def main():
    args = sys.argv[1:]
    tol = 1e-12
    if "--rel" in args:
        i = args.index("--rel")
        tol = float(args[i + 1])
        del args[i:i + 2]
    old, new = (json.load(open(p)) for p in args)
    diffs = []
    walk(old, new, "", diffs)
    worst = 0.0
    bad = False
    for path, what, x, y in diffs:
        print(f"{path}: {x!r} -> {y!r} ({what if isinstance(what, str) else f'rel {what:.2e}'})")
        if isinstance(what, str) or what > tol:
            bad = True
        else:
            worst = max(worst, what)
    print(f"{len(diffs)} difference(s); largest relative difference of numbers {worst:.2e}; "
          f"{'FAIL' if bad else 'ok'} at tolerance {tol:g}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
