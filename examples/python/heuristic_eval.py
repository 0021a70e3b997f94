#!/usr/bin/python3
"""A hand-written heuristic scored exactly as `aia eval` scores the
built-ins, in one table beside them.

Each robot heads for the unlocalized target (in its own belief) whose mean
is nearest, one lattice step along the larger coordinate gap; the world
rule replaces a move into a wall.

    build/aia eval --sizes 10x10 --seeds 20 --policies greedy,igbnet --out renders/compare
    PYTHONPATH=build/python examples/python/heuristic_eval.py renders/compare 10x10 20
"""
import sys

import numpy as np

import aia

LEFT, RIGHT, UP, DOWN = 0, 1, 2, 3


def nearest_target(mission):
    s = mission.state()  # what the robots know; no ground truth here
    moves = np.zeros(mission.num_robots, dtype=np.int64)
    for i in range(mission.num_robots):
        open_ = s["det"][i] >= s["eps"]
        if not open_.any():
            continue
        gaps = s["mean"][i][open_] - s["positions"][i]
        dx, dy = gaps[np.argmin(np.hypot(gaps[:, 0], gaps[:, 1]))]
        if abs(dx) >= abs(dy):
            moves[i] = RIGHT if dx > 0 else LEFT
        else:
            moves[i] = UP if dy > 0 else DOWN
    return moves


if __name__ == "__main__":
    if len(sys.argv) > 4 or any(a.startswith("-") for a in sys.argv[1:]):
        print("usage: heuristic_eval.py [OUT_DIR [SIZE [SEEDS]]] (default "
              "renders/compare 10x10 20)\n" + __doc__, file=sys.stderr)
        sys.exit(0 if sys.argv[1:2] in (["-h"], ["--help"]) else 2)
    out = sys.argv[1] if len(sys.argv) > 1 else "renders/compare"
    size = sys.argv[2] if len(sys.argv) > 2 else "10x10"
    seeds = int(sys.argv[3]) if len(sys.argv) > 3 else 20
    rows = aia.evaluate(nearest_target, [size], seeds, out=out,
                        name="nearest_target")
    print(f"{'policy':16} {'success':>8} {'flowtime increase':>18}")
    for r in rows:
        inc = r["flowtime_increase"]
        print(f"{r['policy']:16} {r['success_rate']:8.2f} "
              f"{'-' if inc is None else format(inc, '.3f'):>18}")
