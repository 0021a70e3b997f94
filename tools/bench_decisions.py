#!/usr/bin/python3
"""What asynchronous decisions cost the simulation (issue 40): wall time per
simulated second, mission.decisions async against lockstep, on the same
world and seed, run in turn (lockstep, async, lockstep, ...) so that a noisy
machine hits both alike; the ratio is the median of the pairs' ratios.

Each condition runs `aia run` with the random policy (it costs nothing) for
--steps decision steps without stopping at success, and reads
diagnostics.json: the time inside mj_step (physics) and the whole step
without the policy (physics, sensing, fusion, the episode's loop), each
divided by the simulated seconds.

Usage:
  tools/bench_decisions.py --out DIR [--conditions crowd80,open10,point320]
                           [--repeats 3] [--steps 12] [--aia build/aia]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys

CONDITIONS = {
    "open10": "workspace: {obstacles: {random: {count: 30}}}\n"
              "robots: {count: 10, model: diff_drive}\ntargets: {count: 10}\n",
    "crowd80": "workspace: {obstacles: {random: {count: 30}}}\n"
               "robots: {count: 80, model: diff_drive}\ntargets: {count: 80}\n",
    "point320": "workspace: {size: [40, 40], obstacles: {random: {count: 120}}}\n"
                "robots: {count: 320}\ntargets: {count: 320}\n",
}
MODES = ("lockstep", "async")


def per_second(aia, scenario, mode, folder):
    """(physics ms, step-without-policy ms) per simulated second."""
    cmd = [aia, "run", scenario, "--policy", "random", "--seed", "5", "--out", folder,
           "--quiet", "--set", f"mission.decisions={mode}"]
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        sys.exit(f"error: {' '.join(cmd)} exited with {done.returncode}: {done.stderr.strip()}")
    d = json.load(open(os.path.join(folder, "diagnostics.json")))
    wall, sim = d["wall_seconds"], d["physics"]["sim_seconds"]
    return 1000 * wall["physics"] / sim, 1000 * (wall["total"] - wall["policy"]) / sim


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True, help="folder for the scenarios and runs")
    p.add_argument("--conditions", default=",".join(CONDITIONS),
                   help="comma-separated: " + ", ".join(CONDITIONS))
    p.add_argument("--repeats", type=int, default=3, help="pairs per condition (3)")
    p.add_argument("--steps", type=int, default=12, help="decision steps per run (12)")
    p.add_argument("--aia", default="build/aia", help="the aia binary (build/aia)")
    a = p.parse_args(argv)
    names = a.conditions.split(",")
    bad = [n for n in names if n not in CONDITIONS]
    if bad or a.repeats < 1 or a.steps < 1:
        print(f"error: --conditions: {','.join(bad)} is not one of {', '.join(CONDITIONS)}"
              if bad else "error: --repeats and --steps must be at least 1", file=sys.stderr)
        return 2
    if not os.access(a.aia, os.X_OK):
        print(f"error: {a.aia}: not built (run tools/bootstrap.sh)", file=sys.stderr)
        return 2
    os.makedirs(a.out, exist_ok=True)
    print("| condition | physics ms / simulated s, lockstep | async | ratio | without policy, "
          "lockstep | async | ratio |")
    print("|---|---|---|---|---|---|---|")
    for name in names:
        scenario = os.path.join(a.out, name + ".yaml")
        with open(scenario, "w") as f:
            f.write(f"name: {name}\n{CONDITIONS[name]}"
                    f"mission: {{max_steps: {a.steps}, stop_at_success: false}}\n")
        runs = {m: [] for m in MODES}
        for r in range(a.repeats):
            for m in MODES:
                print(f"[bench_decisions] {name} {m} {r + 1}/{a.repeats}", file=sys.stderr,
                      flush=True)
                runs[m].append(per_second(a.aia, scenario, m,
                                          os.path.join(a.out, f"{name}.{m}.{r}")))
        cells = []
        for k in (0, 1):
            lock = statistics.median(x[k] for x in runs["lockstep"])
            asyn = statistics.median(x[k] for x in runs["async"])
            ratio = statistics.median(y[k] / x[k] for x, y in zip(runs["lockstep"], runs["async"]))
            cells += [f"{lock:.1f}", f"{asyn:.1f}", f"{ratio:.2f}"]
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from tool_io import run  # one error line for bad paths, not a traceback
    run(main)
