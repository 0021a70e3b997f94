#!/usr/bin/python3
"""The paper's experiments (section V; ../shared/docs/SPEC.md section 9), one
command each, built on `build/aia`:

  scalability  success rate and flowtime increase against N x M (the paper's
               figure 2), error bars from the seeds: `aia eval` on 7 sizes x
               100 seeds (resumable; `--mpi K` runs it under mpirun).
  tracking     the localization mission (5 robots, 3 static targets, dense
               clutter, eps 1.8e-2) and the tracking mission (2 robots, one
               static and one moving target): det Sigma per robot and per
               target over time with the threshold, the estimate's RMSE and
               NEES over time, and a video of each.
  robustness   5 robots, 5 targets, r_com = 4 m, Poisson(1) packet loss, a
               random robot failing at step 10, on 50 worlds, against the
               same worlds with a static full graph and no failure: the mean
               mission time's increase (the paper: +71.51 %), and a video.

  generalization
               every policy on worlds unlike the training ones, seeds from
               931000: team sizes 2x2 to 80x80, 20 to 40 m at constant box
               density, 0 and 60 boxes, sensor range 1.5 and 3 m, a range
               graph with packet loss (aia eval, F* from the expert), the 12
               hand-made worlds of scenarios/long, the robustness scenario
               and a moving target (aia run): success, flowtime increase (or
               mean steps), reversal share, with standard errors.
  motion       every policy with point and with wheeled (robots.model
               diff_drive) robots on the same worlds (open clutter, rooms and
               doors, an 80-robot crowd): decision steps, simulated seconds,
               and where the robots' time went (driving, turning in place,
               blocked, waiting for the step's slowest robot).

Each writes, under --out: CSV, summary.json and PNG plots (and MP4 videos);
--quick shrinks it to about a minute. Every piece already written is kept:
run the command again after an interruption and it goes on.

Usage:
  tools/experiment.py scalability --out results/scalability [--quick] [--mpi 2]
  tools/experiment.py tracking --out results/tracking [--quick]
  tools/experiment.py robustness --out results/robustness [--quick]
  tools/experiment.py generalization --out results/generalization [--quick]
  tools/experiment.py motion --out results/motion [--quick]
"""

import argparse
import concurrent.futures
import csv
import io
import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import plot_trace  # noqa: E402
from tool_io import BadInput, os_error, pyplot, save_figure  # noqa: E402

plt = pyplot()  # headless; where matplotlib is missing, its first use says so

SIZES = ["10x10", "20x20", "30x30", "40x40", "50x50", "60x60", "80x80"]
POLICIES = ["expert", "igbnet", "decsb", "greedy", "random"]  # expert: C-SB in the loop
POLICY_COLOR = {"igbnet": "C0", "decsb": "C1", "greedy": "C2", "random": "C3", "expert": "C4"}


def policy_color(policy, _others={}):
    """The built-ins' fixed colours; another policy (one scored from Python,
    say) the next colour none of them uses."""
    if policy in POLICY_COLOR:
        return POLICY_COLOR[policy]
    if policy not in _others:
        _others[policy] = "C%d" % (len(POLICY_COLOR) + len(_others) % 5)
    return _others[policy]


class Failure(Exception):
    pass


class AlreadySaid(Exception):
    """A child failed and printed its own error line: exit with its code."""

    def __init__(self, code):
        super().__init__(code)
        self.code = code


class Usage(Exception):
    """Bad arguments found once the experiment knows its pieces: exit 2."""


def write_atomic(path, text):
    tmp = f"{path}.tmp.{os.getpid()}"
    with open(tmp, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def write_json(path, data):
    write_atomic(path, json.dumps(data, indent=2, sort_keys=False) + "\n")


def write_csv(path, header, rows):
    """RFC 4180 CSV (a field with a comma is quoted: condition names have
    them), floats to 6 significant digits, None as an empty field."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow(["" if v is None else (f"{v:.6g}" if isinstance(v, float) else str(v))
                    for v in r])
    write_atomic(path, out.getvalue())


def run(cmd, quiet=False):
    """Runs a command; a failure stops the experiment with its stderr."""
    if not quiet:
        print("+ " + " ".join(cmd), flush=True)
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise Failure(f"{' '.join(cmd)} exited with {p.returncode}:\n{p.stderr.strip()}")
    return p.stdout


def save(fig, path, inputs=()):
    """The figure, written atomically (a kill never leaves half a PNG)."""
    save_figure(fig, path, 110, inputs)
    print(f"wrote {path}", flush=True)


def finished(summary_path):
    """Whether a run of `aia run` or `aia render` finished: its summary is
    there and does not say it was interrupted (Ctrl-C writes the steps done
    so far with "interrupted": true; such a run is run again)."""
    try:
        with open(summary_path) as f:
            return not json.load(f).get("interrupted", False)
    except (OSError, ValueError):
        return False


def video_finished(video):
    """A video of `aia render` that was not cut short (FILE.summary.json)."""
    return os.path.isfile(video) and \
        finished(os.path.splitext(video)[0] + ".summary.json")


# Keys of the arguments that change a folder's results without changing its
# runs' folder names: a second call with other values would mix them.
SETTINGS = ("set", "policy", "scenario", "max_steps", "quick")


def check_settings(args):
    """OUT/settings.json holds the settings the folder was made with; a call
    with others is refused (Usage) rather than mixed into it."""
    settings = {"experiment": args.experiment,
                **{k: getattr(args, k) for k in SETTINGS if hasattr(args, k)}}
    if "scenario" in settings:
        settings["scenario"] = os.path.abspath(settings["scenario"])
    path = os.path.join(args.out, "settings.json")
    if os.path.isfile(path):
        try:
            with open(path) as f:
                old = json.load(f)
        except (OSError, ValueError) as e:
            raise Usage(f"{path}: not readable ({e}); use another --out")
        if old != settings:
            changed = ", ".join(
                f"{k}: {old.get(k)!r} -> {settings.get(k)!r}"
                for k in sorted(set(old) | set(settings))
                if old.get(k) != settings.get(k))
            raise Usage(f"{path}: this folder was made with other settings "
                        f"({changed}); its runs would be mixed with these: "
                        "use another --out")
    else:
        write_json(path, settings)


# ---------------------------------------------------------------- scalability


def load_runs(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def outcome(r):
    """A runs.csv row's success (0 or 1) and flowtime increase (F - F*) / F*,
    a failure counting F = 3 F* as in aia eval's summary."""
    fstar = int(r["fstar"])
    denom = max(fstar, 1)
    success = r["success"] == "1"
    f = int(r["flowtime"]) if success else 3 * denom
    return (1.0 if success else 0.0), (f - fstar) / denom


def mission_seconds(r):
    """A runs.csv row's simulated seconds (until success, else until the run
    stopped at 3 F*); None for rows of an aia without the column."""
    value = r.get("mission_seconds")
    return float(value) if value not in (None, "") else None


def mean_se(xs):
    xs = [x for x in xs if x is not None]
    n = len(xs)
    if n == 0:
        return None, None
    m = sum(xs) / n
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (n - 1)) if n > 1 else 0.0
    return m, sd / math.sqrt(n)


