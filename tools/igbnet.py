#!/usr/bin/python3
"""I-GBNet from Python (docs/learning.md): read aia's datasets with the
standard library, load aia's models with Debian's python3-torch.

  tools/igbnet.py info DATASET_DIR_OR_FILE...
      episodes, samples, label counts and the useful share.
  tools/igbnet.py check MODEL INPUT.f32 N H W LOGITS.f32
      runs the model on N images of 4 x H x W float32 (little-endian,
      channel-major) and compares with the logits the C++ side wrote;
      exit 0 when they agree to 1e-4.

The dataset is SQLite (one file per shard): tables meta(key, value),
worlds(episode, seed, width, height, map_cell, lattice_step, robot_radius,
eps, robots, targets, steps, flowtime, obstacles, log_det_prior) and
samples(episode, step, robot, x, y, label, useful, acted, neighbours,
targets). Blobs are little-endian float64 arrays: obstacles 4 per box
(lo x, lo y, hi x, hi y), log_det_prior 1 per target, neighbours 2 per
neighbour (x, y), targets 6 per target (mean x, mean y, cov xx, cov xy,
cov yy, log det Sigma of the whole block). Labels: 0 left, 1 right, 2 up,
3 down.
"""
import glob
import os
import sqlite3
import struct
import sys

MOVES = ("left", "right", "up", "down")


def floats(blob):
    return struct.unpack("<%dd" % (len(blob) // 8), blob) if blob else ()


def dataset_files(paths):
    files = []
    for p in paths:
        files += sorted(glob.glob(os.path.join(p, "*.sqlite"))) if os.path.isdir(p) else [p]
    return files


def read_samples(path):
    """Yields one dict per sample of one SQLite file."""
    db = sqlite3.connect("file:%s?mode=ro" % path, uri=True)
    for row in db.execute(
            "SELECT episode, step, robot, x, y, label, useful, acted, neighbours, "
            "targets FROM samples ORDER BY episode, step, robot"):
        nb, tg = floats(row[8]), floats(row[9])
        yield {
            "episode": row[0], "step": row[1], "robot": row[2],
            "position": (row[3], row[4]), "label": row[5], "useful": bool(row[6]),
            "acted": row[7],
            "neighbours": [nb[i:i + 2] for i in range(0, len(nb), 2)],
            "targets": [tg[i:i + 6] for i in range(0, len(tg), 6)],
        }
    db.close()


def info(paths):
    episodes = samples = useful = 0
    labels = [0] * 4
    for f in dataset_files(paths):
        db = sqlite3.connect("file:%s?mode=ro" % f, uri=True)
        episodes += db.execute("SELECT count(*) FROM worlds").fetchone()[0]
        for label, n, u in db.execute(
                "SELECT label, count(*), sum(useful) FROM samples GROUP BY label"):
            labels[label] += n
            samples += n
            useful += u
        db.close()
    print("%d episodes, %d samples, %.1f %% with useful work" %
          (episodes, samples, 100.0 * useful / max(samples, 1)))
    print("labels: " + ", ".join("%s %d" % (m, n) for m, n in zip(MOVES, labels)))


def load_model(path):
    """The saved model as a torch.nn.Module in evaluation mode, and its
    metadata (the channels' frame, cell, window, ...): the Python package's
    network (python/aia/network.py), loaded from the source tree."""
    import importlib.util

    here = os.path.dirname(os.path.abspath(__file__))
    spec = importlib.util.spec_from_file_location(
        "aia_network", os.path.join(here, "..", "python", "aia", "network.py"))
    network = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(network)
    return network.load_model(path)


def check(model, images, n, h, w, logits):
    import torch

    net, meta = load_model(model)
    c = meta["channels"]
    with open(images, "rb") as f:
        x = torch.tensor(struct.unpack("<%df" % (n * c * h * w), f.read()))
    with open(logits, "rb") as f:
        want = torch.tensor(struct.unpack("<%df" % (n * 4), f.read())).reshape(n, 4)
    with torch.no_grad():
        got = net(x.reshape(n, c, h, w))
    diff = (got - want).abs().max().item()
    print("max |python - c++| = %.3g over %d logits" % (diff, n * 4))
    return 0 if diff <= 1e-4 else 1


def main(argv):
    if len(argv) >= 2 and argv[0] == "info":
        info(argv[1:])
        return 0
    if len(argv) == 7 and argv[0] == "check":
        return check(argv[1], argv[2], int(argv[3]), int(argv[4]), int(argv[5]),
                     argv[6])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
