#!/usr/bin/python3
"""How each phase of a decision step grows with the team (issue 19, Scale).

Runs `aia bench` once per team size N (N robots, N targets) in worlds that
grow with the team: side = 20 sqrt(max(N, 40) / 40) m (the paper's 20 x 20 m
world up to 40 robots, then 10 m^2 per robot: 100 x 100 m at 1000) with the
paper's box density, 0.075 per m^2 (30 boxes at 20 m, 750 at 100 m). Each run
is its own process, timed by /usr/bin/time for its peak memory. Writes
OUT/scale.csv (one row per size: ms per step and per phase, physics being
the time inside mj_step; mj_step/s and contacts per mj_step inside episodes
and mujoco-testspeed's on the same model; peak RSS), OUT/scale.png
(ms per phase against N on log axes) and OUT/scale.md (the table, with each
phase's growth order: the least-squares slope of log ms against log N from
80 robots on, and physics split into ms per mj_step call and calls per
decision step, each with its growth). Every finished size is kept; a second call goes on.

Usage:
  tools/bench_scale.py --out DIR [--sizes 10,80,200,500,1000] [--policy igbnet]
                       [--steps 10] [--repeats 3] [--policy-threads 1]
                       [--aia build/aia] [--set KEY=VALUE ...]
"""

import argparse
import csv
import fcntl
import json
import math
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tool_io import pyplot, run  # noqa: E402

plt = pyplot()  # headless; where matplotlib is missing, its first use says so

PHASES = ["physics", "sensing", "fusion", "policy", "rest"]
COLUMNS = (["robots", "side_m", "boxes", "steps_per_s", "ms_step"] + PHASES +
           ["mj_step_pct", "mj_step_per_s", "testspeed_per_s", "contacts",
            "testspeed_contacts", "peak_rss_mib", "wall_s"])


def world(n):
    side = 20.0 * math.sqrt(max(n, 40) / 40.0)
    return side, int(round(0.075 * side * side))


def run_size(args, n):
    side, boxes = world(n)
    cmd = ["/usr/bin/time", "-f", "%M %e", args.aia, "bench", "--sizes", f"{n}x{n}",
           "--steps", str(args.steps), "--repeats", str(args.repeats),
           "--policy", args.policy, "--seed", str(args.seed),
           "--policy-threads", str(args.policy_threads),
           "--set", f"workspace.size=[{side:g},{side:g}]",
           "--set", f"workspace.obstacles.random.count={boxes}"]
    for kv in args.set:
        cmd += ["--set", kv]
    print(f"[bench_scale] {n}x{n} in {side:g} x {side:g} m, {boxes} boxes ...",
          file=sys.stderr, flush=True)
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        # aia's own error line (the last of its stderr; /usr/bin/time adds
        # its line after it).
        lines = [ln for ln in p.stderr.splitlines()
                 if ln and not ln.startswith("Command exited")]
        why = next((ln for ln in reversed(lines) if ln.startswith("error:")),
                   lines[-1] if lines else f"exit {p.returncode}")
        raise RuntimeError(f"{n}x{n}: {why.removeprefix('error: ')}")
    row = None
    for line in p.stdout.splitlines():
        f = line.split()
        if f and f[0] == f"{n}x{n}":
            row = f
    if row is None:
        raise RuntimeError(f"no result row in:\n{p.stdout}")
    rss_kib, wall = p.stderr.strip().splitlines()[-1].split()
    values = [float(x.rstrip("%")) for x in row[1:]]
    rate, ms, phys, sens, fus, pol, rest, share, mj, ts, con, ts_con = values
    return {"robots": n, "side_m": f"{side:.1f}", "boxes": boxes,
            "steps_per_s": rate, "ms_step": ms, "physics": phys, "sensing": sens,
            "fusion": fus, "policy": pol, "rest": rest, "mj_step_pct": share,
            "mj_step_per_s": mj, "testspeed_per_s": ts, "contacts": con,
            "testspeed_contacts": ts_con,
            "peak_rss_mib": round(int(rss_kib) / 1024.0, 1), "wall_s": float(wall)}


class Damaged(Exception):
    """A file of the folder that this tool did not write as it is."""


