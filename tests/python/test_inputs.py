"""Bad input from Python: each case one aia.InputError (a ValueError) on one
line that names the Python callable and argument, never a silent
conversion, another exception type or a crash (issue 39, docs/python.md)."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import aia

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
DEFAULT = str(SOURCE / "scenarios" / "default.yaml")
SMALL = {"robots.count": 3, "targets.count": 2}


def refused(f, *match):
    """f() raises aia.InputError whose one-line text holds every `match`."""
    with pytest.raises(aia.InputError) as e:
        f()
    text = str(e.value)
    assert "\n" not in text, text
    assert "command line" not in text, text
    for m in match:
        assert m in text, (m, text)
    return text


@pytest.fixture(scope="module")
def mission():
    return aia.Mission(DEFAULT, seed=1, overrides=SMALL)


@pytest.mark.parametrize("moves,match", [
    (np.array([1.7, 1.2, 0.3]), "got an array of float64"),
    ([1.7, 1, 0], "moves[0]: must be 0 (left)"),
    ([True, False, True], "moves[0]: must be 0 (left)"),
    ([1, True, 0], "got True (bool)"),
    (np.array([True, False, True]), "got an array of bool"),
    ([2.0, 0, 0], "got 2.0 (float)"),
    ([float("nan"), 0, 0], "got nan (float)"),
    ([float("inf"), 0, 0], "got inf (float)"),
    (np.zeros((3, 2), dtype=int), "got shape (3, 2)"),
    (np.zeros((3, 1), dtype=int), "got shape (3, 1)"),
    (np.zeros((1, 3), dtype=int), "got shape (1, 3)"),
    ([[0], [1], [2]], "got shape (3, 1)"),
    ([0, 0], "must have shape (3,), one move per robot, got shape (2,)"),
    ([0, 0, 5], "moves[2]: must be 0 (left), 1 (right), 2 (up), 3 (down) "
                "or 4 (stay), got 5"),
    ([0, 0, -1], "got -1"),
    ([0, 0, 2 ** 70], "got 1180591620717411303424"),
    (np.array([0, 0, 9], dtype=np.uint64), "got 9"),
    (["0", 0, 0], "got '0' (str)"),
    ([[0, 1], [2]], "shape"),
    (3, "must be a list or numpy array"),
    (range(3), "must be a list or numpy array of integers (one move per "
               "robot), each 0 (left), 1 (right), 2 (up), 3 (down) or 4 "
               "(stay), got range(0, 3)"),
    ("012", "must be a list or numpy array"),
    (None, "must be a list or numpy array"),
])
def test_bad_moves_are_refused_and_nothing_moves(mission, moves, match):
    before = mission.steps
    text = refused(lambda: mission.step(moves), match)
    assert text.startswith("aia.Mission.step: moves"), text
    assert mission.steps == before


def test_integer_moves_of_every_kind_are_taken(mission):
    before = mission.steps
    for moves in ([4, 4, 4], (4, 4, 4), np.array([4, 4, 4], dtype=np.uint8),
                  np.array([4, 4, 4], dtype=np.int32),
                  [np.int64(4), 4, aia.Move.STAY],
                  [aia.Move.STAY] * 3):
        mission.step(moves)
    assert mission.steps == before + 6


def test_the_move_enum():
    assert [int(m) for m in (aia.Move.LEFT, aia.Move.RIGHT, aia.Move.UP,
                             aia.Move.DOWN, aia.Move.STAY)] == [0, 1, 2, 3, 4]
    assert aia.Move.UP == 2 and aia.Move(3) == aia.Move.DOWN


@pytest.mark.parametrize("seed,match", [
    (-1, "seed: must be an integer in [0, 2^64 - 1] or None, got -1"),
    ("x", "got 'x' (str)"),
    (1.5, "got 1.5 (float)"),
    (True, "got True (bool)"),
    (2 ** 64, "got 18446744073709551616"),
])
def test_bad_seeds(seed, match):
    refused(lambda: aia.Mission(DEFAULT, seed=seed), "aia.Mission: ", match)
    refused(lambda: aia.VectorMissions(2, DEFAULT, seed=seed,
                                       overrides=SMALL),
            "aia.VectorMissions: seed: ")
    env = aia.parallel_env(DEFAULT, overrides=SMALL)
    refused(lambda: env.reset(seed=seed), "aia.ParallelEnv.reset: seed: ")


def test_big_seeds_are_seeds():
    assert aia.Mission(DEFAULT, seed=2 ** 64 - 1, overrides=SMALL).seed == \
        2 ** 64 - 1
    assert aia.Mission(DEFAULT, seed=np.uint64(7), overrides=SMALL).seed == 7


def test_overrides_name_the_argument_not_the_command_line():
    refused(lambda: aia.Mission(DEFAULT, overrides={"sensor.range": -1}),
            "aia.Mission: overrides: sensor.range: must be a number in "
            "[0.001, 10000], got -1")
    refused(lambda: aia.Mission(DEFAULT, overrides=[("a", 1)]),
            "aia.Mission: overrides: must be a dict")
    refused(lambda: aia.Mission(DEFAULT, overrides={"seed": object()}),
            "aia.Mission: overrides: seed: a value of type object is not a "
            "scenario value")
    refused(lambda: aia.Mission(3), "aia.Mission: scenario: must be a path")
    refused(lambda: aia.builtin_policy("decsb", p_v=2),
            "aia.builtin_policy: p_v: must be a number in [0, 1], got 2")


def test_evaluate_arguments(tmp_path):
    def left(m):
        return [0] * m.num_robots
    refused(lambda: aia.evaluate(left, ["2x1"], 1, out=tmp_path / "a",
                                 overrides={"sensor.range": -1},
                                 progress=False),
            "aia.evaluate: overrides: sensor.range: must be a number")
    refused(lambda: aia.evaluate(left, ["2x1"], 1.5, out=tmp_path / "b",
                                 progress=False),
            "aia.evaluate: seeds: must be an integer in [1, ", "got 1.5")
    refused(lambda: aia.evaluate(left, ["2x1"], 1, seed_base=-3,
                                 out=tmp_path / "c", progress=False),
            "aia.evaluate: seed_base: ", "got -3")
    refused(lambda: aia.evaluate(left, ["2x1"], 1, threads=-1,
                                 out=tmp_path / "d", progress=False),
            "aia.evaluate: threads: ", "got -1")
    refused(lambda: aia.evaluate(left, ["2x1"], 1, out=tmp_path / "e",
                                 progress="yes"),
            "aia.evaluate: progress: must be True, False or a callable")
    refused(lambda: aia.evaluate(42, ["2x1"], 1, out=tmp_path / "f"),
            "aia.evaluate: policy: must be callable")
    # More worlds than one evaluation takes: refused before any bar is
    # drawn or folder made (the bar went to stderr first).
    import contextlib
    import io
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        refused(lambda: aia.evaluate(left, ["2x1", "3x1"], 500001,
                                     out=tmp_path / "g"),
                "aia.evaluate: seeds: 2 sizes x 500001 seeds are 1000002 "
                "worlds, more than one evaluation takes (1000000)")
    assert err.getvalue() == ""
    assert not (tmp_path / "g").exists()
    (tmp_path / "file").write_text("x")
    refused(lambda: aia.evaluate(left, ["2x1"], 1, out=tmp_path / "file",
                                 progress=False),
            "aia.evaluate: out: ")


def test_vector_missions_arguments():
    refused(lambda: aia.VectorMissions(2, DEFAULT, threads=-1),
            "aia.VectorMissions: threads: must be an integer >= 0, got -1")
    refused(lambda: aia.VectorMissions(2.0, DEFAULT),
            "aia.VectorMissions: n: ", "got 2.0 (float)")
    refused(lambda: aia.VectorMissions(0, DEFAULT),
            "aia.VectorMissions: n: must be an integer in [1, 2147483647], "
            "got 0")
    v = aia.VectorMissions(2, DEFAULT, seed=1, overrides=SMALL)
    refused(lambda: v.step(np.zeros((2, 3))), "got an array of float64")
    refused(lambda: v.step([[float("nan"), 0, 0], [0, 0, 0]]),
            "aia.VectorMissions.step: moves[0][0]: ", "got nan (float)")
    refused(lambda: v.step(np.zeros((3, 3), dtype=int)),
            "must have shape (2, 3)", "got shape (3, 3)")
    refused(lambda: v.step(np.zeros(6, dtype=int)), "got shape (6,)")
    refused(lambda: v.reset(seed=-1), "aia.VectorMissions.reset: seed: ")


def test_a_closed_env_refuses_everything():
    env = aia.parallel_env(DEFAULT, overrides=SMALL)
    refused(lambda: env.step({}), "aia.ParallelEnv.step: call reset() "
            "before step()")
    refused(lambda: env.state(), "call reset() before state()")
    env.reset(seed=1)
    env.close()
    for call, what in ((lambda: env.state(), "state"),
                       (lambda: env.state_dict(), "state_dict"),
                       (lambda: env.step({"robot_0": 0}), "step"),
                       (lambda: env.reset(), "reset")):
        refused(call, f"aia.ParallelEnv.{what}: the env is closed")


def test_env_actions():
    env = aia.parallel_env(DEFAULT, overrides=SMALL)
    env.reset(seed=1)
    ok = {a: 0 for a in env.agents}
    for bad, match in ((2.0, "got 2.0 (float)"), (True, "got True (bool)"),
                       (4, "must be an integer in [0, 3], got 4"),
                       (np.float64(1), "(float64)"), ("1", "(str)")):
        refused(lambda: env.step({**ok, "robot_1": bad}),
                "aia.ParallelEnv.step: actions['robot_1']: ", match)
    refused(lambda: env.step({**ok, "robot_9": 0}), "unknown agent 'robot_9'")
    refused(lambda: env.step([0, 0, 0]), "actions: must be a dict")
    env.step({a: np.int64(1) for a in env.agents})  # numpy integers are moves


def test_an_action_for_an_agent_that_left():
    env = aia.parallel_env(str(SOURCE / "scenarios" / "robustness.yaml"),
                           seed=0)
    env.reset()
    greedy = aia.builtin_policy("greedy")
    while env.agents:
        moves = greedy.decide(env.mission)
        live = list(env.agents)
        env.step({a: int(moves[env.possible_agents.index(a)]) for a in live})
        gone = [a for a in live if a not in env.agents]
        if env.agents and gone:
            actions = {a: 0 for a in env.agents}
            actions[gone[0]] = 0
            refused(lambda: env.step(actions),
                    f"actions['{gone[0]}']: {gone[0]} is not among the "
                    "agents (it left at step")
            return
    pytest.fail("no robot left while others went on")


def test_dataset_arguments(tmp_path):
    refused(lambda: aia.Dataset(12), "aia.Dataset: paths: ")
    refused(lambda: aia.Dataset([]), "aia.Dataset: paths: ")


def test_channel_settings_name_the_callable(mission):
    refused(lambda: mission.channels(window=2), "aia.Mission.channels: "
            "channels: window: must be an integer in [4, 512], got 2")


def test_render_arguments(mission):
    refused(lambda: mission.render(10.5, 100), "aia.Mission.render: width: ",
            "got 10.5 (float)")
    refused(lambda: mission.render(640, 8), "aia.Mission.render: height: "
            "must be an integer in [16, 8192], got 8")


def test_builtin_policy_arguments(mission):
    greedy = aia.builtin_policy("greedy")
    refused(lambda: greedy.decide("mission"), "mission: must be an "
            "aia.Mission")
    refused(lambda: aia.builtin_policy(3), "aia.builtin_policy: name: ")
    refused(lambda: aia.builtin_policy("nope"), "aia.builtin_policy: name: "
            "unknown policy 'nope'")


BINARY = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))


@pytest.fixture(scope="module")
def shard(tmp_path_factory):
    """One small dataset shard made by `aia dataset`."""
    import subprocess
    out = tmp_path_factory.mktemp("shard")
    r = subprocess.run([BINARY, "dataset", "--episodes", "1", "--size", "2x2",
                        "--max-steps", "3", "--out", str(out), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    (path,) = out.glob("*.sqlite")
    return path


@pytest.mark.parametrize("sql,match", [
    ("UPDATE worlds SET width = 1e12", "width and height must be in"),
    ("UPDATE worlds SET height = 1e999", "width and height must be in"),
    ("UPDATE worlds SET width = 1e4, height = 1e4", "at most 5e7 cells"),
    ("UPDATE worlds SET lattice_step = 0", "lattice_step must be in"),
    ("UPDATE worlds SET map_cell = 1e-9", "map_cell must be in"),
    ("UPDATE worlds SET robot_radius = 1e300", "robot_radius must be in"),
    ("UPDATE worlds SET eps = -1", "eps must be above 0"),
    ("UPDATE samples SET x = 1e999 WHERE rowid = 1",
     "position outside the workspace"),
    ("UPDATE samples SET y = -50 WHERE rowid = 1",
     "position outside the workspace"),
    # SQLite converts between types at will: a label 'x' was read as 0,
    # 1.7 as 1, a position 'abc' as 0.0 (a review, 2026-12-07).
    ("UPDATE samples SET label = 'x' WHERE rowid = 1",
     "column label holds text, not an integer"),
    ("UPDATE samples SET label = 1.7 WHERE rowid = 1",
     "column label holds a real number, not an integer"),
    ("UPDATE samples SET x = 'abc' WHERE rowid = 1",
     "column x holds text, not a number"),
    ("UPDATE worlds SET flowtime = 'zz'", "column flowtime holds text"),
    ("UPDATE samples SET step = -5 WHERE rowid = 1", "step or robot out of "
     "range"),
    ("UPDATE worlds SET obstacles = zeroblob(320000)",
     "10000 obstacle boxes, more than a world has (5000)"),
    ("UPDATE samples SET neighbours = zeroblob(8000) WHERE rowid = 1",
     "neighbours or targets blob size"),
])
def test_a_damaged_dataset_is_refused(shard, tmp_path, sql, match):
    """A shard edited to nonsense (a world 1e12 m wide, a lattice step of 0,
    a robot at infinity) gets one error line and exit 2 from `aia train`
    and an aia.InputError from aia.Dataset, never a crash, a hang or a map
    the size of the memory (found by fuzzing, 2026-12-06)."""
    import shutil
    import sqlite3
    import subprocess
    folder = tmp_path / "d"
    folder.mkdir()
    damaged = folder / shard.name
    shutil.copy(shard, damaged)
    with sqlite3.connect(damaged) as db:
        db.execute(sql)
    r = subprocess.run([BINARY, "train", "--data", str(folder), "--epochs", "1",
                        "--out", str(tmp_path / "m.pt"), "--quiet"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert r.stderr.startswith(f"error: {damaged}: --data: episode "), r.stderr
    assert r.stderr.count("\n") == 1 and match in r.stderr, r.stderr
    with pytest.raises(aia.InputError) as e:
        aia.Dataset(folder)
    assert match in str(e.value)


# --- A second pass over the Python API (2026-12-06), each case a finding.

def test_a_mission_takes_one_call_at_a_time():
    """Two threads stepping one mission: before, the process crashed
    (SIGSEGV, or an internal check in the filter). Now a call made while
    the other thread's is inside is refused, and every step taken counts."""
    import threading
    m = aia.Mission(DEFAULT, seed=2, overrides={"robots.count": 20,
                                                "targets.count": 20,
                                                "mission.max_steps": 100000})
    taken, errors, other = [0, 0], [], []

    def run(k):
        for _ in range(40):
            try:
                m.step([4] * m.num_robots)
                taken[k] += 1
            except aia.InputError as e:
                errors.append(str(e))
            except Exception as e:  # noqa: BLE001 - any other is a finding
                other.append(repr(e))

    threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not other, other
    assert m.steps == sum(taken)
    assert sum(taken) + len(errors) == 80
    for e in errors:
        assert "another thread is inside aia.Mission.step on this object" \
            in e, e


