#!/usr/bin/python3
"""Kills an aia long job with SIGKILL at random moments, restarts it each
time, lets the last restart finish, and checks that the result equals an
uninterrupted run's: no finished work lost, nothing duplicated, no temporary
or corrupt file left (docs/hardening.md).

  tools/kill_restart.py --job eval|dataset|train --kills 8 --out DIR [--seed S]

The uninterrupted run goes to DIR/whole, the killed one to DIR/killed; each
kill lands uniform-randomly within the first 2 T / KILLS seconds of its
restart (T: the uninterrupted run's wall time), so the kills spread over
the whole job. The verdict and the moments are written to DIR/report.json;
the exit code is 0 when the results match, 1 otherwise, 2 on bad arguments.
"""
import argparse
import hashlib
import json
import os
import pathlib
import random
import re
import shutil
import signal
import sqlite3
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
MARK = ".kill_restart"  # written first into a folder this tool makes
MINE = {"whole", "killed", "data", "report.json", MARK}  # what --out may hold


def job_args(job: str, out: pathlib.Path, data: pathlib.Path) -> list:
    if job == "eval":
        return ["eval", "--sizes", "4x4,6x6,8x8,10x10", "--seeds", "100",
                "--policies",
                "greedy,decsb", "--threads", "2", "--out", str(out), "--quiet"]
    if job == "dataset":
        return ["dataset", "--episodes", "600", "--size", "4x4", "--keep", "2",
                "--first-seed", "900", "--out", str(out), "--quiet"]
    return ["train", "--data", str(data), "--out", str(out / "model.pt"),
            "--epochs", "150", "--width", "8", "--window", "16", "--threads",
            "1", "--resume", "--quiet"]


def digest(job: str, out: pathlib.Path) -> dict:
    """What must match between the two runs, wall-clock columns aside."""
    if job == "eval":
        runs = (out / "runs.csv").read_text()
        return {"runs.csv": re.sub(r",[0-9.]+\n", ",X\n", runs),
                "summary.csv": (out / "summary.csv").read_text()}
    if job == "dataset":
        rows = {}
        for f in sorted(out.glob("*.sqlite")):
            db = sqlite3.connect(f"file:{f}?mode=ro", uri=True)
            for table in ("worlds", "samples"):
                got = db.execute(f"SELECT * FROM {table} ORDER BY 1, 2, 3"
                                 if table == "samples" else
                                 f"SELECT * FROM {table} ORDER BY 1").fetchall()
                rows[f"{f.name}:{table}"] = hashlib.sha256(
                    repr(got).encode()).hexdigest() + f" ({len(got)} rows)"
            db.close()
        return rows
    log = (out / "model.train.csv").read_text()
    return {"model.train.csv": re.sub(r",[0-9.e+-]+\n", ",X\n", log),
            "model.pt": hashlib.sha256(
                (out / "model.pt").read_bytes()).hexdigest()}


def done(job: str, out: pathlib.Path) -> int:
    """Finished work on disk: eval rows, dataset episodes, training epochs."""
    try:
        if job == "eval":
            return max(0, len((out / "runs.csv").read_text().splitlines()) - 1)
        if job == "dataset":
            n = 0
            for f in out.glob("*.sqlite"):
                db = sqlite3.connect(f"file:{f}?mode=ro", uri=True)
                n += db.execute("SELECT COUNT(*) FROM worlds").fetchone()[0]
                db.close()
            return n
        return max(0, len((out / "model.train.csv").read_text().splitlines())
                   - 1)
    except (OSError, sqlite3.Error):
        return 0


