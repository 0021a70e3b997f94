#!/usr/bin/python3
"""Audit the expert planner (C-SB) over generated and long-horizon worlds.

Per world it runs

    aia plan FILE --out plan.json [--budget B]     F*, cost, solve time, bound
    aia run FILE --policy greedy --out DIR --quiet  greedy flowtime
    aia run FILE --policy expert --out DIR --quiet  executed expert flowtime,
                                                    moves.reversals / total

and writes one CSV row per world (OUT/audit.csv) plus a markdown summary per
set (printed, and written to OUT/summary.md).

Worlds:
  --sets 10x10:50,40x40:20   generated sets ROBOTSxTARGETS:SEEDS, seeds
                             0..SEEDS-1; each world is the scenario that
                             `aia eval --sizes RxT` builds for that seed
                             (seed, robots.count, targets.count, random
                             obstacles, every other key default)
  --long                     every scenarios/long/*.yaml

A command that runs past --timeout seconds is recorded as `timeout`, one that
fails as `error`. Keys missing from a JSON output (bound, moves.reversals,
moves.total with older binaries) are left empty.

  --compare BEFORE.csv [AFTER.csv]   before/after table per set; with one
                                     file, AFTER is this run's CSV (or
                                     OUT/audit.csv when no world is given).

Stdlib only.
"""

import argparse
import concurrent.futures
import csv
import glob
import json
import os
import re
import statistics
import subprocess
import sys
import time

COLUMNS = [
    "set", "world", "seed", "found", "fstar", "bound", "cost", "solve_s",
    "greedy_success", "greedy_flowtime", "expert_success", "expert_flowtime",
    "reversals", "moves"
]

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                     ".."))


# ------------------------------------------------------------------ worlds


def parse_sets(text):
    """'10x10:50,40x40:20' -> [(name, robots, targets, seeds)]."""
    out = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        m = re.fullmatch(r"(\d+)x(\d+):(\d+)", part)
        if not m:
            raise argparse.ArgumentTypeError(
                "bad set '%s' (expected ROBOTSxTARGETS:SEEDS, e.g. 10x10:50)" %
                part)
        r, t, n = (int(g) for g in m.groups())
        if r < 1 or n < 1:
            raise argparse.ArgumentTypeError("bad set '%s'" % part)
        out.append(("%dx%d" % (r, t), r, t, n))
    return out


def generated_yaml(robots, targets, seed):
    """The instance `aia eval --sizes RxT` builds for this seed: everything
    else default (random obstacles with their default count and sizes)."""
    return ("# aia eval instance %dx%d, seed %d (tools/expert_audit.py)\n"
            "name: generated_%dx%d\n"
            "seed: %d\n"
            "workspace:\n"
            "  obstacles:\n"
            "    random: {}\n"
            "robots: {count: %d}\n"
            "targets: {count: %d}\n" %
            (robots, targets, seed, robots, targets, seed, robots, targets))


def yaml_seed(path):
    try:
        with open(path) as f:
            for line in f:
                m = re.match(r"seed:\s*(\d+)\s*$", line)
                if m:
                    return int(m.group(1))
    except OSError:
        pass
    return 0


# ------------------------------------------------------------------ running


def run_cmd(cmd, timeout, log):
    """Runs cmd; returns 'ok', 'timeout' or 'error' (stdout+stderr to log)."""
    with open(log, "w") as f:
        f.write("$ " + " ".join(cmd) + "\n")
        f.flush()
        try:
            p = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT,
                               timeout=timeout)
        except subprocess.TimeoutExpired:
            f.write("\n[timeout after %s s]\n" % timeout)
            return "timeout"
        except OSError as e:
            f.write("\n[%s]\n" % e)
            return "error"
    return "ok" if p.returncode == 0 else "error"


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def get(d, dotted):
    for k in dotted.split("."):
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def cell(v):
    if v is None:
        return ""
    if isinstance(v, bool):
        return "1" if v else "0"
    if isinstance(v, float):
        return "%.6g" % v
    return str(v)