def test_string_overrides_stay_strings_and_numpy_scalars_are_values():
    m = aia.Mission(DEFAULT, seed=1, overrides={**SMALL, "name": "run # 2"})
    assert m.summary()["scenario"] == "run # 2"  # not cut at the '#'
    refused(lambda: aia.Mission(DEFAULT, overrides={"robots.count": "3"}),
            "robots.count: must be an integer", 'got "3"')
    refused(lambda: aia.Mission(DEFAULT, overrides={"sensor.range": ".5"}),
            "sensor.range: must be a number", 'got ".5"')
    refused(lambda: aia.Mission(DEFAULT, overrides={"workspace.size":
                                                    "[30, 30]"}),
            "workspace.size")
    m = aia.Mission(DEFAULT, seed=1, overrides={
        "robots.count": np.int64(3), "sensor.range": np.float32(2.5),
        "sensor.line_of_sight": np.bool_(False), "targets.count": 2})
    assert m.num_robots == 3
    assert aia.Mission(DEFAULT, seed=1, overrides={
        **SMALL, "mission.decisions": "async"}).asynchronous


def test_words_inside_list_and_dict_overrides_stay_words():
    # JSON quoted them ("random"), and a quoted keyword is a string: a list
    # of failures or a generator block given as Python containers was
    # refused, naming the top key.
    m = aia.Mission(DEFAULT, seed=1, overrides={
        **SMALL, "communication.failures": [{"robot": "random", "step": 3}],
        "workspace.obstacles.random.count": 0,
        "workspace.obstacles.generator": {"type": "rooms", "door": 1.0},
        "workspace.size": np.array([30.0, 30.0])})
    assert m.num_robots == 3
    refused(lambda: aia.Mission(DEFAULT, overrides={
        **SMALL, "communication.failures": [{"robot": "some", "step": 3}]}),
            "overrides: communication.failures: must be an integer >= 0 or "
            "random, got some")
    refused(lambda: aia.Mission(DEFAULT, overrides={
        "workspace.size": {1: 2}}), "a mapping's keys are strings")
    # The env made by aec_env names aec_env.
    refused(lambda: aia.aec_env(DEFAULT, overrides={
        **SMALL, "mission.decisions": "async"}), "aia.aec_env: ")


