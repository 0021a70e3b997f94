"""aia in a child forked from a process that used it: nothing may hang.
Every child runs under a time limit, so that a hang fails the test."""

import gc
import multiprocessing
import os
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