def audit_world(job, args):
    """One world: plan, greedy, expert. Returns its CSV row (strings)."""
    set_name, world, seed, scenario, wdir = job
    os.makedirs(wdir, exist_ok=True)
    done = os.path.join(wdir, "row.json")
    if args.resume:
        row = load_json(done)
        if row is not None:
            return row
    row = {c: "" for c in COLUMNS}
    row.update(set=set_name, world=world, seed=str(seed))

    plan = os.path.join(wdir, "plan.json")
    if os.path.exists(plan):
        os.remove(plan)
    cmd = [args.aia, "plan", scenario, "--out", plan]
    if args.budget is not None:
        cmd += ["--budget", str(args.budget)]
    st = run_cmd(cmd, args.timeout, os.path.join(wdir, "plan.log"))
    d = load_json(plan) if st == "ok" else None
    if d is None:
        row["found"] = st if st != "ok" else "error"
    else:
        found = bool(d.get("found"))
        row["found"] = cell(found)
        if found:
            row["fstar"] = cell(d.get("flowtime"))
            row["cost"] = cell(d.get("cost"))
        row["bound"] = cell(d.get("bound"))
        row["solve_s"] = cell(d.get("solve_s"))
        if "seed" in d:
            row["seed"] = cell(d["seed"])

    for policy in ("greedy", "expert"):
        out = os.path.join(wdir, policy)
        summary = os.path.join(out, "summary.json")
        if os.path.exists(summary):
            os.remove(summary)
        st = run_cmd([args.aia, "run", scenario, "--policy", policy, "--out",
                      out, "--quiet"], args.timeout,
                     os.path.join(wdir, policy + ".log"))
        s = load_json(summary) if st == "ok" else None
        if s is None:
            row[policy + "_success"] = st if st != "ok" else "error"
            continue
        row[policy + "_success"] = cell(bool(s.get("success")))
        if s.get("success"):
            row[policy + "_flowtime"] = cell(s.get("flowtime"))
        if policy == "expert":
            diag = load_json(os.path.join(out, "diagnostics.json")) or {}
            row["reversals"] = cell(get(diag, "moves.reversals"))
            row["moves"] = cell(get(diag, "moves.total"))
    with open(done, "w") as f:
        json.dump(row, f)
    return row


# ------------------------------------------------------------------ summary


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def fmt(v, digits=3):
    if v is None:
        return "-"
    if isinstance(v, int):
        return str(v)
    return ("%." + str(digits) + "g") % v


def mean(xs):
    return statistics.fmean(xs) if xs else None


def set_stats(rows):
    """Summary metrics of one set's rows (dict of name -> number or None)."""
    found = [r for r in rows if r["found"] == "1" and num(r["fstar"]) is not None]
    fstar = [num(r["fstar"]) for r in found]
    ratios = [num(r["fstar"]) / num(r["bound"]) for r in found
              if (num(r["bound"]) or 0) > 0]
    gr = [(num(r["fstar"]), num(r["greedy_flowtime"])) for r in found
          if r["greedy_success"] == "1" and num(r["greedy_flowtime"])]
    ex = [num(r["expert_flowtime"]) / num(r["fstar"]) - 1.0 for r in found
          if r["expert_success"] == "1" and num(r["expert_flowtime"]) is not None
          and num(r["fstar"]) > 0]
    rev = [(num(r["reversals"]), num(r["moves"])) for r in rows
           if num(r["reversals"]) is not None and num(r["moves"])]
    solve = [num(r["solve_s"]) for r in rows if num(r["solve_s"]) is not None]
    return {
        "worlds": len(rows),
        "no_plan": len(rows) - len(found),
        "mean_fstar": mean(fstar),
        "mean_ratio": mean(ratios),
        "worst_ratio": max(ratios) if ratios else None,
        "fstar_gt_greedy": sum(1 for f, g in gr if f > g),
        "greedy_gap": mean([(g - f) / g for f, g in gr]),
        "exec_gap": mean(ex),
        "reversal_share": (sum(a for a, _ in rev) / sum(b for _, b in rev)
                           if rev else None),
        "median_solve_s": statistics.median(solve) if solve else None,
        "greedy_ok": sum(1 for r in rows if r["greedy_success"] == "1"),
        "expert_ok": sum(1 for r in rows if r["expert_success"] == "1"),
        "expert_timeout": sum(1 for r in rows
                              if r["expert_success"] == "timeout"),
    }