def test_keys_that_change_nothing_are_scenario_warnings():
    # What aia's commands print as "warning: FILE:LINE: key: ..." lines.
    with pytest.warns(aia.ScenarioWarning,
                      match=r"^aia.Mission: overrides: communication.range: "
                            r"applies to communication.mode range only"):
        aia.Mission(DEFAULT, overrides={**SMALL, "communication.range": 5})
    import warnings
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        aia.Mission(DEFAULT, overrides=SMALL)
        aia.VectorMissions(2, DEFAULT, seed=1, overrides={
            **SMALL, "robots.diff_drive.max_speed": 1.0})
    texts = [str(w.message) for w in seen
             if issubclass(w.category, aia.ScenarioWarning)]
    assert len(texts) == 1 and "aia.VectorMissions: overrides: " \
        "robots.diff_drive.max_speed: sets max_speed" in \
        texts[0], texts


def test_array_shaped_actions_and_seeds_are_refused():
    env = aia.parallel_env(DEFAULT, overrides=SMALL)
    env.reset(seed=1)
    ok = {a: 0 for a in env.agents}
    for bad in (np.array([1]), np.array(1.0), np.array([[1]])):
        refused(lambda: env.step({**ok, "robot_1": bad}),
                "actions['robot_1']: must be an integer in [0, 3]", "ndarray")
    env.step({**ok, "robot_1": np.array(1)})  # no shape: an integer
    refused(lambda: env.reset(seed=np.array([5])), "seed: must be an integer")


