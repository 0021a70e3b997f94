#!/usr/bin/python3
"""Plots `aia train`'s log: loss and accuracy per epoch, training and
validation; several logs (say, two frames) side by side on the same axes.

Usage:
  tools/plot_training.py models/igbnet.train.csv --out docs/igbnet_training.png
  tools/plot_training.py a.train.csv b.train.csv --labels centred,global --out cmp.png
"""

import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tool_io import (BadInput, number, pyplot, read_rows, run,  # noqa: E402
                     save_figure)

plt = pyplot()  # headless; where matplotlib is missing, its first use says so

COLUMNS = ("epoch", "train_loss", "train_acc", "val_loss", "val_acc",
           "val_acc_useful")


def load(path):
    rows = read_rows(path, COLUMNS, "a log of aia train (*.train.csv)")
    if not rows:
        raise BadInput(f"{path}: no epochs logged")
    # Validation fields are empty when no world was held out (--val-share 0).
    return {k: [number(path, r, k, empty=math.nan) if k.startswith("val_")
                else number(path, r, k) for r in rows]
            for k in COLUMNS}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("logs", nargs="+", help="*.train.csv files of aia train")
    ap.add_argument("--labels", help="comma-separated, one per log")
    ap.add_argument("--out", required=True, help="PNG to write")
    a = ap.parse_args()
    labels = a.labels.split(",") if a.labels else a.logs
    if len(labels) != len(a.logs):
        raise BadInput(f"--labels: {len(labels)} labels for {len(a.logs)} "
                       "logs; give one label per log")
    logs = [load(path) for path in a.logs]
    fig, (ax_loss, ax_acc) = plt.subplots(1, 2, figsize=(9, 3.4))
    for i, (d, label) in enumerate(zip(logs, labels)):
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
    save_figure(fig, a.out, 90, inputs=a.logs)
    print("wrote " + a.out)
    return 0


if __name__ == "__main__":
    run(main)