METRICS = [
    # key, header, formatter
    ("worlds", "worlds", fmt),
    ("no_plan", "no plan", fmt),
    ("mean_fstar", "mean F*", lambda v: fmt(v, 4)),
    ("mean_ratio", "mean F*/bound", fmt),
    ("worst_ratio", "worst F*/bound", fmt),
    ("fstar_gt_greedy", "F* > greedy", fmt),
    ("greedy_gap", "mean (greedy-F*)/greedy", fmt),
    ("exec_gap", "mean expert/F* - 1", fmt),
    ("reversal_share", "reversal share", fmt),
    ("median_solve_s", "median solve_s", fmt),
    ("greedy_ok", "greedy ok", fmt),
    ("expert_ok", "expert ok", fmt),
    ("expert_timeout", "expert timeout", fmt),
]


def by_set(rows):
    sets = {}
    for r in rows:
        sets.setdefault(r["set"], []).append(r)
    return sets


def summary_table(rows):
    lines = ["| set | " + " | ".join(h for _, h, _ in METRICS) + " |",
             "|---|" + "---:|" * len(METRICS)]
    for name, rs in by_set(rows).items():
        s = set_stats(rs)
        lines.append("| %s | " % name +
                     " | ".join(f(s[k]) for k, _, f in METRICS) + " |")
    return "\n".join(lines)


def compare_table(before, after):
    """Per set, 'before -> after' of every metric, plus paired F* ratio."""
    b_sets, a_sets = by_set(before), by_set(after)
    names = list(b_sets) + [n for n in a_sets if n not in b_sets]
    out = []
    heads = ["set"] + [h for _, h, _ in METRICS] + [
        "paired F* after/before", "F* better/worse"]
    out.append("| " + " | ".join(heads) + " |")
    out.append("|---|" + "---:|" * (len(heads) - 1))
    for name in names:
        bs = set_stats(b_sets.get(name, []))
        as_ = set_stats(a_sets.get(name, []))
        cells = [name]
        for k, _, f in METRICS:
            cells.append("%s → %s" % (f(bs[k]), f(as_[k])))
        bmap = {r["world"]: num(r["fstar"]) for r in b_sets.get(name, [])
                if r["found"] == "1"}
        pairs = [(bmap[r["world"]], num(r["fstar"]))
                 for r in a_sets.get(name, []) if r["found"] == "1" and
                 bmap.get(r["world"]) and num(r["fstar"]) is not None]
        cells.append(fmt(mean([a / b for b, a in pairs])))
        cells.append("%d/%d" % (sum(1 for b, a in pairs if a < b),
                                sum(1 for b, a in pairs if a > b)))
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for c in COLUMNS:
            r.setdefault(c, "")
            if r[c] is None:
                r[c] = ""
    return rows


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({c: r.get(c, "") for c in COLUMNS})


# ------------------------------------------------------------------ main