def test_env_checks_overrides_options_penalty_and_render_after_close():
    for bad in ("", 0, [("robots.count", 3)], "ab"):
        refused(lambda: aia.parallel_env(DEFAULT, overrides=bad),
                "aia.parallel_env: overrides: must be a dict")
    refused(lambda: aia.parallel_env(DEFAULT, overrides=SMALL,
                                     step_penalty=np.complex128(1 + 2j)),
            "step_penalty: must be a finite number")
    env = aia.parallel_env(DEFAULT, overrides=SMALL)
    for bad in ("x", 42, {"foo": 1}):
        refused(lambda: env.reset(seed=1, options=bad),
                "aia.ParallelEnv.reset: options: this env takes no options")
    env.reset(seed=1, options={})
    env.close()
    refused(lambda: env.render(), "aia.ParallelEnv.render: the env is closed")


def test_a_mission_over_at_reset_has_no_agents():
    """A prior already within eps: success at step 0. reset lists no agent
    (before, it listed them all and their first step was refused)."""
    over = {**SMALL, "mission.eps": 1e30}
    env = aia.parallel_env(DEFAULT, overrides=over)
    observations, infos = env.reset(seed=1)
    assert env.mission.done and env.mission.success
    assert env.agents == [] and observations == {} and infos == {}
    aec = aia.aec_env(DEFAULT, overrides=over)
    aec.reset(seed=1)
    assert aec.agents == [] and aec.agent_selection is None
    assert list(aec.agent_iter()) == []
    refused(lambda: aec.last(), "aia.AECEnv.last: no agent is selected")