def scalability_table(runs, sizes, policies):
    """Per size and policy: n, success rate and flowtime increase, each with
    its standard error over the seeds (a failure counts F = 3 F*, as in
    aia eval's summary)."""
    table = []
    for size in sizes:
        for policy in policies:
            rs = [r for r in runs if r["size"] == size and r["policy"] == policy
                  and int(r["fstar"]) >= 0]
            n = len(rs)
            if n == 0:
                continue
            succ = [outcome(r)[0] for r in rs]
            inc = [outcome(r)[1] for r in rs]
            p = sum(succ) / n
            mean_inc = sum(inc) / n
            sd_inc = math.sqrt(sum((x - mean_inc) ** 2 for x in inc) / (n - 1)) if n > 1 else 0.0
            wall = sum(float(r["wall_s"]) for r in rs)
            secs, secs_se = mean_se([mission_seconds(r) for r in rs])
            table.append({
                "size": size, "policy": policy, "instances": n,
                "success_rate": p, "success_se": math.sqrt(p * (1 - p) / n),
                "flowtime_increase": mean_inc, "flowtime_increase_se": sd_inc / math.sqrt(n),
                "mission_seconds": secs, "mission_seconds_se": secs_se,
                "policy_wall_s": wall,
            })
    return table


def plot_scalability(table, sizes, path, title, inputs=()):
    fig, (ax_s, ax_f) = plt.subplots(1, 2, figsize=(11, 4))
    for policy in dict.fromkeys(r["policy"] for r in table):
        rs = [r for r in table if r["policy"] == policy]
        x = [sizes.index(r["size"]) for r in rs]
        kw = dict(label=policy, color=policy_color(policy), marker="o", capsize=3)
        ax_s.errorbar(x, [100 * r["success_rate"] for r in rs],
                      yerr=[100 * r["success_se"] for r in rs], **kw)
        ax_f.errorbar(x, [100 * r["flowtime_increase"] for r in rs],
                      yerr=[100 * r["flowtime_increase_se"] for r in rs], **kw)
    for ax, label in ((ax_s, "success rate (%)"), (ax_f, "flowtime increase (%)")):
        ax.set_xticks(range(len(sizes)))
        ax.set_xticklabels(sizes)
        ax.set_xlabel("robots x targets")
        ax.set_title(label)
        ax.grid(alpha=0.3)
    ax_s.set_ylim(-5, 105)
    ax_s.legend()
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save(fig, path, inputs)


def canonical_size(text):
    """"RxT" as aia eval writes it (whole numbers without leading zeros);
    anything else as given, for aia eval to refuse."""
    r, x, t = text.partition("x")
    if x and r.isdigit() and t.isdigit():
        return f"{int(r)}x{int(t)}"
    return text


def scalability(args):
    sizes = args.sizes or (["10x10", "20x20"] if args.quick else SIZES)
    seeds = args.seeds or (3 if args.quick else 100)
    policies = args.policies or POLICIES
    eval_dir = os.path.join(args.out, "eval")
    cmd = [args.aia, "eval", "--sizes", ",".join(sizes), "--seeds", str(seeds),
           "--seed-base", str(args.seed_base), "--policies", ",".join(policies),
           "--out", eval_dir, "--threads", str(args.threads)]
    for s in args.set:
        cmd += ["--set", s]
    if args.mpi > 1:
        cmd = ["mpirun", "-n", str(args.mpi)] + cmd
    t0 = time.time()
    print("+ " + " ".join(cmd), flush=True)
    rc = subprocess.run(cmd).returncode  # its progress line shows
    if rc == 2:  # bad input: aia eval said what, in one line
        raise AlreadySaid(2)
    if rc != 0:
        raise Failure("aia eval failed (see above)")
    wall = time.time() - t0
    runs = load_runs(os.path.join(eval_dir, "runs.csv"))
    runs = [r for r in runs if args.seed_base <= int(r["seed"]) < args.seed_base + seeds]
    table = scalability_table(runs, sizes, policies)
    header = ["size", "policy", "instances", "success_rate", "success_se",
              "flowtime_increase", "flowtime_increase_se", "mission_seconds",
              "mission_seconds_se", "policy_wall_s"]
    write_csv(os.path.join(args.out, "scalability.csv"), header,
              [[r[h] for h in header] for r in table])
    no_plan = {s: sum(1 for r in runs if r["size"] == s and int(r["fstar"]) < 0) // max(1, len(policies))
               for s in sizes}
    write_json(os.path.join(args.out, "summary.json"), {
        "experiment": "scalability", "sizes": sizes, "seeds": seeds,
        "seed_base": args.seed_base, "policies": policies, "sets": args.set,
        "mpi_ranks": args.mpi, "wall_s_this_call": wall,
        "instances_without_expert_plan": no_plan, "rows": table})
    plot_scalability(table, sizes, os.path.join(args.out, "scalability.png"),
                     f"scalability: {seeds} worlds per size, 20 x 20 m, error bars: 1 s.e.")


# ------------------------------------------------------------------- tracking


def load_estimate(path):
    """estimate.csv -> {target: (steps, error_m, nees)}."""
    out = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            k = int(r["target"])
            s, e, n = out.setdefault(k, ([], [], []))
            s.append(int(r["step"]))
            e.append(float(r["error_m"]))
            n.append(float(r["nees"]))
    return out


