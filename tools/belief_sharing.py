#!/usr/bin/python3
"""How many distinct beliefs a team holds of each target, step by step
(docs/design.md, Estimation: the figure behind a shared-block
representation of the beliefs; the scale issue).

Plays one mission in the scale worlds of tools/bench_scale.py (N robots, N
static targets, side 20 sqrt(N / 40) m, 0.075 boxes per m^2, a full graph)
with a built-in policy, and after every step counts, per target, the
distinct (mean, covariance) pairs among the robots' beliefs
(aia.Mission.state()): one when every robot holds the same belief.

  PYTHONPATH=build/python tools/belief_sharing.py --robots 1000 --seed 1001
"""
import argparse
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "build", "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import aia  # noqa: E402
from bench_scale import world  # noqa: E402
from tool_io import BadInput, run  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--robots", type=int, default=200,
                   help="N: robots and targets (default 200)")
    p.add_argument("--seed", type=int, default=504, help="the world's seed")
    p.add_argument("--policy", default="igbnet", help="a built-in policy")
    p.add_argument("--scenario",
                   default=os.path.join(ROOT, "scenarios", "default.yaml"))
    a = p.parse_args()
    if not 1 <= a.robots <= 1000:
        raise BadInput("--robots: must be in [1, 1000], got "
                       f"{a.robots}")
    side, boxes = world(a.robots)
    overrides = {"robots.count": a.robots, "targets.count": a.robots,
                 "workspace.size": [side, side],
                 "workspace.obstacles.random.count": boxes}
    try:
        m = aia.Mission(a.scenario, seed=a.seed, overrides=overrides)
        policy = aia.builtin_policy(a.policy)
    except aia.InputError as e:
        raise BadInput(str(e)) from None
    shares = []
    while True:
        s = m.state()
        n, k = s["mean"].shape[:2]
        blocks = np.concatenate([s["mean"].reshape(n, k, 2),
                                 s["cov"].reshape(n, k, 4)], axis=2)
        distinct = sum(len(np.unique(blocks[:, t, :], axis=0))
                       for t in range(k))
        shares.append(distinct / (n * k))
        print(f"step {m.steps}: {distinct} distinct beliefs of {n * k} "
              f"({distinct / (n * k):.4f}), {distinct / k:.1f} a target",
              flush=True)
        if m.done:
            break
        m.step(policy.decide(m))
    print(f"{a.robots} x {a.robots}, seed {a.seed}, {a.policy}: "
          f"{'success' if m.success else 'no success'} in {m.steps} steps; "
          f"distinct share {min(shares):.4f} to {max(shares):.4f}")
    return 0


if __name__ == "__main__":
    run(main)