def test_the_aec_env_refuses_a_bad_action_at_once_and_goes_on():
    aec = aia.aec_env(DEFAULT, overrides=SMALL)
    aec.reset(seed=3)
    refused(lambda: aec.step(7), "aia.AECEnv.step: action: must be an "
            "integer in [0, 3], got 7")
    refused(lambda: aec.step(None), "aia.AECEnv.step: action: robot_0 is "
            "live")
    refused(lambda: aec.observe("robot_99"), "unknown agent 'robot_99'")
    assert aec.render_mode is None and aec.state_space is not None
    # PettingZoo's loop, to the end of the mission.
    rng = np.random.default_rng(0)
    for agent in aec.agent_iter(max_iter=3000):
        _, _, term, trunc, info = aec.last()
        aec.step(None if term or trunc else
                 aec.action_space(agent).sample(info["action_mask"]))
    assert aec.agents == [] and aec.unwrapped.mission.done
    aec.close()
    for call in (lambda: aec.last(), lambda: aec.observe("robot_0"),
                 lambda: aec.step(0)):
        refused(call, "the env is closed")
    del rng


def test_channel_settings_need_what_they_need(mission):
    for settings, key, needs in (({"search": True}, "search", "reach_world"),
                                 ({"reach_world": True}, "reach_world",
                                  "geodesic"),
                                 ({"geodesic": True, "reach_detour": 0.5},
                                  "reach_detour", "reach_world"),
                                 ({"geodesic": True, "reach_second": True},
                                  "reach_second", "reach_world")):
        refused(lambda: mission.channels(**settings), "aia.Mission.channels: "
                f"channels: {key}: needs {needs}")