def read_rows(path):
    if not os.path.exists(path):
        return {}
    try:
        with open(path, newline="", encoding="utf-8") as f:
            # rows of an older layout (columns missing) are measured again
            return {int(r["robots"]): r for r in csv.DictReader(f)
                    if all(r.get(k) not in (None, "") for k in COLUMNS)}
    except (OSError, UnicodeDecodeError, ValueError, csv.Error) as e:
        raise Damaged(f"{path}: cannot be read as this tool's table "
                      f"({getattr(e, 'strerror', None) or e}); move it away "
                      "to measure again") from None


def write_rows(path, rows):
    tmp = f"{path}.tmp.{os.getpid()}"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for n in sorted(rows):
            w.writerow({k: rows[n][k] for k in COLUMNS})
    os.replace(tmp, path)


def ms_per_mj_step(r):
    """Milliseconds per mj_step call inside the episodes."""
    rate = float(r["mj_step_per_s"])
    return 1000.0 / rate if rate > 0 else 0.0


def mj_steps_per_decision(r):
    """mj_step calls per decision step: physics time over time per call.
    A lockstep decision step lasts until the team's last robot arrives, so
    this grows where some robots take longer (blocked, stalled)."""
    per = ms_per_mj_step(r)
    return float(r["physics"]) / per if per > 0 else 0.0


def slope(rows, key):
    """Growth order: least-squares slope of log ms against log N over the
    sizes from 80 robots on (all sizes when fewer than two reach 80). `key`
    is a column or a function of a row."""
    value = key if callable(key) else (lambda r: float(r[key]))
    ns = [n for n in sorted(rows) if n >= 80]
    if len(ns) < 2:
        ns = sorted(rows)
    pts = [(math.log(n), math.log(value(rows[n]))) for n in ns
           if value(rows[n]) > 0]
    if len(pts) < 2:
        return float("nan")
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sxx


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--sizes", default="10,80,200,500,1000",
                        help="team sizes N (N robots, N targets), comma-separated")
    parser.add_argument("--policy", default="igbnet", help="policy to time (default igbnet)")
    parser.add_argument("--steps", type=int, default=10, help="decision steps per run")
    parser.add_argument("--repeats", type=int, default=3, help="runs per size (aia bench reports the median run)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the worlds")
    parser.add_argument("--policy-threads", type=int, default=1,
                        help="threads of a learned policy and of a large "
                             "team's fusion (aia bench's --policy-threads; "
                             "physics has one)")
    parser.add_argument("--aia", default="build/aia", help="the aia binary")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="another scenario key for every size, e.g. "
                             "communication.mode=range (repeatable)")
    args = parser.parse_args(argv)
    try:
        sizes = sorted({int(s) for s in args.sizes.split(",") if s})
    except ValueError:
        print(f"error: --sizes: '{args.sizes}' is not a list of whole numbers",
              file=sys.stderr)
        return 2
    if not sizes or min(sizes) < 1:
        print("error: --sizes: give team sizes of at least 1", file=sys.stderr)
        return 2
    for name in ("policy_threads", "steps", "repeats"):
        if getattr(args, name) < 1:
            print(f"error: --{name.replace('_', '-')}: give at least 1, got "
                  f"{getattr(args, name)}", file=sys.stderr)
            return 2
    if args.seed < 0:
        print(f"error: --seed: give a seed of 0 or more, got {args.seed}",
              file=sys.stderr)
        return 2
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        print(f"error: --out: {args.out} is a file, not a folder", file=sys.stderr)
        return 2
    os.makedirs(args.out, exist_ok=True)
    # One call at a time per folder: two would each rewrite scale.csv from
    # their own rows (the lock ends with the process, however it ends).
    lock = open(os.path.join(args.out, ".lock"), "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        print(f"error: --out: {args.out} is in use by another bench_scale.py "
              "(it holds the folder's lock); wait for it or use another "
              "folder", file=sys.stderr)
        return 2
    try:
        return measure(args, sizes)
    except Damaged as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ninterrupted: the sizes measured are kept; run the same "
              "command again to go on", file=sys.stderr)
        return 130


