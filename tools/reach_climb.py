#!/usr/bin/python3
"""Does a model read its own reach channel? (issue 35, docs/notes)

Plays missions three ways from the same channels (aia.Mission.channels with
the model's settings: exactly the input the igbnet policy gives it):

  network  the model alone (policy.coordination none, the C++ policy);
  climb    no network: each robot takes the valid move to the neighbour pixel
           of its own pixel where the reach channel is largest (ties to the
           lower move), i.e. it climbs the channel the model is shown;
  agree    the network plays; at every state the climb's move is worked out
           too, and for the missions that fail, over their last 50 steps:
           how often the two agree and how often the robot stands on a local
           maximum of its reach channel (where climbing gives nothing).

Default worlds: the generalization suite's narrow perfect mazes (20 x 20 m,
passages of 1.5 m, walls of 0.15 m, no loops; 4 robots, 6 targets) at the
selection seeds 5000.. (never the test seeds).

  PYTHONPATH=build/python tools/reach_climb.py --mode climb --seeds 10
"""
import argparse
import json
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools"))
from tool_io import import_aia, run  # noqa: E402

aia = import_aia()
from aia import network  # noqa: E402

# left, right, up, down: the pixel one lattice move away, (du, dv)
STEP = {0: (-1, 0), 1: (1, 0), 2: (0, 1), 3: (0, -1)}
UNDO = {0: 1, 1: 0, 2: 3, 3: 2}


def narrow_maze():
    g = "workspace.obstacles.generator"
    return {f"{g}.type": "maze", f"{g}.corridor": 1.5, f"{g}.wall": 0.15,
            f"{g}.loops": 0, "workspace.obstacles.random.count": 0,
            "robots.count": 4, "targets.count": 6}


def climb_moves(channels, valid, reach):
    c = channels.shape[2] // 2
    moves, at_max = [], []
    for i in range(channels.shape[0]):
        r = channels[i, reach]
        score = [r[c + STEP[a][1], c + STEP[a][0]] for a in range(4)]
        ok = [a for a in range(4) if valid[i, a]]
        moves.append(max(ok, key=lambda a: (score[a], -a)) if ok else 0)
        at_max.append(not ok or max(score[a] for a in ok) <= r[c, c])
    return moves, at_max


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--mode", choices=["network", "climb", "agree"],
                   default="agree")
    p.add_argument("--model", default=os.path.join(ROOT, "models",
                                                   "igbnet_learned.pt"))
    p.add_argument("--scenario", default=os.path.join(ROOT, "scenarios",
                                                      "default.yaml"))
    p.add_argument("--seeds", type=int, default=10, help="worlds")
    p.add_argument("--seed-base", type=int, default=5000)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="another scenario key (replaces the narrow maze's "
                        "keys of the same name); a JSON value is read as "
                        "one: robots.count=20, workspace.size=[60,60]")
    a = p.parse_args()
    if a.seeds < 1:
        p.error("--seeds: must be at least 1")
    if not os.path.isfile(a.model):
        p.error(f"--model {a.model}: no such file")
    overrides = narrow_maze()
    for kv in a.set:
        if "=" not in kv:
            p.error(f"--set {kv}: must be KEY=VALUE")
        k, v = kv.split("=", 1)
        try:  # numbers and lists as the Python API takes them: 20, [60, 60]
            overrides[k] = json.loads(v)
        except ValueError:
            overrides[k] = v
    _, meta = network.load_model(a.model)
    if not meta.get("geodesic"):
        p.error(f"--model {a.model}: has no reach channel")
    params = network.channel_params(meta)
    reach = 4
    wins = reversals = moves_made = 0
    for seed in range(a.seed_base, a.seed_base + a.seeds):
        m = aia.Mission(a.scenario, seed=seed, overrides=overrides)
        net = aia.builtin_policy("igbnet", model=a.model, coordination="none")
        last = [None] * m.num_robots
        kept = []  # (network's moves, climb's moves, at a local max)
        while not m.done:
            x = m.channels(**params)
            climb, at_max = climb_moves(x, m.valid_moves(), reach)
            played = climb if a.mode == "climb" else list(net.decide(m))
            if a.mode == "agree":
                kept.append((played, climb, at_max))
            for i, mv in enumerate(played):
                reversals += last[i] is not None and UNDO[last[i]] == mv
                last[i] = mv
                moves_made += 1
            m.step(played)
        wins += m.success
        line = f"seed {seed}: success {m.success}, {m.steps} steps"
        if a.mode == "agree" and not m.success:
            tail = kept[-50:]
            same = np.mean([x == y for n, c, _ in tail for x, y in zip(n, c)])
            top = np.mean([t for _, _, ts in tail for t in ts])
            line += (f"; last 50 steps: network = climb {same:.2f}, "
                     f"at a local max {top:.2f}")
        print(line, flush=True)
    print(f"{a.mode}: success {wins / a.seeds:.2f}, reversal share "
          f"{reversals / max(moves_made, 1):.3f} ({a.seeds} worlds from "
          f"{a.seed_base})")


if __name__ == "__main__":
    run(main)
