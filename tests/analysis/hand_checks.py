"""Shared by the analysis tests with answers by hand (test_clogging.py,
test_silo_validation.py): puts the source tree's analysis/ on the import path (the first
command-line argument names the source tree) and collects failed checks, so that every check
runs and each failure is printed before the exit code is set."""
import os
import sys


def analysis_on_path():
    src = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")
    sys.path.insert(0, os.path.join(src, "analysis"))


class Checks:
    def __init__(self, name):
        self.name = name
        self.failures = []

    def __call__(self, cond, what):
        if not cond:
            self.failures.append(what)
            print("FAIL: " + what)

    def finish(self):
        print("%s: %d failed" % (self.name, len(self.failures)))
        sys.exit(1 if self.failures else 0)
