#!/usr/bin/python3
"""A mission stepped from Python with random moves, then with the built-in
greedy policy deciding; prints what the robots achieved.

    PYTHONPATH=build/python examples/python/random_policy.py [SCENARIO]
"""
import sys

import numpy as np

import aia

scenario = sys.argv[1] if len(sys.argv) > 1 else "scenarios/default.yaml"
rng = np.random.default_rng(0)
for name, decide in [
        ("random moves", lambda m: rng.integers(0, 4, size=m.num_robots)),
        ("greedy", aia.builtin_policy("greedy").decide)]:
    m = aia.Mission(scenario, seed=1)
    while not m.done:
        m.step(decide(m))
    s = m.summary()
    print(f"{name}: success {s['success']} in {s['steps']} steps, "
          f"{s['localized_at_end']} of {s['targets']} targets localized")
