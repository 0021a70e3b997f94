#!/usr/bin/python3
"""Runs `aia run` on randomly mutated scenarios and reports any that crash,
hang or eat memory (docs/hardening.md).

Each mutant is one of the scenario files given (default: scenarios/ and
tests/data/) with a few random edits: numbers replaced by extreme values,
keys dropped or duplicated, values turned into lists, maps or long strings,
bytes flipped or the text cut short. A mutant passes when `aia run` exits
with 0 (it ran), 2 (one `error:` line) or 1 with one `error:` line, within
--timeout seconds and --max-rss-mb of memory. Everything else is a finding,
copied to OUT/findings/ with its output.

  tools/mutate_scenarios.py --count 1000 --out /tmp/mutants [--jobs 2]
"""
import argparse
import concurrent.futures
import json
import os
import pathlib
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent

EXTREMES = [
    "0", "-0", "-1", "1", "0.5", "1e-300", "-1e-300", "1e308", "-1e308",
    "1e9", "1e-9", "2147483647", "2147483648", "-2147483648",
    "9223372036854775807", "18446744073709551616", ".nan", ".inf", "-.inf",
    "0x7fffffff", "1e6", "100000000", "3.5", "~", "''", "yes", "[]", "{}",
    "[1e308, 1e308]", "[-1e9, 5]", "[0, 0]", "[[2, 0], [0, 2]]",
    "[[0, 0], [0, 0]]", "\"\\xff\\xfe\"", "&a [*a]",
]
NUMBER = re.compile(r"(?<![\w.])-?\d+(\.\d+)?(e[-+]?\d+)?(?![\w.])")


def mutate(text: str, rng: random.Random) -> str:
    lines = text.split("\n")
    for _ in range(rng.randint(1, 4)):
        kind = rng.random()
        i = rng.randrange(len(lines)) if lines else 0
        line = lines[i] if lines else ""
        if kind < 0.45:  # a number becomes an extreme value
            spots = list(NUMBER.finditer(line))
            if spots:
                m = rng.choice(spots)
                line = line[:m.start()] + rng.choice(EXTREMES) + line[m.end():]
                lines[i] = line
        elif kind < 0.55:  # a key's value becomes something else
            if ":" in line:
                key = line.split(":", 1)[0]
                lines[i] = key + ": " + rng.choice(EXTREMES + [
                    "x" * rng.choice([1, 100, 100000]), "[" + "1, " * 1000 + "1]",
                    "{a: 1}", "[[1]]"])
        elif kind < 0.65:  # a line goes
            if lines:
                del lines[i]
        elif kind < 0.72:  # a line is repeated (duplicate keys)
            if lines:
                lines.insert(i, line)
        elif kind < 0.8:  # count-like keys get large
            lines[i] = re.sub(r"(count|max_steps|max_nodes|iterations|width|"
                              r"height|fps|horizon)(\s*:\s*)\d+",
                              lambda m: m.group(1) + m.group(2) + rng.choice(
                                  ["0", "5000", "5001", "100000", "2147483647",
                                   "1000000000"]), line)
        elif kind < 0.86:  # indentation breaks
            lines[i] = " " * rng.randint(0, 5) + line.lstrip()
        elif kind < 0.92:  # the text is cut
            cut = rng.randrange(len(text) + 1)
            return "\n".join(lines)[:cut]
        else:  # random bytes
            raw = bytearray("\n".join(lines).encode("utf-8", "surrogateescape"))
            for _ in range(rng.randint(1, 8)):
                if raw:
                    raw[rng.randrange(len(raw))] = rng.randrange(256)
            return raw.decode("utf-8", "surrogateescape")
    return "\n".join(lines)


def sources(paths):
    files = []
    for p in paths:
        p = pathlib.Path(p)
        files += sorted(p.rglob("*.yaml")) if p.is_dir() else [p]
    return files


