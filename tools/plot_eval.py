#!/usr/bin/python3
"""Plots an `aia eval` summary: success rate and flowtime increase against
the team size, one line per policy (the paper's figure 2).

Usage:
  tools/plot_eval.py renders/eval/summary.csv --out renders/eval/eval.png
"""

import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import experiment  # noqa: E402  (the one plot of success and flowtime)


def load(path):
    """summary.csv rows grouped per policy, in the file's size order."""
    rows = {}
    sizes = []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["size"] not in sizes:
                sizes.append(row["size"])
            if not row["success_rate"]:
                continue
            rows.setdefault(row["policy"], []).append(row)
    return sizes, rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("summary", help="summary.csv written by aia eval")
    parser.add_argument("--out", required=True, help="PNG file to write")
    args = parser.parse_args(argv)
    try:
        sizes, rows = load(args.summary)
    except (OSError, KeyError, csv.Error) as e:
        print(f"error: {args.summary}: {e}", file=sys.stderr)
        return 2
    if not rows:
        print(f"error: {args.summary}: no scored rows", file=sys.stderr)
        return 2
    table = [{"size": r["size"], "policy": policy,
              "success_rate": float(r["success_rate"]), "success_se": 0.0,
              "flowtime_increase": float(r["flowtime_increase"]), "flowtime_increase_se": 0.0}
             for policy, rs in rows.items() for r in rs]
    n = max(int(r["instances"]) for rs in rows.values() for r in rs)
    experiment.plot_scalability(table, sizes, args.out,
                                f"aia eval: {n} worlds per size; a failure counts F = 3 F*")
    return 0


if __name__ == "__main__":
    sys.exit(main())
