#!/usr/bin/python3
"""Plots an `aia eval` summary: success rate and flowtime increase against
the team size, one line per policy (the paper's figure 2).

Usage:
  tools/plot_eval.py renders/eval/summary.csv --out renders/eval/eval.png
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import experiment  # noqa: E402  (the one plot of success and flowtime)
from tool_io import BadInput, number, read_rows, run  # noqa: E402

COLUMNS = ("size", "policy", "instances", "success_rate", "flowtime_increase")


def load(path):
    """summary.csv's scored rows grouped per policy, as numbers, and the
    sizes in the file's order. A row without a success rate (no world of
    its size had an expert plan) is left out."""
    rows = {}
    sizes = []
    for row in read_rows(path, COLUMNS, "aia eval's summary.csv"):
        if row["size"] not in sizes:
            sizes.append(row["size"])
        if not row["success_rate"]:
            continue
        rows.setdefault(row["policy"], []).append({
            "size": row["size"],
            "instances": number(path, row, "instances"),
            "success_rate": number(path, row, "success_rate"),
            "flowtime_increase": number(path, row, "flowtime_increase")})
    return sizes, rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("summary", help="summary.csv written by aia eval")
    parser.add_argument("--out", required=True, help="PNG file to write")
    args = parser.parse_args(argv)
    sizes, rows = load(args.summary)
    if not rows:
        raise BadInput(f"{args.summary}: no scored rows")
    table = [{"size": r["size"], "policy": policy,
              "success_rate": r["success_rate"], "success_se": 0.0,
              "flowtime_increase": r["flowtime_increase"], "flowtime_increase_se": 0.0}
             for policy, rs in rows.items() for r in rs]
    n = int(max(r["instances"] for rs in rows.values() for r in rs))
    experiment.plot_scalability(table, sizes, args.out,
                                f"aia eval: {n} worlds per size; a failure counts F = 3 F*",
                                inputs=[args.summary])
    return 0


if __name__ == "__main__":
    run(main)