def chi2_even_ppf(p, dof):
    """Quantile of chi-square with an even number of degrees of freedom
    (closed-form CDF, bisection)."""
    def cdf(x):
        h = x / 2.0
        term, total = 1.0, 1.0
        for j in range(1, dof // 2):
            term *= h / j
            total += term
        return 1.0 - math.exp(-h) * total
    lo, hi = 0.0, 1000.0
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if cdf(mid) < p else (lo, mid)
    return (lo + hi) / 2


def plot_estimate(est, dof, path, title):
    fig, (ax_e, ax_n) = plt.subplots(1, 2, figsize=(11, 4))
    for k, (s, e, n) in sorted(est.items()):
        ax_e.plot(s, e, label=f"target {k}", color=f"C{k % 10}")
        ax_n.plot(s, n, label=f"target {k}", color=f"C{k % 10}")
    lo, hi = chi2_even_ppf(0.025, dof), chi2_even_ppf(0.975, dof)
    ax_n.axhspan(lo, hi, color="0.85", zorder=0, label=f"chi2({dof}) 95 %")
    ax_n.axhline(dof, color="0.5", linestyle="--", linewidth=1, label=f"E = {dof}")
    ax_e.set_title("position error of the team's best estimate (m)")
    ax_n.set_title("NEES of the team's best estimate")
    for ax in (ax_e, ax_n):
        ax.set_yscale("log")
        ax.set_xlabel("decision step t")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save(fig, path)


def mission(args, name, scenario, extra):
    """One mission: aia run, its plots, and its video."""
    folder = os.path.join(args.out, name)
    base = [scenario, "--policy", args.policy] + extra
    for s in args.set:
        base += ["--set", s]
    if not finished(os.path.join(folder, "summary.json")):
        run([args.aia, "run"] + base + ["--out", folder, "--quiet"])
    summary = json.load(open(os.path.join(folder, "summary.json")))
    trace = plot_trace.load_trace(os.path.join(folder, "trace.csv"))
    ns = argparse.Namespace(eps=None, title=None)
    fig = plot_trace.figure_uncertainty(trace, summary, ns)
    save(fig, os.path.join(folder, "uncertainty.png"))
    est = load_estimate(os.path.join(folder, "estimate.csv"))
    # The shipped missions' targets are positions (2-D states); NEES of a
    # consistent filter is then chi-square with 2 degrees of freedom.
    dof = 2
    plot_estimate(est, dof, os.path.join(folder, "estimate.png"),
                  f"{name}: {args.policy}, seed {summary['seed']}")
    video = os.path.join(folder, f"{name}.mp4")
    if not args.no_video and not video_finished(video):
        size = ["--width", "320", "--height", "240"] if args.quick else []
        run([args.aia, "render"] + base + size + ["--heatmap", "0", "--out", video, "--quiet"])
    band = chi2_even_ppf(0.025, dof), chi2_even_ppf(0.975, dof)
    per_target = {}
    for k, (s, e, n) in sorted(est.items()):
        per_target[str(k)] = {
            "rmse_m": math.sqrt(sum(x * x for x in e) / len(e)),
            "final_error_m": e[-1],
            "mean_nees": sum(n) / len(n),
            "nees_in_95_band": sum(1 for x in n if band[0] <= x <= band[1]) / len(n),
        }
    keys = ("scenario", "policy", "seed", "robots", "targets", "success", "flowtime",
            "steps", "eps", "localized_share")
    return {**{k: summary.get(k) for k in keys}, "targets_estimate": per_target,
            "video": None if args.no_video else os.path.basename(video)}


def tracking(args):
    steps = ["--max-steps", "40"] if args.quick else []
    results = {
        "localization": mission(args, "localization",
                                os.path.join(ROOT, "scenarios/localization.yaml"), steps),
        "tracking": mission(args, "tracking", os.path.join(ROOT, "scenarios/tracking.yaml"),
                            steps),
    }
    rows = []
    for name, r in results.items():
        for k, t in r["targets_estimate"].items():
            rows.append([name, r["policy"], r["seed"], int(r["success"]), r["flowtime"],
                         r["steps"], r["localized_share"], k, t["rmse_m"], t["final_error_m"],
                         t["mean_nees"], t["nees_in_95_band"]])
    write_csv(os.path.join(args.out, "tracking.csv"),
              ["mission", "policy", "seed", "success", "flowtime", "steps", "localized_share",
               "target", "rmse_m", "final_error_m", "mean_nees", "nees_in_95_band"], rows)
    write_json(os.path.join(args.out, "summary.json"),
               {"experiment": "tracking", "quick": args.quick, "missions": results})


# ----------------------------------------------------------------- robustness

NOMINAL = ["--set", "communication.mode=full", "--set", "communication.packet_loss_lambda=0",
           "--set", "communication.failures=[]"]


def robustness_run(args, variant, seed):
    folder = os.path.join(args.out, "runs", f"{variant}-{seed}")
    path = os.path.join(folder, "summary.json")
    if not finished(path):
        cmd = [args.aia, "run", args.scenario, "--policy", args.policy, "--seed", str(seed),
               "--out", folder, "--quiet"]
        if variant == "nominal":
            cmd += NOMINAL
        for s in args.set:
            cmd += ["--set", s]
        run(cmd, quiet=True)
    s = json.load(open(path))
    return {"variant": variant, "seed": seed, "success": bool(s["success"]),
            "flowtime": s["flowtime"], "steps": s["steps"], "max_steps": s["max_steps"],
            "mission_seconds": s.get("mission_seconds"),
            "failed_robots": s.get("failed_robots", [])}


def robustness(args):
    runs_n = args.seeds or (5 if args.quick else 50)
    seeds = list(range(args.seed_base, args.seed_base + runs_n))
    jobs = [(v, s) for s in seeds for v in ("nominal", "faults")]
    results = []
    t0 = time.time()
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(robustness_run, args, v, s) for v, s in jobs]
        try:
            for i, f in enumerate(concurrent.futures.as_completed(futures), 1):
                results.append(f.result())
                print(f"\r[robustness] {i}/{len(jobs)} runs", end="", file=sys.stderr,
                      flush=True)
        except BaseException:
            for f in futures:  # finished runs stay on disk for the next call
                f.cancel()
            raise
    print(file=sys.stderr)
    wall = time.time() - t0
    results.sort(key=lambda r: (r["seed"], r["variant"]))

    def mission_time(r):  # a run that never succeeds counts its whole horizon
        return r["flowtime"] if r["success"] else r["max_steps"]

    by = {v: [r for r in results if r["variant"] == v] for v in ("nominal", "faults")}
    stats = {}
    for v, rs in by.items():
        times = [mission_time(r) for r in rs]
        stats[v] = {"runs": len(rs), "success_rate": sum(r["success"] for r in rs) / len(rs),
                    "mean_mission_time": sum(times) / len(times),
                    # simulated seconds (a failure: its whole horizon)
                    "mean_mission_seconds": mean_se([r["mission_seconds"] for r in rs])[0]}
    both = [(mission_time(a), mission_time(b)) for a, b in zip(by["nominal"], by["faults"])
            if a["success"] and b["success"]]
    # A ratio to nominal missions that all succeed at step 0 has no value.
    nominal_time = stats["nominal"]["mean_mission_time"]
    penalty = (stats["faults"]["mean_mission_time"] / nominal_time - 1
               if nominal_time > 0 else None)
    nominal_both = sum(a for a, _ in both)
    penalty_both = (sum(b for _, b in both) / nominal_both - 1
                    if both and nominal_both > 0 else None)
    write_csv(os.path.join(args.out, "robustness.csv"),
              ["seed", "variant", "success", "flowtime", "steps", "mission_time",
               "mission_seconds", "failed_robots"],
              [[r["seed"], r["variant"], int(r["success"]), r["flowtime"], r["steps"],
                mission_time(r), r["mission_seconds"], " ".join(map(str, r["failed_robots"]))]
               for r in results])
    write_json(os.path.join(args.out, "summary.json"), {
        "experiment": "robustness", "scenario": os.path.relpath(args.scenario, ROOT),
        "policy": args.policy, "seeds": seeds, "variants": {
            "faults": "the scenario as written: range graph, Poisson packet loss, a failure",
            "nominal": "the same worlds with a static full graph, no loss, no failure"},
        "stats": stats, "mission_time_increase": penalty,
        "mission_time_increase_both_succeeded": penalty_both,
        "paper_mission_time_increase": 0.7151, "wall_s_this_call": wall})
    increase = "no ratio (the nominal missions took 0 steps)" if penalty is None \
        else f"{100 * penalty:+.1f} %"
    print(f"mission time: nominal {stats['nominal']['mean_mission_time']:.1f}, with faults "
          f"{stats['faults']['mean_mission_time']:.1f} steps: {increase} "
          f"(paper: +71.51 %)")

    fig, (ax_b, ax_s) = plt.subplots(1, 2, figsize=(11, 4))
    ax_b.bar(["static full graph", "range, loss, failure"],
             [stats["nominal"]["mean_mission_time"], stats["faults"]["mean_mission_time"]],
             color=["C2", "C3"])
    ax_b.set_ylabel("mean mission time (steps)")
    ax_b.set_title(f"{args.policy}, {runs_n} worlds: {increase} (paper +71.51 %)")
    x = [mission_time(r) for r in by["nominal"]]
    y = [mission_time(r) for r in by["faults"]]
    ax_s.scatter(x, y, s=14)
    top = max(x + y + [1])
    ax_s.plot([0, top], [0, top], color="0.6", linestyle="--", linewidth=1)
    ax_s.set_xlabel("static full graph (steps)")
    ax_s.set_ylabel("range, loss, failure (steps)")
    ax_s.set_title("per world")
    for ax in (ax_b, ax_s):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, os.path.join(args.out, "robustness.png"))
    video = os.path.join(args.out, "robustness.mp4")
    if not args.no_video and not video_finished(video):
        size = ["--width", "320", "--height", "240", "--max-steps", "40"] if args.quick else []
        cmd = [args.aia, "render", args.scenario, "--policy", args.policy, "--seed",
               str(seeds[0]), "--out", video, "--quiet"] + size
        for s in args.set:
            cmd += ["--set", s]
        run(cmd)