def run(aia: str, args: list) -> float:
    t0 = time.monotonic()
    r = subprocess.run([aia] + args, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"error: {' '.join(args[:1])} failed ({r.returncode}): "
                 f"{r.stderr.strip()}")
    return time.monotonic() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--job", choices=["eval", "dataset", "train"],
                    required=True, help="the long job to kill")
    ap.add_argument("--kills", type=int, default=8,
                    help="SIGKILLs before the last restart (default 8)")
    ap.add_argument("--seed", type=int, default=1,
                    help="seed of the kill moments (default 1)")
    ap.add_argument("--aia", default=str(ROOT / "build/aia"),
                    help="the aia binary (default build/aia)")
    ap.add_argument("--out", required=True,
                    help="scratch folder, replaced (new, or one this tool "
                    "wrote before)")
    a = ap.parse_args()
    if not 1 <= a.kills <= 1000:
        ap.error("--kills: must be in 1..1000")
    if not os.access(a.aia, os.X_OK):
        ap.error(f"--aia: '{a.aia}' is not an executable")
    out = pathlib.Path(a.out)
    if out.exists():
        if not out.is_dir():
            ap.error(f"--out: '{out}' is not a folder")
        names = {p.name for p in out.iterdir()}
        others = names - MINE
        if others:
            ap.error(f"--out: '{out}' holds files this tool did not write "
                     f"({', '.join(sorted(others)[:3])}); give a new folder")
        # Only a folder this tool made is replaced: a "data" folder of the
        # same name may be anyone's.
        if names and MARK not in names:
            ap.error(f"--out: '{out}' was not made by this tool (no {MARK} "
                     "in it); give a new folder")
        shutil.rmtree(out)
    out.mkdir(parents=True)
    (out / MARK).write_text("made by tools/kill_restart.py; replaced by its "
                            "next run\n")
    data = out / "data"
    if a.job == "train":  # a small dataset to train on, made once
        run(a.aia, ["dataset", "--episodes", "40", "--size", "4x4", "--keep",
                    "4", "--first-seed", "500", "--out", str(data), "--quiet"])
    whole, killed = out / "whole", out / "killed"
    whole.mkdir()
    killed.mkdir()
    t_whole = run(a.aia, job_args(a.job, whole, data))
    rng = random.Random(a.seed)
    moments, hits = [], 0
    for k in range(a.kills):
        delay = rng.uniform(0.25, 1.75) * t_whole / a.kills
        p = subprocess.Popen([a.aia] + job_args(a.job, killed, data),
                             stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
        try:
            p.wait(timeout=delay)
            moments.append({"after_s": round(delay, 3), "hit": False,
                            "exit": p.returncode, "done": done(a.job, killed)})
        except subprocess.TimeoutExpired:
            p.send_signal(signal.SIGKILL)
            p.wait()
            hits += 1
            moments.append({"after_s": round(delay, 3), "hit": True,
                            "done": done(a.job, killed)})
        print(f"\r[kill_restart] {a.job}: {k + 1}/{a.kills} kills, "
              f"{hits} in flight", end="", file=sys.stderr)
    print(file=sys.stderr)
    t_last = run(a.aia, job_args(a.job, killed, data))
    temporaries = [str(p) for p in killed.rglob("*") if ".tmp." in p.name]
    want, got = digest(a.job, whole), digest(a.job, killed)
    differ = sorted(k for k in set(want) | set(got) if want.get(k) != got.get(k))
    report = {"job": a.job, "kills": a.kills, "seed": a.seed,
              "whole_s": round(t_whole, 2), "last_restart_s": round(t_last, 2),
              "kills_in_flight": hits, "moments": moments,
              "differ": differ, "temporaries": temporaries,
              "same": not differ and not temporaries,
              "compared": {k: (v if len(v) < 100 else
                               hashlib.sha256(v.encode()).hexdigest())
                           for k, v in want.items()}}
    tmp = out / f"report.json.tmp.{os.getpid()}"
    tmp.write_text(json.dumps(report, indent=1) + "\n")
    tmp.replace(out / "report.json")
    kept = " ".join(str(m["done"]) for m in moments)
    verdict = ("identical to an uninterrupted run's" if report["same"] else
               "DIFFERENT: " + ", ".join(differ + temporaries))
    print(f"[kill_restart] {a.job}: {hits} of {a.kills} kills hit a running "
          f"job (work kept after each: {kept} of {done(a.job, whole)}); "
          f"result {verdict}", file=sys.stderr)
    return 0 if report["same"] else 1


if __name__ == "__main__":
    sys.exit(main())
