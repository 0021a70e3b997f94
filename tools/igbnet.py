#!/usr/bin/python3
"""I-GBNet from Python (docs/learning.md): read aia's datasets with the
standard library, load aia's models with Debian's python3-torch.

  tools/igbnet.py info DATASET_DIR_OR_FILE...
      episodes, samples, label counts and the useful share.
  tools/igbnet.py check MODEL INPUT.f32 N H W LOGITS.f32
      runs the model on N images of 4 x H x W float32 (little-endian,
      channel-major) and compares with the logits the C++ side wrote;
      exit 0 when they agree to 1e-4.
  tools/igbnet.py set MODEL OUT KEY=VALUE...
      writes MODEL's weights to OUT with channel parameters changed, and
      nothing else: KEY is reach_detour (metres, 0 off; the model must read
      the reach channel over the workspace), geodesic_length (metres,
      above 0) or neighbour_cap (a whole number, 0 off). The learned
      recipe's round 9 actor and its last step are made this way
      (tools/train_igbnet.sh).

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
import math
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


def network():
    """The Python package's network module (python/aia/network.py), loaded
    from the source tree (without the compiled part of the package)."""
    import importlib.util

    here = os.path.dirname(os.path.abspath(__file__))
    spec = importlib.util.spec_from_file_location(
        "aia_network", os.path.join(here, "..", "python", "aia", "network.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def load_model(path):
    """The saved model as a torch.nn.Module in evaluation mode, and its
    metadata (the channels' frame, cell, window, ...)."""
    return network().load_model(path)


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


# The channel parameters `set` may change: they shape what a channel reads,
# not the network's inputs or weights. KEY -> (check, what a bad value is).
SETTABLE = {
    "reach_detour": (lambda v: v >= 0.0, "must be 0 (off) or above"),
    "geodesic_length": (lambda v: v > 0.0, "must be above 0"),
    "neighbour_cap": (lambda v: v >= 0.0 and v == int(v) and v <= 1e6,
                      "must be a whole number, 0 (off) to 1000000"),
}


def set_channels(model, out, assignments):
    changes = {}
    for a in assignments:
        key, eq, text = a.partition("=")
        if key not in SETTABLE:
            print("error: command line: %s: not a settable channel parameter (%s)"
                  % (key, ", ".join(sorted(SETTABLE))), file=sys.stderr)
            return 2
        try:
            value = float(text) if eq else None
        except ValueError:
            value = None
        ok, why = SETTABLE[key]
        if value is None or not math.isfinite(value) or not ok(value):
            print("error: command line: %s: %s; got '%s'" % (key, why, text),
                  file=sys.stderr)
            return 2
        changes[key] = int(value) if key == "neighbour_cap" else value
    if not os.path.isfile(model):
        print("error: command line: MODEL: no such file: %s" % model, file=sys.stderr)
        return 2
    # The model is read whole before OUT is written, but a mistyped OUT that
    # names MODEL would replace it with no way back (a shipped model too).
    if os.path.exists(out) and os.path.samefile(model, out):
        print("error: command line: OUT: %s is MODEL; give another file" % out,
              file=sys.stderr)
        return 2
    nw = network()
    net, _ = nw.load_model(model)
    net.meta.update(changes)
    if net.meta.get("reach_detour", 0.0) > 0.0 and not net.meta.get("reach_world"):
        print("error: command line: reach_detour: needs a model whose reach channel "
              "covers the workspace (reach_world)", file=sys.stderr)
        return 2
    # Atomically, through a file of OUT's own name (torch names the archive's
    # folder after the file, so the bytes depend on OUT's name alone).
    import tempfile

    folder = tempfile.mkdtemp(dir=os.path.dirname(os.path.abspath(out)))
    tmp = os.path.join(folder, os.path.basename(out))
    try:
        nw.save_model(net, tmp)
        os.replace(tmp, out)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
        os.rmdir(folder)
    print("%s <- %s with %s" % (out, model, ", ".join(
        "%s=%g" % kv for kv in sorted(changes.items()))))
    return 0


def main(argv):
    if argv[:1] in (["-h"], ["--help"]):
        print(__doc__)
        return 0
    if len(argv) >= 2 and argv[0] == "info":
        info(argv[1:])
        return 0
    if len(argv) == 7 and argv[0] == "check":
        return check(argv[1], argv[2], int(argv[3]), int(argv[4]), int(argv[5]),
                     argv[6])
    if len(argv) >= 4 and argv[0] == "set":
        # TorchScript writes a module's constants in the order of a Python
        # set: a fixed hash seed makes OUT the same bytes on every run.
        if os.environ.get("PYTHONHASHSEED") != "0":
            os.execve(sys.executable, [sys.executable, os.path.abspath(__file__)] + argv,
                      dict(os.environ, PYTHONHASHSEED="0"))
        return set_channels(argv[1], argv[2], argv[3:])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
