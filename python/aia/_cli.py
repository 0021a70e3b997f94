"""The `aia` command of an environment the wheel was installed into: the
CLI the wheel holds (aia/bin/aia)."""
import os
import sys


def main():
    exe = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bin",
                       "aia")
    if not os.path.exists(exe):
        sys.exit("aia: this package has no CLI (build/aia is the build "
                 "tree's)")
    os.execv(exe, [exe] + sys.argv[1:])