# ------------------------------------------------------------- generalization

GEN_POLICIES = ["igbnet", "greedy", "decsb", "expert"]
GEN_SEED_BASE = 931000  # disjoint from training (datasets) and model selection
BOX_DENSITY = 0.075     # boxes per m^2: the paper's 30 in 20 x 20 m


def gen_conditions(quick):
    """The suite: (name, group, kind, spec). kind "eval": spec is (size,
    [KEY=VALUE]) for aia eval's generated worlds (F* from the expert); kind
    "files": spec is a list of scenario files run with aia run per seed."""
    c = []
    sizes = ["2x2", "10x10"] if quick else ["2x2", "5x5", "10x10", "20x20", "40x40", "80x80"]
    for size in sizes:
        c.append((f"team {size}", "team size", "eval", (size, [])))
    for side in ([30] if quick else [20, 30, 40]):
        boxes = int(round(BOX_DENSITY * side * side))
        c.append((f"{side} m, {boxes} boxes", "workspace at constant density", "eval",
                  ("10x10", [f"workspace.size=[{side},{side}]",
                             f"workspace.obstacles.random.count={boxes}"])))
    if not quick:
        for boxes in [0, 60]:
            c.append((f"{boxes} boxes", "clutter", "eval",
                      ("10x10", [f"workspace.obstacles.random.count={boxes}"])))
        for r in [1.5, 3]:
            c.append((f"sensor range {r:g} m", "sensing", "eval",
                      ("10x10", [f"sensor.range={r:g}"])))
    # Generated structured worlds (workspace.obstacles.generator), each at
    # 10 robots in 30 x 30 m, and small teams in 20 x 20 m.
    gen = ["maze", "rooms"] if quick else ["maze", "rooms", "corridors", "cave"]
    for g in gen:
        c.append((f"{g} 30 m", "generated structured", "eval",
                  ("10x10", ["workspace.size=[30,30]",
                             f"workspace.obstacles.generator.type={g}"])))
    for size, g in ([("3x3", "rooms")] if quick else
                    [("3x3", "rooms"), ("3x3", "maze"), ("5x5", "corridors"),
                     ("5x5", "cave")]):
        c.append((f"{g} 20 m, {size.split('x')[0]} robots", "generated structured",
                  "eval", (size, [f"workspace.obstacles.generator.type={g}"])))
    if not quick:
        # Narrow perfect mazes (passages of 3 lattice points, no loops), the
        # generated kin of the mazes of scenarios/long.
        c.append(("narrow maze 20 m, 4 robots", "generated structured", "eval",
                  ("4x6", ["workspace.obstacles.generator.type=maze",
                           "workspace.obstacles.generator.corridor=1.5",
                           "workspace.obstacles.generator.wall=0.15",
                           "workspace.obstacles.generator.loops=0"])))
    c.append(("range graph 4 m, packet loss 1", "communication", "eval",
              ("10x10", ["communication.mode=range", "communication.range=4",
                         "communication.packet_loss_lambda=1"])))
    long_worlds = sorted(os.path.join(ROOT, "scenarios/long", f)
                         for f in os.listdir(os.path.join(ROOT, "scenarios/long"))
                         if f.endswith(".yaml"))
    # quick: the two smallest hand-made worlds (20 x 20 m)
    small = [w for w in long_worlds if os.path.basename(w) in ("maze20.yaml", "office20.yaml")]
    c.append(("scenarios/long (hand-made worlds)", "structured", "files",
              (small or long_worlds[:2]) if quick else long_worlds))
    if not quick:
        c.append(("robustness scenario", "faults", "files",
                  [os.path.join(ROOT, "scenarios/robustness.yaml")]))
        c.append(("moving target (tracking scenario)", "moving targets", "files",
                  [os.path.join(ROOT, "scenarios/tracking.yaml")]))
    return c


