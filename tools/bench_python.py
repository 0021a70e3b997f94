#!/usr/bin/python3
"""The Python package's costs (docs/python.md, Speed), medians of alternating
runs on one scenario:

  overhead  a mission stepped from Python, the built-in random policy
            deciding, against the same mission's steps in `aia run`
            (diagnostics.json's wall_seconds.steps): ms a step and ratio;
  vector    VectorMissions of N missions with 1 and with 2 threads.

  PYTHONPATH=build/python tools/bench_python.py [--scenario FILE] [--runs 5]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from tool_io import import_aia, run  # noqa: E402

aia = import_aia()


def overhead(scenario, aia_binary, steps, runs):
    overrides = {"mission.stop_at_success": False, "mission.max_steps": steps}
    py, cpp = [], []
    with tempfile.TemporaryDirectory() as out:
        for _ in range(runs):
            m = aia.Mission(scenario, seed=1, overrides=overrides)
            policy = aia.builtin_policy("random")
            t = time.perf_counter()
            while not m.done:
                m.step(policy.decide(m))
            py.append((time.perf_counter() - t) / m.steps)
            subprocess.run([aia_binary, "run", scenario, "--seed", "1",
                            "--policy", "random", "--set",
                            "mission.stop_at_success=false", "--max-steps",
                            str(steps), "--trace", "min", "--out", out,
                            "--quiet"], check=True, capture_output=True)
            with open(os.path.join(out, "diagnostics.json")) as f:
                d = json.load(f)
            cpp.append(d["wall_seconds"]["steps"] / d["physics"]["steps"])
    p, c = statistics.median(py), statistics.median(cpp)
    print(f"overhead: Python {p * 1e3:.3f} ms/step, aia run {c * 1e3:.3f} "
          f"ms/step (medians of {runs}), ratio {p / c:.3f}")


def vector(scenario, n, steps, runs):
    overrides = {"mission.stop_at_success": False, "mission.max_steps": 400}

    def run(threads):
        v = aia.VectorMissions(n, scenario, seed=1, overrides=overrides,
                               threads=threads)
        moves = np.random.default_rng(0).integers(
            0, 4, size=(steps, n, v.num_robots))
        t = time.perf_counter()
        for k in range(steps):
            v.step(moves[k])
        return (time.perf_counter() - t) / steps

    one, two = [], []
    for _ in range(runs):
        one.append(run(1))
        two.append(run(2))
    a, b = statistics.median(one), statistics.median(two)
    print(f"vector: {n} missions, 1 thread {a * 1e3:.2f} ms/step, 2 threads "
          f"{b * 1e3:.2f} ms/step (medians of {runs}), speed-up {a / b:.2f}x")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenario", default=os.path.join(HERE, "..", "scenarios",
                                                      "default.yaml"))
    p.add_argument("--aia", default=os.path.join(HERE, "..", "build", "aia"),
                   help="the aia binary (default build/aia)")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--steps", type=int, default=300)
    p.add_argument("--missions", type=int, default=8)
    a = p.parse_args()
    if a.runs < 1 or a.steps < 1 or a.missions < 1:
        sys.exit("error: --runs, --steps and --missions must be >= 1")
    overhead(a.scenario, a.aia, a.steps, a.runs)
    vector(a.scenario, a.missions, 40, max(a.runs, 7))


if __name__ == "__main__":
    run(main)
