"""aia.VectorMissions and Mission.channels."""

import os
import pickle
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
        assert (changed.done == [m.done for m in alone]).all()
        states = v.states()
        for i, m in enumerate(alone):
            assert (states["det"][i] == m.state()["det"]).all()
            assert (states["positions"][i] == m.state()["positions"]).all()
    assert [m.flowtime for m in v.missions] == [m.flowtime for m in alone]
    assert all(m.success for m in v.missions)


def test_one_policy_keeps_the_state_of_every_mission_it_decides_for():
    # 257 missions deciding in turn with one random policy once lost every
    # policy's state at every step (256 were kept): none repeated its run.
    n = 300
    small = {"robots.count": 2, "targets.count": 2, "mission.max_steps": 6}
    v = aia.VectorMissions(n, DEFAULT, seed=40, overrides=small)
    shared = aia.builtin_policy("random")
    while not v.done.all():
        v.step(np.stack([shared.decide(m) for m in v.missions]))
    for i in (0, 150, n - 1):
        alone = aia.Mission(DEFAULT, seed=40 + i, overrides=small)
        own = aia.builtin_policy("random")
        while not alone.done:
            alone.step(own.decide(alone))
        assert (alone.state()["positions"] ==
                v.missions[i].state()["positions"]).all(), i


def test_vector_moves_are_checked():
    v = aia.VectorMissions(2, DEFAULT, seed=1, overrides=SMALL)
    with pytest.raises(aia.InputError, match=r"must have shape \(2, 3\), "
                       r"\(missions, robots\)"):
        v.step(np.zeros((3, 3), dtype=int))
    with pytest.raises(aia.InputError, match=r"moves\[1\]\[2\]: must be 0"):
        v.step([[0, 0, 0], [0, 0, 5]])
    with pytest.raises(aia.InputError,
                       match=r"n: must be an integer in \[1, 2147483647\]"):
        aia.VectorMissions(0, DEFAULT)


def test_more_missions_than_memory_holds_are_refused_before_they_are_made():
    # Ten million missions of a few hundred KiB each: refused after the
    # first few, not by a std::bad_alloc (or the machine swapping) later.
    with pytest.raises(aia.InputError, match=r"aia.VectorMissions: n: "
                       r"10000000 missions of this scenario need about \d+ "
                       r"MiB more \(\d+ KiB each\), and this machine has "
                       r"\d+ MiB available"):
        aia.VectorMissions(10 ** 7, DEFAULT, overrides=SMALL)
    # The most missions allowed: refused as soon (a list of their seeds,
    # made first, took the machine's memory).
    with pytest.raises(aia.InputError, match=r"aia.VectorMissions: n: "
                       r"2147483647 missions of this scenario need about"):
        aia.VectorMissions(2 ** 31 - 1, DEFAULT, overrides=SMALL)


def play(v, rounds):
    """Greedy moves for every mission for `rounds` steps; the results."""
    policies = [aia.builtin_policy("greedy") for _ in range(len(v))]
    out = []
    for _ in range(rounds):
        moves = np.stack([p.decide(m) for p, m in zip(policies, v.missions)])
        out.append(v.step(moves))
    return out


def test_autoreset_restarts_with_the_next_seed_and_reports_the_end():
    limit = {**SMALL, "mission.max_steps": 4}
    v = aia.VectorMissions(2, DEFAULT, seed=30, overrides=limit,
                           autoreset=True)
    results = play(v, 9)
    ends = [k for k, r in enumerate(results) if r.done.any()]
    assert ends == [3, 7]  # every 4 steps, both missions together
    first = results[3]
    assert first.truncated.all() and not first.terminated.any()
    assert first.steps.tolist() == [4, 4]
    assert first.info["_final_info"].tolist() == [True, True]
    assert [s["seed"] for s in first.info["final_info"]] == [30, 31]
    assert [s["steps"] for s in first.info["final_info"]] == [4, 4]
    # Each one's last state is the state its mission ended in.
    alone = aia.Mission(DEFAULT, seed=31, overrides=limit)
    greedy = aia.builtin_policy("greedy")
    while not alone.done:
        alone.step(greedy.decide(alone))
    assert (first.info["final_state"][1]["det"] ==
            alone.state()["det"]).all()
    # Restarted with the next seeds, in the order they ended.
    assert results[7].info["final_info"][0]["seed"] == 32
    assert results[7].info["final_info"][1]["seed"] == 33
    assert v.seeds.tolist() == [34, 35]
    assert [m.steps for m in v.missions] == [1, 1]
    assert results[4].info == {} and not results[4].done.any()


def test_a_mission_over_at_step_0_is_reported_done_with_steps_0():
    # Seed 1 of this world has its one target localized at step 0 (the
    # sensor sees the whole workspace), seed 2 not.
    over = {"robots.count": 3, "targets.count": 1, "sensor.range": 50}
    v = aia.VectorMissions(2, DEFAULT, seed=1, overrides=over,
                           autoreset=True)
    assert v.done.tolist() == [True, False]
    r = v.step(np.zeros((2, 3), dtype=int))
    assert r.steps.tolist() == [0, 1] and r.done.tolist() == [True, False]
    assert r.success.tolist() == [True, False]
    assert [f and f["seed"] for f in r.info["final_info"]] == [1, None]
    # Restarted with the next seed, 3, whatever its mission is at step 0.
    assert v.seeds.tolist() == [3, 2]
    assert v.missions[0].steps == 0