def slug(text):
    return "".join(ch if ch.isalnum() else "_" for ch in text).strip("_")


def gen_eval(args, name, size, sets, seeds, policies):
    """One eval condition: rows per policy (success, flowtime increase,
    reversal share), resumable through aia eval's own resume."""
    folder = os.path.join(args.out, "eval", slug(name))
    cmd = [args.aia, "eval", "--sizes", size, "--seeds", str(seeds), "--seed-base",
           str(args.seed_base), "--policies", ",".join(policies), "--out", folder,
           "--threads", str(args.threads), "--quiet"]
    for kv in sets + args.set:
        cmd += ["--set", kv]
    run(cmd)
    runs = [r for r in load_runs(os.path.join(folder, "runs.csv"))
            if args.seed_base <= int(r["seed"]) < args.seed_base + seeds]
    out = {}
    for policy in policies:
        rs = [r for r in runs if r["policy"] == policy and int(r["fstar"]) >= 0]
        succ = [outcome(r)[0] for r in rs]
        inc = [outcome(r)[1] for r in rs]
        # Mean steps: the flowtime, a failure counting 3 F* (as the increase).
        steps = [int(r["fstar"]) + x * max(int(r["fstar"]), 1) for r, x in zip(rs, inc)]
        out[policy] = {"n": len(rs), "success": succ, "flowtime_increase": inc,
                       "steps": steps, "seconds": [mission_seconds(r) for r in rs],
                       "reversal_share": [float(r["reversal_share"]) for r in rs],
                       "longest_reversal_run": max([int(r["longest_reversal_run"]) for r in rs],
                                                   default=0)}
    return out


def gen_files_run(args, name, scenario, seed, policy):
    folder = os.path.join(args.out, "runs", slug(name),
                          f"{os.path.splitext(os.path.basename(scenario))[0]}.{seed}.{policy}")
    path = os.path.join(folder, "summary.json")
    if not finished(path):
        cmd = [args.aia, "run", scenario, "--policy", policy, "--seed", str(seed),
               "--out", folder, "--quiet"]
        for kv in args.set:
            cmd += ["--set", kv]
        run(cmd, quiet=True)
    s = json.load(open(path))
    d = json.load(open(os.path.join(folder, "diagnostics.json")))
    moves = d.get("moves", {})
    total = moves.get("total", 0)
    return {"success": bool(s["success"]),
            "steps": s["flowtime"] if s["success"] else s["max_steps"],
            "seconds": s.get("mission_seconds"),
            "reversal_share": moves.get("reversals", 0) / total if total else 0.0,
            "longest_reversal_run": moves.get("longest_reversal_run", 0)}


def gen_files(args, name, files, seeds, policies):
    """One condition of scenario files: every file x seed x policy with aia
    run (each run's folder kept: a second call goes on)."""
    jobs = [(f, args.seed_base + i, p) for f in files for i in range(seeds) for p in policies]
    workers = args.jobs
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        results = list(pool.map(lambda j: (j[2], gen_files_run(args, name, *j)), jobs))
    out = {}
    for policy in policies:
        rs = [r for p, r in results if p == policy]
        out[policy] = {"n": len(rs), "success": [1.0 if r["success"] else 0.0 for r in rs],
                       "flowtime_increase": [], "steps": [float(r["steps"]) for r in rs],
                       "seconds": [r["seconds"] for r in rs],
                       "reversal_share": [r["reversal_share"] for r in rs],
                       "longest_reversal_run": max([r["longest_reversal_run"] for r in rs],
                                                   default=0)}
    return out


def plot_generalization(table, path, title):
    conds = list(dict.fromkeys(r["condition"] for r in table))
    policies = list(dict.fromkeys(r["policy"] for r in table))
    fig, axes = plt.subplots(1, 3, figsize=(15, 0.45 * len(conds) + 1.8), sharey=True)
    width = 0.8 / max(1, len(policies))
    for j, policy in enumerate(policies):
        for ax, key in zip(axes, ("success", "flowtime_increase", "reversal_share")):
            ys, vals, errs = [], [], []
            for i, c in enumerate(conds):
                r = next((r for r in table if r["condition"] == c and r["policy"] == policy), None)
                if r is None or r[key] is None:
                    continue
                ys.append(i + (j - (len(policies) - 1) / 2) * width)
                vals.append(r[key])
                errs.append(r[key + "_se"] or 0.0)
            ax.barh(ys, vals, height=width, xerr=errs, color=policy_color(policy),
                    label=policy, capsize=2)
    for ax, label in zip(axes, ("success rate", "flowtime increase (F - F*) / F*",
                                "reversal share of moves")):
        ax.set_title(label, fontsize=10)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(range(len(conds)))
    axes[0].set_yticklabels(conds, fontsize=8)
    axes[0].invert_yaxis()
    axes[0].set_xlim(0, 1.05)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="upper right", ncol=len(labels))
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save(fig, path)


