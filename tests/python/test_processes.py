"""aia in a child forked from a process that used it, and at the
interpreter's exit with a thread inside a call: nothing may hang or abort
(or, where it cannot work, it is refused). Every child runs under a time
limit, so that a hang fails the test."""

import gc
import multiprocessing
import os
import signal
import subprocess
import sys
import time
import weakref
from pathlib import Path

import numpy as np
import pytest

import aia

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
DEFAULT = str(SOURCE / "scenarios" / "default.yaml")
SMALL = {"workspace.size": [10, 10], "workspace.obstacles.random.count": 8,
         "robots.count": 3, "targets.count": 3}
LIMIT = 120  # seconds a child may take (each takes a few)
FORK = multiprocessing.get_context("fork")


def _report(conn, target, args):
    try:
        conn.send(("returned", target(*args)))
    except BaseException as e:  # the child's only report
        conn.send(("raised", f"{type(e).__name__}: {e}"))


def in_forked_child(target, *args):
    """("returned", value) or ("raised", text) of target(*args) in a child
    forked from this process (multiprocessing's default on Linux); a child
    that runs past LIMIT hung, and is killed."""
    ours, theirs = FORK.Pipe(duplex=False)
    p = FORK.Process(target=_report, args=(theirs, target, args))
    p.start()
    theirs.close()
    p.join(LIMIT)
    if p.is_alive():
        p.kill()
        p.join()
        pytest.fail(f"the forked child hung (killed after {LIMIT} s)")
    assert p.exitcode == 0
    return ours.recv()


def run_python(code, *args, env=None):
    """(exit code, stdout, stderr) of `python -c code args`, in a session of
    its own that is killed whole (forked children too) past LIMIT."""
    p = subprocess.Popen([sys.executable, "-c", code, *args], env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, start_new_session=True)
    try:
        out, err = p.communicate(timeout=LIMIT)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
        pytest.fail(f"python hung (killed after {LIMIT} s): {out} {err}")
    return p.returncode, out, err


def test_a_vector_made_before_a_fork_steps_in_the_child():
    # Its pool's threads are the parent's: the child used to wait for them
    # for ever.
    v = aia.VectorMissions(2, DEFAULT, seed=1, overrides=SMALL, threads=2)
    assert list(v.step(np.zeros((2, 3), dtype=int)).steps) == [1, 1]

    def child():
        return [list(v.step(np.zeros((2, 3), dtype=int)).steps)
                for _ in range(3)]

    assert in_forked_child(child) == ("returned", [[2, 2], [3, 3], [4, 4]])
    # The parent's pool is untouched.
    assert list(v.step(np.zeros((2, 3), dtype=int)).steps) == [2, 2]


@pytest.mark.parametrize("step_first", [False, True])
def test_a_vector_made_before_a_fork_is_freed_in_the_child(step_first):
    held = [aia.VectorMissions(2, DEFAULT, seed=1, overrides=SMALL,
                               threads=2)]
    held[0].step(np.zeros((2, 3), dtype=int))

    def child():
        v = held.pop()
        if step_first:
            v.step(np.zeros((2, 3), dtype=int))
        core = weakref.ref(v._v)
        del v
        gc.collect()
        return core() is None

    assert in_forked_child(child) == ("returned", True)