def test_a_vector_step_result_pickles():
    # What a worker process sends back through a pipe.
    limit = {**SMALL, "mission.max_steps": 2}
    v = aia.VectorMissions(2, DEFAULT, seed=30, overrides=limit,
                           autoreset=True)
    for r in play(v, 2):
        back = pickle.loads(pickle.dumps(r))
        for field in ("steps", "invalid_moves", "localized", "terminated",
                      "truncated", "success", "done"):
            assert (getattr(back, field) == getattr(r, field)).all()
            assert getattr(back, field).dtype == getattr(r, field).dtype
        assert back.info.keys() == r.info.keys()
    assert back.info["final_info"] == r.info["final_info"]  # the end
    assert (back.info["final_state"][1]["det"] ==
            r.info["final_state"][1]["det"]).all()


def test_reset_and_a_finished_row_without_autoreset():
    v = aia.VectorMissions(2, DEFAULT, seed=5, overrides=SMALL)
    states, info = v.reset(seed=40)
    assert info["seeds"].tolist() == [40, 41]
    assert states["det"].shape[0] == 2
    fresh = aia.Mission(DEFAULT, seed=41, overrides=SMALL)
    assert (states["det"][1] == fresh.state()["det"]).all()
    play(v, 2)
    _, info = v.reset()  # the next seeds
    assert info["seeds"].tolist() == [42, 43]
    assert [m.steps for m in v.missions] == [0, 0]
    # Without autoreset a finished mission keeps its end and ignores its row.
    short = aia.VectorMissions(1, DEFAULT, seed=2,
                               overrides={**SMALL, "mission.max_steps": 1})
    r = short.step([[0, 0, 0]])
    assert r.done.tolist() == [True] and r.info == {}
    r = short.step([[1, 1, 1]])
    assert r.steps.tolist() == [1] and r.done.tolist() == [True]


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


def test_autoreset_and_reset_read_no_file(tmp_path, monkeypatch):
    """The missions restart the scenario as read when they were made: a
    working directory changed since, or the file edited, changes nothing."""
    scenario = tmp_path / "s.yaml"
    scenario.write_text(Path(DEFAULT).read_text())
    monkeypatch.chdir(tmp_path)
    v = aia.VectorMissions(2, "s.yaml", seed=2, autoreset=True,
                           overrides={**SMALL, "mission.max_steps": 1})
    scenario.write_text("robots: {count: 4}\n")
    monkeypatch.chdir(SOURCE)
    r = v.step([[4, 4, 4]] * 2)
    assert r.done.tolist() == [True, True]
    assert v.seeds.tolist() == [4, 5]
    states, info = v.reset(seed=9)
    assert states["positions"].shape == (2, 3, 2)
    with pytest.raises(aia.InputError,
                       match=r"^aia\.VectorMissions\.reset: options: "):
        v.reset(options={"a": 1})
    assert v.reset(options={})[1]["seeds"].tolist() == [11, 12]


def test_a_vectors_mission_is_stepped_by_the_vector_only():
    v = aia.VectorMissions(2, DEFAULT, seed=2, overrides=SMALL)
    with pytest.raises(aia.InputError,
                       match=r"^aia\.Mission\.step: this mission is one of "
                             r"an aia\.VectorMissions"):
        v.missions[0].step([4, 4, 4])
    assert v.missions[0].steps == 0
    assert v.missions[0].channels().shape[0] == 3  # reading is allowed
    v.step([[4, 4, 4]] * 2)
    assert [m.steps for m in v.missions] == [1, 1]


def test_reset_without_a_seed_wraps_past_the_last_seed():
    # The seeds after 2^64 - 3, 2^64 - 2 are 2^64 - 1 and 0: reset() took
    # them as a seed out of range, a seed the caller never gave.
    v = aia.VectorMissions(2, DEFAULT, seed=2 ** 64 - 3, overrides=SMALL)
    _, info = v.reset()
    assert list(info["seeds"]) == [2 ** 64 - 1, 0]


def test_vector_channels_are_the_missions_channels():
    # One (n, N, C, H, W) array rendered on the threads: the same numbers
    # as each mission's own call, the search points included once asked for
    # at step 0; asked first later, refused as a mission refuses it.
    v = aia.VectorMissions(3, DEFAULT, seed=40, overrides=SMALL, threads=2)
    learned = dict(geodesic=True, reach_world=True, search=True, trail=True)
    first = v.channels(**learned)
    assert first.shape[:2] == (3, 3) and first.dtype == np.float32
    greedy = aia.builtin_policy("greedy")
    for _ in range(4):
        v.step(np.stack([greedy.decide(m) for m in v.missions]))
        for kw in (learned, {}, {"frame": "global"}):
            together = v.channels(**kw)
            alone = np.stack([m.channels(**kw) for m in v.missions])
            assert together.shape == alone.shape
            assert np.array_equal(together, alone)
    late = aia.VectorMissions(2, DEFAULT, seed=40, overrides=SMALL)
    late.step(np.zeros((2, 3), dtype=int))
    with pytest.raises(aia.InputError,
                       match=r"^aia.VectorMissions.channels: search: .*step "
                             r"0 of a mission \(this one is at step 1\)"):
        late.channels(geodesic=True, reach_world=True, search=True)
    with pytest.raises(aia.InputError,
                       match=r"^aia.VectorMissions.channels: channels: "
                             r"window: "):
        v.channels(window=2)