def generalization(args):
    """Every policy on worlds unlike the training ones, fresh seeds."""
    policies = args.policies or (["igbnet", "greedy"] if args.quick else GEN_POLICIES)
    seeds = args.seeds or (2 if args.quick else 30)
    file_seeds = args.file_seeds or (1 if args.quick else 4)
    t0 = time.time()
    conditions = gen_conditions(args.quick)
    if args.only:
        wanted = [w.strip().lower() for w in args.only.split(",") if w.strip()]
        conditions = [c for c in conditions
                      if any(w in c[0].lower() or w in c[1].lower() for w in wanted)]
        if not conditions:
            names = "; ".join(f"{c[0]} ({c[1]})" for c in gen_conditions(args.quick))
            raise Usage(f"--only: '{args.only}' matches no condition (conditions: {names})")
    table = []
    for name, group, kind, spec in conditions:
        print(f"[generalization] {name} ...", flush=True)
        if kind == "eval":
            size, sets = spec
            res = gen_eval(args, name, size, sets, seeds, policies)
        else:
            res = gen_files(args, name, spec, file_seeds, policies)
        for policy, r in res.items():
            succ, succ_se = mean_se(r["success"])
            inc, inc_se = mean_se(r["flowtime_increase"])
            steps, steps_se = mean_se(r["steps"])
            secs, secs_se = mean_se(r["seconds"])
            rev, rev_se = mean_se(r["reversal_share"])
            if succ is not None and len(r["success"]) > 0:
                succ_se = math.sqrt(succ * (1 - succ) / len(r["success"]))
            table.append({"condition": name, "group": group, "policy": policy, "n": r["n"],
                          "success": succ, "success_se": succ_se,
                          "flowtime_increase": inc, "flowtime_increase_se": inc_se,
                          "mean_steps": steps, "mean_steps_se": steps_se,
                          "mission_seconds": secs, "mission_seconds_se": secs_se,
                          "reversal_share": rev, "reversal_share_se": rev_se,
                          "longest_reversal_run": r["longest_reversal_run"]})
    header = ["condition", "group", "policy", "n", "success", "success_se",
              "flowtime_increase", "flowtime_increase_se", "mean_steps", "mean_steps_se",
              "mission_seconds", "mission_seconds_se",
              "reversal_share", "reversal_share_se", "longest_reversal_run"]
    write_csv(os.path.join(args.out, "generalization.csv"), header,
              [[r[h] for h in header] for r in table])

    def cell(r, key, digits=2):
        if r[key] is None:
            return "-"
        return f"{r[key]:.{digits}f} ± {r[key + '_se']:.{digits}f}"
    lines = ["| condition | policy | n | success | flowtime increase | mean steps "
             "| mission seconds | reversal share | longest reversal run |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in table:
        lines.append(f"| {r['condition']} | {r['policy']} | {r['n']} | {cell(r, 'success')} "
                     f"| {cell(r, 'flowtime_increase')} | {cell(r, 'mean_steps', 1)} "
                     f"| {cell(r, 'mission_seconds', 1)} "
                     f"| {cell(r, 'reversal_share', 3)} | {r['longest_reversal_run']} |")
    write_atomic(os.path.join(args.out, "generalization.md"), "\n".join(lines) + "\n")
    write_json(os.path.join(args.out, "summary.json"), {
        "experiment": "generalization", "quick": args.quick, "policies": policies,
        "seeds": seeds, "file_seeds": file_seeds, "seed_base": args.seed_base,
        "sets": args.set, "wall_s_this_call": time.time() - t0, "rows": table})
    plot_generalization(table, os.path.join(args.out, "generalization.png"),
                        f"generalization: seeds from {args.seed_base}, error bars: 1 s.e.")


# --------------------------------------------------------------------- motion

MOTION_MODELS = ["point", "diff_drive"]


def motion_conditions(quick):
    """(name, scenario text): generated worlds where real motion costs in
    different ways: open clutter, doors, a crowd."""
    conds = [("open 20 m: 10 robots",
              "workspace: {obstacles: {random: {count: 30}}}\n"
              "robots: {count: 10}\ntargets: {count: 10}\n"),
             ("rooms 20 m: 5 robots",
              "workspace: {obstacles: {generator: {type: rooms}}}\n"
              "robots: {count: 5}\ntargets: {count: 5}\n")]
    if not quick:
        conds.append(("crowd 20 m: 80 robots",
                      "workspace: {obstacles: {random: {count: 30}}}\n"
                      "robots: {count: 80}\ntargets: {count: 80}\n"))
    return conds


def motion_variant(model, decisions):
    """A robot model with a decision mode: 'diff_drive' (lockstep, the
    folder names of earlier runs) or 'diff_drive async'."""
    return model if decisions == "lockstep" else f"{model} {decisions}"


def motion_run(args, name, scenario, variant, policy, seed):
    model, _, decisions = variant.partition(" ")
    folder = os.path.join(args.out, "runs", slug(name),
                          f"{model}{'.' + decisions if decisions else ''}.{policy}.{seed}")
    path = os.path.join(folder, "summary.json")
    if not finished(path):
        cmd = [args.aia, "run", scenario, "--policy", policy, "--seed", str(seed),
               "--set", f"robots.model={model}", "--out", folder, "--quiet"]
        if decisions:
            cmd += ["--set", f"mission.decisions={decisions}"]
        for kv in args.set:
            cmd += ["--set", kv]
        run(cmd, quiet=True)
    s = json.load(open(path))
    physics = json.load(open(os.path.join(folder, "diagnostics.json")))["physics"]
    use = physics.get("robot_seconds", {})
    # Robot-steps: every robot's completed decisions (async robots make
    # more than the slowest one's steps).
    robot_steps = max(1, sum(physics.get("robot_decisions", [])) or s["steps"] * s["robots"])
    total = sum(use.values()) or 1.0
    return {"success": 1.0 if s["success"] else 0.0,
            "steps": float(s["flowtime"] if s["success"] else s["steps"]),
            "seconds": s["mission_seconds"],
            "decisions": (sum(physics["robot_decisions"]) / max(1, len(physics["robot_decisions"]))
                          if physics.get("robot_decisions") else float(s["steps"])),
            "seconds_per_step": physics["sim_seconds"] / max(1, s["steps"]),
            "stalls": s["robot_stalls"] / robot_steps,
            "timeouts": s["robot_timeouts"] / robot_steps,
            **{f"share_{k}": use.get(k, 0.0) / total
               for k in ("driving", "turning", "blocked", "arrived", "yielding", "staying")}}


def plot_motion(table, path, title):
    """Left: mission seconds per condition, policy and model (error bars 1
    s.e.); right: where the wheeled robots' time went."""
    conds = list(dict.fromkeys(r["condition"] for r in table))
    policies = list(dict.fromkeys(r["policy"] for r in table))
    variants = list(dict.fromkeys(r["model"] for r in table))
    fig, (ax_s, ax_u) = plt.subplots(1, 2, figsize=(13, 0.9 * len(conds) * len(policies) / 2 + 2))
    labels, y = [], 0
    parts = [("share_driving", "driving", "C0"), ("share_turning", "turning in place", "C1"),
             ("share_blocked", "blocked", "C3"), ("share_yielding", "yielding", "C4"),
             ("share_staying", "staying", "C2"), ("share_arrived", "arrived, waiting", "0.7")]
    for c in conds:
        for p in policies:
            rows = {r["model"]: r for r in table if r["condition"] == c and r["policy"] == p}
            hatches = ["", "//", "..", "xx"]
            height = 0.8 / max(1, len(variants))
            for k, variant in enumerate(variants):
                r = rows.get(variant)
                if r is None or r["seconds"] is None:
                    continue
                ax_s.barh(y + height * k, r["seconds"], height=height,
                          xerr=r["seconds_se"] or 0, color=policy_color(p),
                          hatch=hatches[k % len(hatches)], edgecolor="0.2", capsize=2)
                if variant.startswith("diff_drive"):
                    left = 0.0
                    for key, name, colour in parts:
                        ax_u.barh(y + height * k, r[key], left=left, height=height,
                                  color=colour, label=name if y == 0 and k == 1 else None)
                        left += r[key]
            labels.append((y + 0.2, f"{c}\n{p}"))
            y += 1
    for ax in (ax_s, ax_u):
        ax.set_yticks([t for t, _ in labels])
        ax.set_yticklabels([n for _, n in labels], fontsize=7)
        ax.invert_yaxis()
        ax.grid(axis="x", alpha=0.3)
    ax_s.set_xlabel("mission seconds (simulated); bars from the top: " + ", ".join(variants))
    ax_u.set_xlabel("share of the wheeled robots' time")
    ax_u.set_xlim(0, 1)
    ax_u.legend(fontsize=7, loc="lower right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save(fig, path)


def motion(args):
    """Every policy with point and with wheeled (diff_drive) robots on the
    same worlds and seeds: decision steps, simulated seconds, and where the
    robots' time went (driving, turning in place, blocked, waiting for the
    step's slowest robot)."""
    policies = args.policies or (["igbnet", "greedy"] if args.quick else GEN_POLICIES)
    seeds = args.seeds or (2 if args.quick else 10)
    for flag, values, known in (("--models", args.models, MOTION_MODELS),
                                ("--decisions", args.decisions, ["lockstep", "async"])):
        bad = [v for v in values if v not in known]
        if bad or not values:
            raise Usage(f"{flag}: {','.join(bad) or 'nothing'} is not one of "
                        f"{', '.join(known)}")
    t0 = time.time()
    os.makedirs(os.path.join(args.out, "scenarios"), exist_ok=True)
    table = []
    keys = ["success", "steps", "decisions", "seconds", "seconds_per_step", "stalls", "timeouts",
            "share_driving", "share_turning", "share_blocked", "share_arrived",
            "share_yielding", "share_staying"]
    variants = [motion_variant(m, d) for m in args.models for d in args.decisions]
    for name, text in motion_conditions(args.quick):
        scenario = os.path.join(args.out, "scenarios", slug(name) + ".yaml")
        write_atomic(scenario, f"name: {slug(name)}\n{text}"
                               f"mission: {{max_steps: {args.max_steps}}}\n")
        print(f"[motion] {name} ...", flush=True)
        jobs = [(m, p, args.seed_base + i) for m in variants for p in policies
                for i in range(seeds)]
        with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
            results = list(pool.map(
                lambda j: (j, motion_run(args, name, scenario, *j)), jobs))
        for model in variants:
            for policy in policies:
                rs = [r for (m, p, _), r in results if m == model and p == policy]
                row = {"condition": name, "model": model, "policy": policy, "n": len(rs)}
                for k in keys:
                    row[k], row[k + "_se"] = mean_se([r[k] for r in rs])
                table.append(row)
    header = ["condition", "model", "policy", "n"] + [x for k in keys for x in (k, k + "_se")]
    write_csv(os.path.join(args.out, "motion.csv"), header,
              [[r[h] for h in header] for r in table])
    lines = ["| condition | policy | model | success | steps | decisions / robot "
             "| mission seconds | s / step "
             "| stalls / robot-step | time: driving / turning / blocked / yielding / "
             "staying / waiting |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(table, key=lambda r: (r["condition"], r["policy"])):
        lines.append(
            f"| {r['condition']} | {r['policy']} | {r['model']} | {r['success']:.2f} "
            f"| {r['steps']:.1f} ± {r['steps_se']:.1f} | {r['decisions']:.1f} "
            f"| {r['seconds']:.1f} ± "
            f"{r['seconds_se']:.1f} | {r['seconds_per_step']:.2f} | {r['stalls']:.3f} "
            f"| {r['share_driving']:.2f} / {r['share_turning']:.2f} / "
            f"{r['share_blocked']:.2f} / {r['share_yielding']:.2f} / "
            f"{r['share_staying']:.2f} / {r['share_arrived']:.2f} |")
    write_atomic(os.path.join(args.out, "motion.md"), "\n".join(lines) + "\n")
    plot_motion(table, os.path.join(args.out, "motion.png"),
                f"{' against '.join(variants)}, {seeds} worlds per condition, "
                f"seeds from {args.seed_base}")
    write_json(os.path.join(args.out, "summary.json"), {
        "experiment": "motion", "policies": policies, "seeds": seeds,
        "seed_base": args.seed_base, "max_steps": args.max_steps, "sets": args.set,
        "wall_s_this_call": time.time() - t0, "rows": table})


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="The paper's experiments (section V), one command each.",
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    sub = parser.add_subparsers(dest="experiment", required=True)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--out", required=True, help="output folder")
    common.add_argument("--quick", action="store_true", help="a small version (about a minute)")
    common.add_argument("--aia", default=os.path.join(ROOT, "build/aia"), help="the aia binary")
    common.add_argument("--set", action="append", default=[],
                        help="override a scenario key (passed to aia as --set)")
    s = sub.add_parser("scalability", parents=[common], help="success and flowtime vs N x M")
    s.add_argument("--sizes", type=lambda t: t.split(","), help="default: the paper's 7")
    s.add_argument("--seeds", type=int, help="worlds per size (default 100; quick 3)")
    s.add_argument("--seed-base", type=int, default=0, help="first seed (default 0)")
    s.add_argument("--policies", type=lambda t: t.split(","),
                   help="default: " + ",".join(POLICIES))
    s.add_argument("--threads", type=int, default=0, help="aia eval --threads (0: all cores)")
    s.add_argument("--mpi", type=int, default=0, help="run aia eval under mpirun -n K")
    t = sub.add_parser("tracking", parents=[common], help="localization and tracking missions")
    t.add_argument("--policy", default="igbnet", help="decision maker (default igbnet)")
    t.add_argument("--no-video", action="store_true", help="skip the videos")
    r = sub.add_parser("robustness", parents=[common], help="failures and packet loss")
    r.add_argument("--policy", default="igbnet", help="decision maker (default igbnet)")
    r.add_argument("--scenario", default=os.path.join(ROOT, "scenarios/robustness.yaml"),
                   help="default: scenarios/robustness.yaml")
    r.add_argument("--seeds", type=int, help="worlds (default 50; quick 5)")
    r.add_argument("--seed-base", type=int, default=0, help="first seed (default 0)")
    r.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="runs at once")
    r.add_argument("--no-video", action="store_true", help="skip the video")
    g = sub.add_parser("generalization", parents=[common],
                       help="every policy on worlds unlike the training ones")
    g.add_argument("--policies", type=lambda t: t.split(","),
                   help="default: " + ",".join(GEN_POLICIES) + " (quick: igbnet,greedy)")
    g.add_argument("--seeds", type=int, help="worlds per generated condition (default 30; quick 2)")
    g.add_argument("--file-seeds", type=int,
                   help="seeds per scenario file (default 4; quick 1)")
    g.add_argument("--seed-base", type=int, default=GEN_SEED_BASE,
                   help=f"first seed (default {GEN_SEED_BASE}, disjoint from training and "
                        "model selection)")
    g.add_argument("--threads", type=int, default=0, help="aia eval --threads (0: all cores)")
    g.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                   help="aia run processes at once for scenario files")
    g.add_argument("--only", help="conditions whose name or group contains one of these "
                                  "comma-separated words, e.g. 'team,structured'")
    mo = sub.add_parser("motion", parents=[common],
                        help="point against wheeled robots: steps, seconds, where time goes")
    mo.add_argument("--policies", type=lambda t: t.split(","),
                    help="default: " + ",".join(GEN_POLICIES) + " (quick: igbnet,greedy)")
    mo.add_argument("--seeds", type=int, help="worlds per condition (default 10; quick 2)")
    mo.add_argument("--seed-base", type=int, default=GEN_SEED_BASE,
                    help=f"first seed (default {GEN_SEED_BASE})")
    mo.add_argument("--max-steps", type=int, default=200, help="mission.max_steps (200)")
    mo.add_argument("--models", type=lambda t: t.split(","), default=MOTION_MODELS,
                    help="robots.model values (default point,diff_drive)")
    mo.add_argument("--decisions", type=lambda t: t.split(","), default=["lockstep"],
                    help="mission.decisions values, e.g. lockstep,async (default lockstep)")
    mo.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="runs at once")
    args = parser.parse_args(argv)
    if not (os.path.isfile(args.aia) and os.access(args.aia, os.X_OK)):
        print(f"error: {args.aia}: not built (run tools/bootstrap.sh)", file=sys.stderr)
        return 2
    for name in ("seeds", "file_seeds", "max_steps"):
        v = getattr(args, name, None)
        if v is not None and v < 1:
            print(f"error: --{name}: must be at least 1", file=sys.stderr)
            return 2
    if getattr(args, "jobs", 1) < 1:
        print("error: --jobs: must be at least 1", file=sys.stderr)
        return 2
    for name in ("seed_base", "threads", "mpi"):
        v = getattr(args, name, 0)
        if v is not None and v < 0:
            print(f"error: --{name.replace('_', '-')}: must be at least 0, got {v}",
                  file=sys.stderr)
            return 2
    for name in ("sizes", "policies", "models", "decisions"):
        v = getattr(args, name, None)
        if v is not None and (not v or any(not x for x in v)):
            print(f"error: --{name}: a comma-separated list with no empty entry, "
                  f"got {','.join(v)!r}", file=sys.stderr)
            return 2
        if v is not None:
            # Each once (two runs of one setting would share a folder), and a
            # size as aia eval writes it ("03x3" is 3x3).
            if name == "sizes":
                v = [canonical_size(x) for x in v]
            setattr(args, name, list(dict.fromkeys(v)))
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        print(f"error: --out: {args.out} is a file, not a folder", file=sys.stderr)
        return 2
    try:
        os.makedirs(args.out, exist_ok=True)
    except OSError as e:
        line, code = os_error(e)
        print(line, file=sys.stderr)
        return code
    settings = os.path.join(args.out, "settings.json")
    fresh = not os.path.exists(settings)

    def refused(code):
        # Bad input found before anything ran: the folder keeps no settings
        # of it, so that the corrected command may use it.
        if code == 2 and fresh and os.listdir(args.out) == ["settings.json"]:
            os.remove(settings)
        return code

    try:
        check_settings(args)
        {"scalability": scalability, "tracking": tracking, "robustness": robustness,
         "generalization": generalization, "motion": motion}[args.experiment](args)
    except AlreadySaid as e:
        return refused(e.code)
    except (Usage, BadInput) as e:
        print(f"error: {e}", file=sys.stderr)
        return refused(2)
    except Failure as e:
        print(f"error: {e}", file=sys.stderr)
        return refused(2 if " exited with 2" in str(e) else 1)
    except KeyboardInterrupt:
        print("\ninterrupted: run the same command again to go on", file=sys.stderr)
        return 130
    except OSError as e:
        line, code = os_error(e)
        print(line, file=sys.stderr)
        return refused(code)
    print(f"results in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