def measure(args, sizes):
    # A folder holds one configuration: resuming with another would mix rows.
    settings = {"policy": args.policy, "set": args.set, "steps": args.steps,
                "repeats": args.repeats, "seed": args.seed}
    if args.policy_threads != 1:  # folders of one thread stay resumable
        settings["policy_threads"] = args.policy_threads
    settings_path = os.path.join(args.out, "settings.json")
    if os.path.exists(settings_path):
        try:
            with open(settings_path, encoding="utf-8") as f:
                old = json.load(f)
        except (OSError, UnicodeDecodeError, ValueError) as e:
            raise Damaged(f"{settings_path}: cannot be read "
                          f"({getattr(e, 'strerror', None) or e}); move it "
                          "away to measure again") from None
        if old != settings:
            print(f"error: {settings_path}: this folder was measured with {old}, "
                  f"not {settings}; use another --out", file=sys.stderr)
            return 2
    path = os.path.join(args.out, "scale.csv")
    rows = read_rows(path)
    if any(n not in rows for n in sizes) and \
            not (os.path.isfile(args.aia) and os.access(args.aia, os.X_OK)):
        print(f"error: --aia: {args.aia} is not an executable (build it: "
              "tools/bootstrap.sh)", file=sys.stderr)
        return 2
    for n in sizes:
        if n in rows:
            continue
        try:
            rows[n] = run_size(args, n)
        except RuntimeError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        # The settings go with the first row measured, so that a call that
        # measured nothing (a bad policy, say) leaves the folder open.
        if not os.path.isfile(settings_path):
            tmp = f"{settings_path}.tmp.{os.getpid()}"
            with open(tmp, "w") as f:
                json.dump(settings, f)
            os.replace(tmp, settings_path)
        write_rows(path, rows)
    rows = {n: rows[n] for n in sizes}

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ns = sorted(rows)
    for key in ["ms_step"] + PHASES:
        ys = [float(rows[n][key]) for n in ns]
        label = "whole step" if key == "ms_step" else key
        ax.plot(ns, ys, marker="o", linewidth=2.2 if key == "ms_step" else 1.2,
                label=f"{label} (~N^{slope(rows, key):.2f})")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("robots N (= targets)")
    ax.set_ylabel("ms per decision step")
    extra = "".join(f", {kv}" for kv in args.set)
    ax.set_title(f"aia bench, policy {args.policy}{extra}, worlds growing with N",
                 fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(args.out, "scale.png")
    fig.savefig(f"{png}.tmp.{os.getpid()}.png", dpi=120)
    os.replace(f"{png}.tmp.{os.getpid()}.png", png)

    md = os.path.join(args.out, "scale.md")
    with open(f"{md}.tmp.{os.getpid()}", "w") as f:
        f.write("| N x N | world | ms/step | physics | sensing | fusion | policy | rest "
                "| mj_step/s (episodes) | testspeed/s "
                "| contacts (episodes / testspeed) | peak RSS (MiB) |\n")
        f.write("|---|---|---|---|---|---|---|---|---|---|---|---|\n")
        for n in ns:
            r = rows[n]
            f.write(f"| {n}x{n} | {r['side_m']} m, {r['boxes']} boxes | "
                    f"{float(r['ms_step']):.1f} | " +
                    " | ".join(f"{float(r[p]):.1f}" for p in PHASES) +
                    f" | {float(r['mj_step_per_s']):.0f} | {float(r['testspeed_per_s']):.0f}"
                    f" | {float(r['contacts']):.1f} / {float(r['testspeed_contacts']):.1f}"
                    f" | {float(r['peak_rss_mib']):.0f} |\n")
        fitted = "N = 80" if sum(n >= 80 for n in rows) >= 2 else "all sizes"
        f.write(f"| growth (fitted from {fitted}) | | " +
                " | ".join(f"N^{slope(rows, k):.2f}" for k in ["ms_step"] + PHASES) +
                " | | | | |\n")
        # Physics per decision step = (ms per mj_step) x (mj_step calls per
        # decision step): MuJoCo's own cost and how long the step lasts.
        f.write("\nphysics = ms per mj_step x mj_step calls per decision step: " +
                ", ".join(f"{n}: {ms_per_mj_step(rows[n]):.3f} x "
                          f"{mj_steps_per_decision(rows[n]):.1f}" for n in ns) +
                f"; growth N^{slope(rows, ms_per_mj_step):.2f} x "
                f"N^{slope(rows, mj_steps_per_decision):.2f}\n")
    os.replace(f"{md}.tmp.{os.getpid()}", md)
    print(md)
    return 0


if __name__ == "__main__":
    run(main)