def test_stand_in_spaces_take_a_mask():
    from aia import env as env_module
    d = env_module.Discrete(4, seed=0)
    mask = np.array([0, 0, 1, 0], dtype=np.int8)
    assert all(d.sample(mask) == 2 for _ in range(20))
    assert d.sample(np.zeros(4, dtype=np.int8)) == 0
    assert 3 in d and 4 not in d
    assert d.seed(5) == [5]
    refused(lambda: d.sample(np.array([1, 1])), "Discrete.sample: mask")


def test_channels_are_read_at_the_lattice_step():
    # 4 km at a 10 m step: one pixel per lattice step, 400 x 400, whatever
    # the cell asked for (at 0.5 m pixels, 8000 x 8000 whole-map grids,
    # some 4 GB, were refused until the pixel followed the step).
    m = aia.Mission(DEFAULT, seed=1, overrides={
        "workspace.size": [4000, 4000], "workspace.cell": 10,
        "workspace.obstacles.random.count": 0, "robots.step": 10,
        "robots.radius": 1, "sensor.range": 30, "robots.count": 1,
        "targets.count": 1})
    at_step = m.channels(cell=10.0)
    assert at_step.shape == (1, 4, 40, 40)
    assert np.array_equal(m.channels(), at_step)
    assert np.array_equal(m.channels(cell=2.0), at_step)


