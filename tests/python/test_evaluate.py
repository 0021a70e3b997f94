"""aia.evaluate scores a Python policy as `aia eval` scores the built-ins."""

import csv
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import aia

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
BINARY = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))


def rows_of(path, policy):
    """runs.csv's rows of one policy, wall time left out, by (size, seed)."""
    with open(path, newline="") as f:
        return {(r["size"], r["seed"]): {k: v for k, v in r.items()
                                         if k not in ("wall_s", "policy")}
                for r in csv.DictReader(f) if r["policy"] == policy}


def test_delegating_to_greedy_gives_the_builtin_greedys_rows(tmp_path):
    sizes, seeds, base = ["3x3", "5x2"], 3, 40
    r = subprocess.run([BINARY, "eval", "--sizes", ",".join(sizes), "--seeds",
                        str(seeds), "--seed-base", str(base), "--policies",
                        "greedy", "--out", str(tmp_path / "cli"), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    greedy = aia.builtin_policy("greedy")
    summary = aia.evaluate(lambda m: greedy.decide(m), sizes, seeds,
                           seed_base=base, out=tmp_path / "py",
                           name="greedy_py", threads=2, progress=False)
    cli = rows_of(tmp_path / "cli" / "runs.csv", "greedy")
    mine = rows_of(tmp_path / "py" / "runs.csv", "greedy_py")
    assert len(cli) == len(sizes) * seeds
    assert mine == cli
    assert [(s["size"], s["policy"]) for s in summary] == [
        ("3x3", "greedy_py"), ("5x2", "greedy_py")]
    assert all(s["instances"] == seeds for s in summary)
    # Beside the built-in's rows in one folder and one summary.
    summary = aia.evaluate(greedy, sizes, seeds, seed_base=base,
                           out=tmp_path / "cli", name="greedy_py",
                           progress=False)
    assert [s["policy"] for s in summary] == ["greedy_py", "greedy",
                                              "greedy_py", "greedy"]
    assert rows_of(tmp_path / "cli" / "runs.csv", "greedy_py") == cli


def test_the_policy_sees_a_read_only_view_without_the_truth(tmp_path):
    seen = []

    def policy(m):
        s = m.state()
        assert "truth" not in s
        assert s["positions"].shape == (m.num_robots, 2)
        with pytest.raises(ValueError, match="can only be read"):
            m.step([0] * m.num_robots)
        seen.append(m)
        return [0] * m.num_robots

    aia.evaluate(policy, ["2x1"], 1, out=tmp_path, name="left",
                 progress=False)
    assert seen
    with pytest.raises(ValueError, match="valid only inside"):
        seen[0].state()


def test_bad_names_sizes_and_exceptions(tmp_path):
    with pytest.raises(aia.InputError, match="registered policy's name"):
        aia.evaluate(lambda m: [0] * m.num_robots, ["2x1"], 1,
                     out=tmp_path / "a", name="greedy", progress=False)
    with pytest.raises(aia.InputError, match="name: must be"):
        aia.evaluate(lambda m: [0], ["2x1"], 1, out=tmp_path / "b",
                     name="a b", progress=False)
    with pytest.raises(aia.InputError, match=r"sizes\[1\]: robots and "
                       "targets must be >= 1, got '0x2'"):
        aia.evaluate(lambda m: [0], ["2x1", "0x2"], 1, out=tmp_path / "c",
                     progress=False)

    class Boom(Exception):
        pass

    def boom(m):
        raise Boom("from the policy")

    with pytest.raises(Boom, match="from the policy"):
        aia.evaluate(boom, ["2x1"], 2, out=tmp_path / "d", name="boom",
                     threads=1, progress=False)
    with pytest.raises(ValueError, match=r"moves\[0\]: must be 0"):
        aia.evaluate(lambda m: [9] * m.num_robots, ["2x1"], 1,
                     out=tmp_path / "e", name="nine", progress=False)
    expert = aia.builtin_policy("expert")
    with pytest.raises(aia.InputError, match="centralized=True"):
        aia.evaluate(expert, ["2x1"], 1, out=tmp_path / "f", name="ex",
                     progress=False)
    rows = aia.evaluate(expert, ["2x1"], 1, out=tmp_path / "g", name="ex",
                        centralized=True, progress=False)
    assert rows[0]["success_rate"] == 1.0


CHILD = """
import sys, time, aia
greedy = aia.builtin_policy("greedy")
def slow(m):
    time.sleep(0.002)
    return greedy.decide(m)
try:
    aia.evaluate(slow, ["4x4"], int(sys.argv[2]), seed_base=7,
                 out=sys.argv[1], name="slow", threads=1, progress=False)
except KeyboardInterrupt as e:
    print("interrupted:", e)
    sys.exit(3)
print("finished")
"""


def test_ctrl_c_keeps_every_finished_row_and_the_rerun_goes_on(tmp_path):
    out, seeds = tmp_path / "e", 12
    env = dict(os.environ)
    p = subprocess.Popen([sys.executable, "-c", CHILD, str(out), str(seeds)],
                         env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    runs = out / "runs.csv"
    deadline = time.time() + 120
    while time.time() < deadline:
        if runs.exists() and len(runs.read_text().splitlines()) >= 3:
            break
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=120)
    assert p.returncode == 3, (stdout, stderr)
    assert "interrupted" in stdout
    done = rows_of(runs, "slow")
    assert 2 <= len(done) < seeds
    # Every row written is a finished run's: the same as the CLI's.
    r = subprocess.run([BINARY, "eval", "--sizes", "4x4", "--seeds",
                        str(seeds), "--seed-base", "7", "--policies",
                        "greedy", "--out", str(tmp_path / "cli"), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    cli = rows_of(tmp_path / "cli" / "runs.csv", "greedy")
    for key, row in done.items():
        assert row == cli[key], key
    p = subprocess.run([sys.executable, "-c", CHILD, str(out), str(seeds)],
                       env=env, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "finished" in p.stdout
    assert rows_of(runs, "slow") == cli


QUIET = """
import sys, aia
greedy = aia.builtin_policy("greedy")
print("before")
def policy(m):
    sys.stdout.write("decided\\n")  # one write: policies run on threads
    sys.stdout.flush()
    return greedy.decide(m)
rows = aia.evaluate(policy, ["2x1"], 2, out=sys.argv[1], name="mine",
                    progress=%s)
print("after", len(rows))
"""


def test_quiet_means_quiet_and_progress_goes_to_stderr(tmp_path):
    r = subprocess.run([sys.executable, "-c", QUIET % "False",
                        str(tmp_path / "q")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    # Only the script's own prints, in the order it made them.
    assert lines[0] == "before" and lines[-1] == "after 1"
    assert set(lines[1:-1]) == {"decided"}
    assert r.stderr == ""
    r = subprocess.run([sys.executable, "-c", QUIET % "True",
                        str(tmp_path / "p")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert set(r.stdout.splitlines()[1:-1]) == {"decided"}
    assert "[aia.evaluate] mine" in r.stderr and "2/2 runs" in r.stderr


def test_progress_callback(tmp_path):
    greedy = aia.builtin_policy("greedy")
    seen = []
    aia.evaluate(greedy, ["2x1"], 3, out=tmp_path, name="g",
                 progress=lambda done, total: seen.append((done, total)),
                 threads=1)
    assert seen[0] == (0, 3) and seen[-1] == (3, 3)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    seen.clear()
    aia.evaluate(greedy, ["2x1"], 4, out=tmp_path, name="g",
                 progress=lambda done, total: seen.append((done, total)))
    assert seen[0] == (3, 4) and seen[-1] == (4, 4)


def test_calls_from_two_threads_take_turns(tmp_path, capfd):
    """Two aia.evaluate calls at once (threads) on one folder: they take
    turns (before 2026-12-06 the process crashed in fflush, eval's lines
    reached stdout and one policy's rows were lost)."""
    import threading
    greedy = aia.builtin_policy("greedy")
    done, errors = {}, []

    def run(name):
        try:
            done[name] = aia.evaluate(lambda m: greedy.decide(m),
                                      ["3x2", "4x4"], 4, out=tmp_path,
                                      name=name, progress=False)
        except Exception as e:  # noqa: BLE001 - any is a finding
            errors.append(repr(e))

    threads = [threading.Thread(target=run, args=(n,)) for n in ("a", "b")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    with open(tmp_path / "runs.csv") as f:
        rows = list(csv.DictReader(f))
    assert sorted(r["policy"] for r in rows) == ["a"] * 8 + ["b"] * 8
    # Both scored the same worlds with the same policy: the same rows.
    key = lambda r: (r["size"], r["seed"], r["success"], r["flowtime"])
    assert sorted(key(r) for r in rows if r["policy"] == "a") == \
        sorted(key(r) for r in rows if r["policy"] == "b")
    assert capfd.readouterr().out == ""  # nothing printed to stdout


def test_a_view_in_use_on_another_thread_outlives_no_decision(tmp_path):
    """A thread still inside the view's channels() when the decision ends
    (the GIL let go) is waited for before the view is invalidated: the
    evaluation read freed memory (a segfault) before. The policy's own call
    is refused while the other thread holds the view (the evaluation ends
    with that error), or, where the thread has not begun yet, the decision
    ends with the thread inside; either way nothing crashes."""
    started = []

    def policy(view):
        t = threading.Thread(target=view.channels,
                             kwargs=dict(geodesic=True, window=128))
        t.start()
        started.append(t)
        time.sleep(0.002)
        return [4] * view.num_robots

    for run in range(3):
        try:
            aia.evaluate(policy, ["10x10"], 1, out=str(tmp_path / f"a{run}"),
                         threads=1, progress=False)
        except aia.InputError as e:
            assert "another thread is inside" in str(e)
        for t in started:
            t.join()


def test_evaluations_do_not_nest(tmp_path):
    def policy(view):
        aia.evaluate(lambda v: [4] * v.num_robots, ["4x4"], 1,
                     out=str(tmp_path / "inner"), progress=False,
                     name="inner")
        return [4] * view.num_robots

    with pytest.raises(aia.InputError,
                       match=r"^aia\.evaluate: called from a policy or "
                             r"progress callback of a running aia\.evaluate"):
        aia.evaluate(policy, ["4x4"], 1, out=str(tmp_path / "outer"),
                     threads=1, progress=False)


def test_a_refusal_draws_no_bar(tmp_path, capfd):
    """A size or an override that C++ refuses is refused before the bar's
    first line (it was drawn first, then the error followed it)."""
    seen = []
    greedy = aia.builtin_policy("greedy")
    with pytest.raises(aia.InputError, match=r"sizes\[1\]"):
        aia.evaluate(greedy, ["2x1", "2y1"], 2, out=tmp_path / "a")
    with pytest.raises(aia.InputError, match="no_such_key"):
        aia.evaluate(greedy, ["2x1"], 2, out=tmp_path / "b",
                     overrides={"sensor.no_such_key": 1})
    with pytest.raises(aia.InputError, match="no_such_key"):
        aia.evaluate(greedy, ["2x1"], 2, out=tmp_path / "c",
                     overrides={"sensor.no_such_key": 1},
                     progress=lambda done, total: seen.append(done))
    assert seen == []
    assert "[aia.evaluate]" not in capfd.readouterr().err


def test_the_first_progress_call_is_inside_the_evaluation(tmp_path):
    def progress(done, total):
        aia.evaluate(lambda v: [4] * v.num_robots, ["2x1"], 1,
                     out=str(tmp_path / "inner"), progress=False)

    with pytest.raises(aia.InputError, match="progress callback of a "
                                             "running aia.evaluate"):
        aia.evaluate(lambda v: [4] * v.num_robots, ["2x1"], 1,
                     out=str(tmp_path / "outer"), progress=progress)