def main():
    ap = argparse.ArgumentParser(
        description="Measure the expert planner (aia plan / run --policy "
        "expert) against greedy over generated and long-horizon worlds; "
        "print a markdown summary per set and write OUT/audit.csv.",
        epilog="Example: tools/expert_audit.py --aia build/aia --sets "
        "10x10:50,40x40:20,80x80:20 --long --out /tmp/audit; "
        "tools/expert_audit.py --compare before/audit.csv after/audit.csv",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--aia", default=os.path.join(REPO, "build", "aia"),
                    help="aia binary (default: build/aia)")
    ap.add_argument("--sets", type=parse_sets, default=[],
                    help="generated sets ROBOTSxTARGETS:SEEDS, comma "
                    "separated (e.g. 10x10:50,40x40:20,80x80:20)")
    ap.add_argument("--long", action="store_true",
                    help="add every scenarios/long/*.yaml (set 'long')")
    ap.add_argument("--long-dir", default=os.path.join(REPO, "scenarios",
                                                       "long"),
                    help="folder of the long worlds (default: "
                    "scenarios/long)")
    ap.add_argument("--out", default="audit",
                    help="output folder: audit.csv, summary.md, worlds/, "
                    "runs/ (default: ./audit)")
    ap.add_argument("--jobs", type=int, default=2,
                    help="worlds run in parallel (default 2)")
    ap.add_argument("--budget", type=int, default=None,
                    help="passed to aia plan --budget (default: the "
                    "expert's policy.anytime)")
    ap.add_argument("--timeout", type=float, default=300.0,
                    help="seconds one aia command may take before it is "
                    "recorded as timeout (default 300)")
    ap.add_argument("--resume", action="store_true",
                    help="reuse the rows of worlds already done in OUT")
    ap.add_argument("--compare", nargs="+", metavar="CSV",
                    help="BEFORE.csv [AFTER.csv]: print a before/after "
                    "table per set (AFTER: this run's CSV, or OUT/audit.csv)")
    args = ap.parse_args()
    if args.compare and len(args.compare) > 2:
        ap.error("--compare takes BEFORE.csv and at most one AFTER.csv")
    if args.jobs < 1:
        ap.error("--jobs must be at least 1")

    out = os.path.abspath(args.out)
    csv_path = os.path.join(out, "audit.csv")
    jobs = []
    for name, r, t, n in args.sets:
        wdir = os.path.join(out, "worlds", name)
        os.makedirs(wdir, exist_ok=True)
        for s in range(n):
            path = os.path.join(wdir, "s%d.yaml" % s)
            with open(path, "w") as f:
                f.write(generated_yaml(r, t, s))
            jobs.append((name, "%s_s%d" % (name, s), s, path,
                         os.path.join(out, "runs", name, "s%d" % s)))
    if args.long:
        files = sorted(glob.glob(os.path.join(args.long_dir, "*.yaml")))
        if not files:
            ap.error("no scenario in %s" % args.long_dir)
        for path in files:
            w = os.path.splitext(os.path.basename(path))[0]
            jobs.append(("long", w, yaml_seed(path), os.path.abspath(path),
                         os.path.join(out, "runs", "long", w)))

    if not jobs and not args.compare:
        ap.error("nothing to do: give --sets, --long or --compare")

    rows = None
    if jobs:
        aia = args.aia
        if os.sep in aia:
            aia = os.path.abspath(aia)
        if not os.access(aia, os.X_OK):
            ap.error("aia binary '%s' is not executable" % args.aia)
        args.aia = aia
        os.makedirs(out, exist_ok=True)
        t0 = time.time()
        results = [None] * len(jobs)
        with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
            futs = {pool.submit(audit_world, j, args): k
                    for k, j in enumerate(jobs)}
            done = 0
            for fut in concurrent.futures.as_completed(futs):
                k = futs[fut]
                results[k] = fut.result()
                done += 1
                r = results[k]
                def shown(value, status):
                    if value:
                        return value
                    return {"0": "fail", "": "-"}.get(status, status)

                print("[%d/%d %.0fs] %s %s: F*=%s greedy=%s expert=%s" %
                      (done, len(jobs), time.time() - t0, r["set"], r["world"],
                       shown(r["fstar"], r["found"]),
                       shown(r["greedy_flowtime"], r["greedy_success"]),
                       shown(r["expert_flowtime"], r["expert_success"])),
                      file=sys.stderr, flush=True)
        rows = results
        write_csv(csv_path, rows)
        table = summary_table(rows)
        with open(os.path.join(out, "summary.md"), "w") as f:
            f.write("# Expert audit\n\naia: `%s`, budget: %s\n\n%s\n" %
                    (args.aia, "default" if args.budget is None else
                     args.budget, table))
        print(table)
        print("\nwrote %s and %s" % (csv_path, os.path.join(out, "summary.md")))

    if args.compare:
        before = read_csv(args.compare[0])
        if len(args.compare) == 2:
            after = read_csv(args.compare[1])
        elif rows is not None:
            after = rows
        elif os.path.exists(csv_path):
            after = read_csv(csv_path)
        else:
            ap.error("--compare with one CSV needs worlds to run or an "
                     "existing %s" % csv_path)
        if rows is not None:
            print()
        print(compare_table(before, after))
    return 0


if __name__ == "__main__":
    sys.exit(main())
