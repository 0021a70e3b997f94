"""aia.VectorMissions and Mission.channels."""

import os
from pathlib import Path

import numpy as np
import pytest

import aia

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
DEFAULT = str(SOURCE / "scenarios" / "default.yaml")
SMALL = {"robots.count": 3, "targets.count": 2}


def test_missions_stepped_together_are_the_missions_stepped_alone():
    v = aia.VectorMissions(3, DEFAULT, seed=20, overrides=SMALL, threads=2)
    alone = [aia.Mission(DEFAULT, seed=20 + i, overrides=SMALL)
             for i in range(3)]
    assert len(v) == 3 and v.num_robots == 3
    greedy = [aia.builtin_policy("greedy") for _ in range(3)]
    mine = [aia.builtin_policy("greedy") for _ in range(3)]
    while not v.done.all():
        moves = np.stack([p.decide(m) for p, m in zip(greedy, v.missions)])
        changed = v.step(moves)
        for i, m in enumerate(alone):
            if not m.done:
                m.step(mine[i].decide(m))
        assert (changed["done"] == [m.done for m in alone]).all()
        states = v.states()
        for i, m in enumerate(alone):
            assert (states["det"][i] == m.state()["det"]).all()
            assert (states["positions"][i] == m.state()["positions"]).all()
    assert [m.flowtime for m in v.missions] == [m.flowtime for m in alone]
    assert all(m.success for m in v.missions)


def test_vector_moves_are_checked():
    v = aia.VectorMissions(2, DEFAULT, seed=1, overrides=SMALL)
    with pytest.raises(ValueError, match=r"\(missions, robots\) = \(2, 3\)"):
        v.step(np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"moves\[1\]\[2\]: must be 0"):
        v.step([[0, 0, 0], [0, 0, 5]])
    with pytest.raises(ValueError, match="n: must be at least 1"):
        aia.VectorMissions(0, DEFAULT)


def test_channels_come_from_the_cpp_renderer():
    m = aia.Mission(DEFAULT, seed=3, overrides=SMALL)
    c = m.channels()
    assert c.shape == (3, 4, 40, 40) and c.dtype == np.float32
    assert np.isfinite(c).all() and c.min() >= 0.0
    # The global frame shows the same obstacles to every robot.
    g = m.channels("global", cell=0.5)
    assert (g[:, 0] == g[0, 0]).all()
    assert g.shape[2:] == (40, 40)  # 20 m at 0.5 m a pixel
    assert m.channels(geodesic=True).shape[1] == 5
    with pytest.raises(aia.InputError, match=r"channels: window: must be an "
                       r"integer in \[4, 512\], got 2"):
        m.channels(window=2)
    with pytest.raises(aia.InputError, match="channels: frame: must be"):
        m.channels("sideways")
