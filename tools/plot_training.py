#!/usr/bin/python3
"""Plots `aia train`'s log: loss and accuracy per epoch, training and
validation; several logs (say, two frames) side by side on the same axes.

Usage:
  tools/plot_training.py models/igbnet.train.csv --out docs/igbnet_training.png
  tools/plot_training.py a.train.csv b.train.csv --labels centred,global --out cmp.png
"""

import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")  # headless
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit("error: %s: no epochs logged" % path)
    # Validation fields are empty when no world was held out (--val-share 0).
    return {k: [float(r[k]) if r[k] != "" else float("nan") for r in rows]
            for k in rows[0]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("logs", nargs="+", help="*.train.csv files of aia train")
    ap.add_argument("--labels", help="comma-separated, one per log")
    ap.add_argument("--out", required=True, help="PNG to write")
    a = ap.parse_args()
    labels = a.labels.split(",") if a.labels else a.logs
    if len(labels) != len(a.logs):
        sys.exit("error: --labels: give one label per log")
    fig, (ax_loss, ax_acc) = plt.subplots(1, 2, figsize=(9, 3.4))
    for i, (path, label) in enumerate(zip(a.logs, labels)):
        d = load(path)
        c = "C%d" % i
        ax_loss.plot(d["epoch"], d["train_loss"], c + "--", label=label + " train")
        ax_loss.plot(d["epoch"], d["val_loss"], c + "-o", ms=3, label=label + " val")
        ax_acc.plot(d["epoch"], d["train_acc"], c + "--", label=label + " train")
        ax_acc.plot(d["epoch"], d["val_acc"], c + "-o", ms=3, label=label + " val")
        ax_acc.plot(d["epoch"], d["val_acc_useful"], c + ":", label=label + " val (useful)")
    ax_loss.set_xlabel("epoch")
    ax_loss.set_ylabel("cross-entropy")
    ax_acc.set_xlabel("epoch")
    ax_acc.set_ylabel("accuracy (expert's move)")
    ax_acc.legend(fontsize=7)
    ax_loss.legend(fontsize=7)
    for ax in (ax_loss, ax_acc):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    print("wrote " + a.out)


if __name__ == "__main__":
    main()