RENDER_IN_CHILD = """
import gc, multiprocessing, sys, weakref, aia
S, SMALL = sys.argv[1], {"robots.count": 3, "targets.count": 3}
HELD = []  # a mission of the parent (rendered there if argv[2] says so)
def frame(mission=None):
    m = mission or aia.Mission(S, seed=1, overrides=SMALL)
    return m.render(64, 48)
def child(conn):
    old = HELD.pop()
    for name in ("new", "old"):
        try:
            conn.send((name, frame(old if name == "old" else None).tobytes()))
        except aia.InputError as e:
            conn.send((name, str(e)))
    core = weakref.ref(old._m)
    del old  # the parent's renderer, freed here
    gc.collect()
    conn.send(("freed", str(core() is None)))
def main():
    HELD.append(aia.Mission(S, seed=1, overrides=SMALL))
    if sys.argv[2] == "rendered":
        want = frame(HELD[0]).tobytes()
    ours, theirs = multiprocessing.get_context("fork").Pipe(duplex=False)
    p = multiprocessing.get_context("fork").Process(target=child,
                                                    args=(theirs,))
    p.start()
    theirs.close()
    p.join(60)
    if p.is_alive():
        p.kill()
        print("child hung")
    if sys.argv[2] != "rendered":
        want = frame().tobytes()
    while True:
        try:
            name, got = ours.recv()
        except EOFError:
            break
        print(name, "same frame" if got == want else got)
    print("exit code", p.exitcode)
main()
"""


def test_a_render_in_a_forked_child_after_the_parent_rendered_is_refused():
    # Mesa's llvmpipe threads, made at the parent's first render, do not
    # exist in the child: its render waited for them for ever.
    env = {k: v for k, v in os.environ.items() if k != "LP_NUM_THREADS"}
    code, out, err = run_python(RENDER_IN_CHILD, DEFAULT, "rendered",
                                env=env)
    assert code == 0, err
    why = ("aia.Mission.render: this process was forked from one that "
           "had rendered (pid ")
    lines = out.splitlines()
    assert len(lines) == 4, out
    assert lines[0].startswith("new " + why), out
    assert lines[1].startswith("old " + why), out
    for fix in ("'spawn'", "'forkserver'", "LP_NUM_THREADS=0"):
        assert fix in lines[0], out
    assert lines[2:] == ["freed True", "exit code 0"], out


@pytest.mark.parametrize("parent", ["rendered", "did not render"])
def test_a_forked_child_renders_where_the_parent_made_no_llvmpipe_threads(
        parent):
    # A first render with LP_NUM_THREADS=0 makes none; a parent that did
    # not render, none either.
    env = dict(os.environ)
    if parent == "rendered":
        env["LP_NUM_THREADS"] = "0"
    else:
        env.pop("LP_NUM_THREADS", None)
    code, out, err = run_python(RENDER_IN_CHILD, DEFAULT, parent, env=env)
    assert code == 0, err
    assert out.splitlines() == ["new same frame", "old same frame",
                                "freed True", "exit code 0"], out


DAEMON_AT_EXIT = """
import atexit, sys, time
# How long the exit waited.
atexit.register(lambda: print("waited", time.time() - DONE, file=sys.stderr))
import threading, aia, numpy as np
S, kind, out = sys.argv[1], sys.argv[2], sys.argv[3]
SMALL = {"robots.count": 3, "targets.count": 3}
def actor():
    if kind == "mission":
        m = aia.Mission(S, seed=1, overrides=SMALL)
        while True:
            if m.done:
                m = aia.Mission(S, seed=m.seed + 1, overrides=SMALL)
            m.step(np.zeros(m.num_robots, dtype=int))
    elif kind == "env":
        env = aia.parallel_env(S, seed=1, overrides=SMALL)
        env.reset()
        while True:
            if not env.agents:
                env.reset()
            env.step({a: 0 for a in env.agents})
    elif kind == "vector":
        v = aia.VectorMissions(2, S, seed=1, overrides=SMALL, threads=2,
                               autoreset=True)
        while True:
            v.step(np.zeros((2, v.num_robots), dtype=int))
    else:
        greedy = aia.builtin_policy("greedy")
        for i in range(1000):
            aia.evaluate(greedy.decide, ["2x1"], 1, out=f"{out}/{i}",
                         name="greedy_py", threads=2, progress=False)
threading.Thread(target=actor, daemon=True).start()
time.sleep(1.0)
print("main done", flush=True)
DONE = time.time()
"""


