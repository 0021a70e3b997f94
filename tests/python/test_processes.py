"""aia in a child forked from a process that used it: nothing may hang
(or, where it cannot work, it is refused).
Every child runs under a time limit, so that a hang fails the test."""

import gc
import multiprocessing
import os
import signal
import subprocess
import sys
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
