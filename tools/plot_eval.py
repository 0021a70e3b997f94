#!/usr/bin/python3
"""Plots an `aia eval` summary: success rate and flowtime increase against
the team size, one line per policy (the paper's figure 2).

Usage:
  tools/plot_eval.py renders/eval/summary.csv --out renders/eval/eval.png
"""

import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")  # headless
import matplotlib.pyplot as plt  # noqa: E402

POLICY_STYLE = {"igbnet": "C0", "decsb": "C1", "greedy": "C2", "random": "C3"}


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
    fig, (ax_s, ax_f) = plt.subplots(1, 2, figsize=(11, 4))
    for policy, rs in rows.items():
        x = [sizes.index(r["size"]) for r in rs]
        color = POLICY_STYLE.get(policy)
        ax_s.plot(x, [100 * float(r["success_rate"]) for r in rs], "o-", label=policy, color=color)
        ax_f.plot(x, [100 * float(r["flowtime_increase"]) for r in rs], "o-", label=policy,
                  color=color)
    for ax, title in ((ax_s, "success rate (%)"), (ax_f, "flowtime increase (%)")):
        ax.set_xticks(range(len(sizes)))
        ax.set_xticklabels(sizes)
        ax.set_xlabel("robots x targets")
        ax.set_title(title)
        ax.grid(alpha=0.3)
        ax.legend()
    n = max(int(r["instances"]) for rs in rows.values() for r in rs)
    fig.suptitle(f"aia eval: {n} worlds per size; a failure counts F = 3 F*")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