def run_one(aia, index, source, text, out, timeout, max_rss_mb):
    work = pathlib.Path(tempfile.mkdtemp(prefix="mutant_"))
    # What sits beside the source (maps, models, folders) is linked into the
    # mutant's folder, so that relative paths still resolve.
    for entry in source.parent.iterdir():
        if entry.suffix != ".yaml":
            (work / entry.name).symlink_to(entry)
    (work / "models").unlink(missing_ok=True)
    (work / "models").symlink_to(ROOT / "models")
    scenario = work / "mutant.yaml"
    scenario.write_bytes(text.encode("utf-8", "surrogateescape"))
    cmd = ["/usr/bin/time", "-f", "%M", aia, "run", str(scenario), "--out",
           str(work / "out"), "--quiet"]
    try:
        # A session of its own: a hang ends /usr/bin/time and the aia it runs
        # (killing time alone left aia running, with parent 1).
        with subprocess.Popen(cmd, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE,
                              start_new_session=True) as proc:
            try:
                _, stderr = proc.communicate(timeout=timeout)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.communicate()
                raise
        p = subprocess.CompletedProcess(cmd, proc.returncode, b"", stderr)
        code, err = p.returncode, p.stderr.decode("utf-8", "replace")
        lines = err.rstrip("\n").split("\n")
        rss_mb = int(lines[-1]) / 1024 if lines[-1].isdigit() else 0
        err = "\n".join(lines[:-1])
        if err.startswith("Command terminated by signal") or \
                err.startswith("Command exited"):
            err = "\n".join(err.split("\n")[1:])
        # /usr/bin/time prints "Command exited with non-zero status N".
        err_lines = [l for l in err.split("\n")
                     if l and not l.startswith("Command exited")]
        verdict = "ok"
        if "terminated by signal" in p.stderr.decode("utf-8", "replace"):
            verdict = "crash"
        elif code not in (0, 1, 2):
            verdict = "crash"
        elif code in (1, 2) and (len(err_lines) != 1 or
                                 not err_lines[0].startswith("error: ")):
            verdict = "unclear error"
        elif rss_mb > max_rss_mb:
            verdict = "memory"
    except subprocess.TimeoutExpired:
        code, err, rss_mb, verdict = None, "", 0, "hang"
    finally:
        shutil.rmtree(work, ignore_errors=True)
    result = {"index": index, "source": str(source.relative_to(ROOT)),
              "exit": code, "rss_mb": round(rss_mb), "verdict": verdict,
              "stderr": err[-400:]}
    if verdict != "ok":
        found = out / "findings"
        found.mkdir(parents=True, exist_ok=True)
        (found / f"{index}.yaml").write_bytes(
            text.encode("utf-8", "surrogateescape"))
        (found / f"{index}.json").write_text(json.dumps(result, indent=1))
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*",
                    default=[str(ROOT / "scenarios"),
                             str(ROOT / "tests/data")])
    ap.add_argument("--count", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=30.0)
    ap.add_argument("--max-rss-mb", type=float, default=2048.0)
    ap.add_argument("--aia", default=str(ROOT / "build/aia"))
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    if a.count < 1 or a.jobs < 1 or a.timeout <= 0:
        ap.error("--count, --jobs and --timeout must be positive")
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    files = sources(a.paths)
    if not files:
        ap.error("no scenario files in " + " ".join(a.paths))
    rng = random.Random(a.seed)
    mutants = []
    for i in range(a.count):
        source = rng.choice(files)
        text = source.read_bytes().decode("utf-8", "surrogateescape")
        mutants.append((i, source, mutate(text, rng)))
    # Resumable: results.jsonl holds the mutants already judged.
    results_path = out / "results.jsonl"
    done = {}
    if results_path.exists():
        for line in results_path.read_text().splitlines():
            try:
                r = json.loads(line)
                done[r["index"]] = r
            except (ValueError, KeyError):
                pass
    todo = [m for m in mutants if m[0] not in done]
    with open(results_path, "a") as log, \
            concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        futures = [pool.submit(run_one, a.aia, i, s, t, out, a.timeout,
                               a.max_rss_mb) for i, s, t in todo]
        for n, f in enumerate(concurrent.futures.as_completed(futures), 1):
            r = f.result()
            done[r["index"]] = r
            log.write(json.dumps(r) + "\n")
            log.flush()
            print(f"\r[mutate] {len(done)}/{a.count}", end="", file=sys.stderr)
    print(file=sys.stderr)
    verdicts = {}
    for r in done.values():
        verdicts[r["verdict"]] = verdicts.get(r["verdict"], 0) + 1
    codes = {}
    for r in done.values():
        codes[str(r["exit"])] = codes.get(str(r["exit"]), 0) + 1
    summary = {"mutants": len(done), "verdicts": verdicts, "exit_codes": codes,
               "max_rss_mb": max(r["rss_mb"] for r in done.values())}
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps(summary))
    return 0 if verdicts.get("ok", 0) == len(done) else 1


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from tool_io import run  # one error line for bad paths, not a traceback
    run(main)