def test_paths_with_a_nul_byte_are_refused():
    refused(lambda: aia.Mission(DEFAULT + "\0x.yaml"), "aia.Mission: "
            "scenario: a path cannot hold a NUL byte")


def test_a_view_inside_evaluate_names_the_call(tmp_path):
    seen = []

    def decide(m):
        for call in (lambda: m.max_steps, lambda: m.summary()):
            try:
                call()
            except aia.InputError as e:
                seen.append(str(e))
        return [4] * m.num_robots

    aia.evaluate(decide, sizes=["2x1"], seeds=1, out=str(tmp_path),
                 name="idle", progress=False)
    assert seen[0].startswith("aia.Mission.max_steps: a mission seen by a "
                              "policy inside aia.evaluate has none"), seen
    assert seen[1].startswith("aia.Mission.summary: a mission seen by a "
                              "policy inside aia.evaluate"), seen


def test_a_file_that_is_not_a_shard(tmp_path):
    import sqlite3
    other = tmp_path / "other.sqlite"
    sqlite3.connect(other).execute("CREATE TABLE t (x)").connection.close()
    text = tmp_path / "text.sqlite"
    text.write_text("not a database\n" * 100)
    refused(lambda: aia.Dataset([str(other)]), "': not an aia dataset "
            "shard (SQLite: no such table: meta)")
    refused(lambda: aia.Dataset([str(text)]), "not an aia dataset shard")
    # Named as every Python error is: the callable first, then the file.
    for path in (other, text, tmp_path / "nope.sqlite"):
        with pytest.raises(aia.InputError) as e:
            aia.Dataset([str(path)])
        assert str(e.value).startswith(f"aia.Dataset: paths: '{path}': "), \
            str(e.value)


def test_a_comma_decimal_locale_is_refused_in_one_line(tmp_path):
    """A host that sets LC_NUMERIC to a comma-decimal locale: MuJoCo's model
    reader and aia's writers follow it (the model was written with 0,005
    and refused with MuJoCo's raw message). One InputError naming the fix,
    and aia works again once the locale is C."""
    made = subprocess.run(
        ["localedef", "-i", "de_DE", "-f", "UTF-8",
         str(tmp_path / "de_DE.UTF-8")], capture_output=True)
    if not (tmp_path / "de_DE.UTF-8").exists():
        pytest.skip("cannot make a de_DE locale here: " +
                    made.stderr.decode(errors="replace")[:200])
    program = (
        "import locale, aia, sys\n"
        "locale.setlocale(locale.LC_NUMERIC, 'de_DE.UTF-8')\n"
        "try:\n"
        "    aia.Mission(sys.argv[1])\n"
        "    print('no error')\n"
        "except aia.InputError as e:\n"
        "    print(e)\n"
        "locale.setlocale(locale.LC_NUMERIC, 'C')\n"
        "print(aia.Mission(sys.argv[1]).num_robots)\n")
    done = subprocess.run(
        [sys.executable, "-c", program, DEFAULT], capture_output=True,
        text=True, env={**os.environ, "LOCPATH": str(tmp_path)}, timeout=300)
    assert done.returncode == 0, done.stderr
    first, second = done.stdout.splitlines()
    assert first.startswith("locale: LC_NUMERIC: this process writes numbers "
                            "with ',' as the decimal point"), first
    assert "locale.setlocale(locale.LC_NUMERIC, 'C')" in first
    assert second == "10"


def test_a_section_after_a_key_in_it_is_refused():
    # It dropped the key in silence ({"robots.count": 3, "robots": {...}}
    # ran 2 robots), as two --set flags would; a key after its section sets
    # it there.
    refused(lambda: aia.Mission(DEFAULT, overrides={
        "robots.count": 3, "robots": {"count": 2}}),
        "aia.Mission: overrides: robots: replaces the whole section, and an "
        "earlier key gives robots.count in it")
    m = aia.Mission(DEFAULT, overrides={"robots": {"count": 2},
                                        "robots.count": 3})
    assert m.num_robots == 3