@pytest.mark.parametrize("kind", ["mission", "env", "vector", "evaluate"])
def test_a_daemon_thread_inside_a_call_at_exit_does_not_abort(kind,
                                                             tmp_path):
    # The thread was ended as it took the GIL back during finalization, and
    # the unwind through gil_scoped_release (noexcept) aborted the process
    # (exit 134, "terminate called without an active exception"), every
    # time: the forced unwind CPython starts there now leaves the module's
    # frames as it leaves CPython's.
    for run in range(3):
        code, out, err = run_python(DAEMON_AT_EXIT, DEFAULT, kind,
                                    str(tmp_path / str(run)))
        assert "terminate called" not in err, err
        assert (code, out) == (0, "main done\n"), err
        waited = [float(line.split()[1]) for line in err.splitlines()
                  if line.startswith("waited ")]
        assert len(waited) == 1 and waited[0] < 3.0, err


JOIN_AT_EXIT = """
import atexit, sys, threading, time
stop = threading.Event()
def cleanup():  # registered before aia is imported: runs after its own
    stop.set()
    t.join()
    print("joined", flush=True)
atexit.register(cleanup)
import aia
S = sys.argv[1]
def worker():
    m = aia.Mission(S, seed=1, overrides={"robots.count": 3})
    while not stop.is_set():
        if m.done:
            m = aia.Mission(S, seed=m.seed + 1, overrides={"robots.count": 3})
        m.step([0] * m.num_robots)
t = threading.Thread(target=worker, daemon=True)
t.start()
time.sleep(1.0)
"""

EVALUATE_AT_EXIT = """
import sys, threading, time, aia
def policy(m):
    time.sleep(0.01)
    return [4] * m.num_robots
def run():
    aia.evaluate(policy, ["4x4"], seeds=200, out=sys.argv[2], threads=1,
                 progress=False)
threading.Thread(target=run, daemon=True).start()
time.sleep(2.0)
print("main done", flush=True)
"""


def test_the_exit_lets_handlers_join_and_stops_an_evaluation(tmp_path):
    # An atexit handler of the package that parked every call after it ran
    # blocked a user handler registered before `import aia` that joins a
    # thread making calls (hung for ever), and the exit waited for a daemon
    # thread's whole aia.evaluate (minutes; without the wait, a segfault).
    code, out, err = run_python(JOIN_AT_EXIT, DEFAULT)
    assert (code, out) == (0, "joined\n"), err
    start = time.time()
    code, out, err = run_python(EVALUATE_AT_EXIT, DEFAULT,
                                str(tmp_path / "e"))
    assert "terminate called" not in err and "Traceback" not in err, err
    assert (code, out) == (0, "main done\n"), err
    assert time.time() - start < 30.0, err
    rows = (tmp_path / "e" / "runs.csv").read_text().splitlines()
    assert 1 < len(rows) < 201, rows  # some runs kept, not all made


FORK_DURING_CALL = """
import os, sys, threading, time, aia, numpy as np
SMALL = {"robots.count": 3, "targets.count": 3}
v = aia.VectorMissions(2, sys.argv[1], seed=1, overrides=SMALL, threads=2,
                       autoreset=True)
def actor():
    while True:
        v.step(np.zeros((2, v.num_robots), dtype=int))
threading.Thread(target=actor, daemon=True).start()
time.sleep(0.3)
for _ in range(3):
    pid = os.fork()
    if pid == 0:
        sys.exit(0)  # through atexit, forked while the actor was stepping
    for _ in range(3000):
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            print("exit status", status, flush=True)
            break
        time.sleep(0.01)
    else:
        os.kill(pid, 9)
        os.waitpid(pid, 0)
        print("child hung", flush=True)
"""


def test_a_child_forked_while_a_thread_is_inside_a_call_exits():
    # A child forked while another thread is inside a call has no such
    # thread: its exit must not wait for it.
    code, out, err = run_python(FORK_DURING_CALL, DEFAULT)
    assert (code, out) == (0, "exit status 0\n" * 3), err
