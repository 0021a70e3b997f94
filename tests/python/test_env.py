"""aia.parallel_env against the PettingZoo ParallelEnv API (pettingzoo's own
parallel_api_test when pettingzoo imports; it is not packaged in Debian, so
check_api below checks what it checks) and against its documented
rewards; aia.aec_env against the AEC API."""

import os
from pathlib import Path

import numpy as np
import pytest

import aia

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
DEFAULT = str(SOURCE / "scenarios" / "default.yaml")
ROBUSTNESS = str(SOURCE / "scenarios" / "robustness.yaml")


def check_api(env, steps):
    observations, infos = env.reset(seed=42)
    assert isinstance(observations, dict) and isinstance(infos, dict)
    assert set(observations) == set(env.agents) == set(infos)
    assert set(env.agents) <= set(env.possible_agents)
    assert env.possible_agents == [f"robot_{i}"
                                   for i in range(env.max_num_agents)]
    for a in env.agents:
        assert env.observation_space(a).contains(observations[a]), a
        assert env.action_space(a).n == 4
        assert env.observation_space(a) is env.observation_spaces[a]
        assert env.action_space(a) is env.action_spaces[a]
        assert set(infos[a]["action_mask"]) <= {0, 1}
    for _ in range(steps):
        if not env.agents:
            break
        live = list(env.agents)
        actions = {a: env.action_space(a).sample() for a in live}
        for a in live:
            assert env.action_space(a).contains(actions[a])
        out = env.step(actions)
        assert len(out) == 5
        for d in out:
            assert isinstance(d, dict) and set(d) == set(live)
        observations, rewards, terminations, truncations, _ = out
        for a in live:
            assert env.observation_space(a).contains(observations[a])
            assert isinstance(rewards[a], float)
            assert isinstance(terminations[a], bool)
            assert isinstance(truncations[a], bool)
            gone = terminations[a] or truncations[a]
            assert (a not in env.agents) == gone
    with pytest.raises(KeyError):
        env.action_space("robot_x")


def test_the_parallel_api():
    env = aia.parallel_env(DEFAULT, seed=1,
                           overrides={"robots.count": 4, "targets.count": 3})
    check_api(env, 400)  # random moves: success or the step limit
    assert env.agents == [] and env.mission.done
    # Success: every remaining agent terminates and agents is empty.
    env.reset(seed=3)
    greedy = aia.builtin_policy("greedy")
    while env.agents:
        moves = greedy.decide(env.mission)
        _, _, term, trunc, _ = env.step(
            {a: int(moves[env.possible_agents.index(a)]) for a in env.agents})
    assert env.mission.success and all(term.values())
    assert not any(trunc.values())
    env.close()


def test_truncation_past_max_steps():
    env = aia.parallel_env(DEFAULT, overrides={"mission.max_steps": 3})
    env.reset(seed=2)
    for k in range(3):
        assert env.agents
        _, _, term, trunc, _ = env.step({a: 0 for a in env.agents})
    assert all(trunc.values()) and not any(term.values())
    assert env.agents == []


def test_a_failed_robot_leaves_the_agents():
    env = aia.parallel_env(ROBUSTNESS, seed=0)
    env.reset()
    greedy = aia.builtin_policy("greedy")
    left = set()
    while env.agents:
        moves = greedy.decide(env.mission)
        live = list(env.agents)
        _, _, term, _, _ = env.step(
            {a: int(moves[env.possible_agents.index(a)]) for a in live})
        active = env.state_dict()["active"]
        for a in live:
            i = env.possible_agents.index(a)
            if not active[i]:
                assert term[a] and a not in env.agents
                left.add(a)
    assert left, "the robustness scenario fails some robot"


def test_rewards_are_the_drop_of_the_own_summed_log_det():
    penalty = 0.25
    env = aia.parallel_env(DEFAULT, overrides={"robots.count": 3,
                                               "targets.count": 2},
                           step_penalty=penalty)
    env.reset(seed=9)

    def own(state):
        with np.errstate(divide="ignore"):
            return np.maximum(np.log(state["det"]),
                              np.log(state["eps"])).sum(axis=1)

    before = own(env.state_dict())
    _, rewards, _, _, _ = env.step({a: 1 for a in env.agents})
    after = own(env.state_dict())
    for i, a in enumerate(env.possible_agents):
        assert rewards[a] == pytest.approx(before[i] - after[i] - penalty)


def test_same_seed_same_observations_and_rewards():
    def run():
        env = aia.parallel_env(DEFAULT, overrides={"robots.count": 3,
                                                   "targets.count": 2})
        obs, _ = env.reset(seed=5)
        trace = [obs["robot_1"]["channels"].copy()]
        for k in range(5):
            obs, r, _, _, _ = env.step({a: k % 4 for a in env.agents})
            trace.append(obs["robot_1"]["channels"].copy())
            trace.append(np.array([r[a] for a in sorted(r)]))
        return trace
    for x, y in zip(run(), run()):
        assert (x == y).all()


def test_bad_actions():
    env = aia.parallel_env(DEFAULT, overrides={"robots.count": 2,
                                               "targets.count": 1})
    with pytest.raises(aia.InputError, match="reset"):
        env.step({})
    env.reset(seed=1)
    with pytest.raises(aia.InputError, match="no move for robot_1"):
        env.step({"robot_0": 0})
    with pytest.raises(aia.InputError, match=r"actions\['robot_0'\]: must "
                       r"be an integer in \[0, 3\], got 7"):
        env.step({"robot_0": 7, "robot_1": 0})
    with pytest.raises(aia.InputError, match="render_mode"):
        aia.parallel_env(DEFAULT, render_mode="human")
    assert env.render() is None  # no render_mode
    shown = aia.parallel_env(DEFAULT, render_mode="rgb_array",
                             overrides={"robots.count": 2, "targets.count": 1})
    shown.reset(seed=1)
    assert shown.render(160, 120).shape == (120, 160, 3)


def test_rewards_follow_aia_runs_trace(tmp_path):
    """The env driven by the built-in greedy policy earns, at every step,
    the rewards that aia run's trace.csv (every robot's det Sigma) gives."""
    import csv
    import subprocess
    binary = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
    r = subprocess.run([binary, "run", DEFAULT, "--seed", "8", "--policy",
                        "greedy", "--trace", "full", "--out", str(tmp_path),
                        "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    det = {}
    with open(tmp_path / "trace.csv") as f:
        for row in csv.DictReader(f):
            det[(int(row["step"]), int(row["target"]))] = [
                float(v) for c, v in row.items() if c.startswith("det_r")]
    env = aia.parallel_env(DEFAULT, step_penalty=0.0)
    env.reset(seed=8)
    eps = env.state_dict()["eps"]
    targets = env.mission.num_targets

    def own(step):
        d = np.array([det[(step, k)] for k in range(targets)]).T
        return np.maximum(np.log(d), np.log(eps)).sum(axis=1)

    greedy = aia.builtin_policy("greedy")
    step = 0
    while env.agents:
        moves = greedy.decide(env.mission)
        _, rewards, _, _, _ = env.step(
            {a: int(moves[env.possible_agents.index(a)]) for a in env.agents})
        step += 1
        want = own(step - 1) - own(step)
        for a, got in rewards.items():
            # trace.csv prints 7 significant digits
            assert got == pytest.approx(want[env.possible_agents.index(a)],
                                        abs=1e-5), (step, a)
    assert (step, 0) in det and (step + 1, 0) not in det


def test_spaces_are_each_agents_own():
    env = aia.parallel_env(DEFAULT, overrides={"robots.count": 3,
                                               "targets.count": 2})
    assert env.unwrapped is env
    spaces = [env.action_space(a) for a in env.possible_agents]
    assert len({id(s) for s in spaces}) == 3
    assert spaces[0] == spaces[1]
    spaces[0].seed(7)
    spaces[1].seed(7)
    spaces[2].seed(8)
    a = [spaces[0].sample() for _ in range(20)]
    assert a == [spaces[1].sample() for _ in range(20)]
    # Seeding robot_0's again replays it and leaves robot_1's stream alone.
    spaces[0].seed(7)
    assert [spaces[0].sample() for _ in range(20)] == a
    assert spaces[2].sample() is not None
    assert env.observation_spaces["robot_2"] is not \
        env.observation_spaces["robot_0"]
    assert not env.action_space("robot_0").contains(2.0)
    assert not env.action_space("robot_0").contains(True)
    assert env.action_space("robot_0").contains(np.int64(3))


def test_state_is_an_array_and_state_dict_keeps_the_truth():
    env = aia.parallel_env(DEFAULT, overrides={"robots.count": 3,
                                               "targets.count": 2})
    _, infos = env.reset(seed=4)
    s = env.state()
    assert s.dtype == np.float32 and s.shape == env.state_space.shape
    assert s.shape == (3 * 3 + 3 * 2 + 1,)
    assert env.state_space.contains(s)
    d = env.state_dict()
    assert "truth" in d
    np.testing.assert_allclose(s[:6], (d["positions"] / d["workspace"])
                               .ravel(), rtol=1e-6)
    assert (s[6:9] == 1).all()  # every robot active
    assert ((s[9:11] >= 0) & (s[9:11] <= 1.0 + 1e-6)).all()
    assert s[-1] == 0.0
    env.step({a: 1 for a in env.agents})
    assert env.state()[-1] == pytest.approx(1 / env.mission.max_steps)
    masks = env.mission.valid_moves()
    for i, a in enumerate(env.possible_agents):
        assert (infos[a]["action_mask"] ==
                aia.Mission(DEFAULT, seed=4, overrides={
                    "robots.count": 3, "targets.count": 2})
                .valid_moves()[i]).all()
    assert masks.shape == (3, 4)


def test_the_aec_env_steps_the_mission_once_every_agent_acted():
    small = {"robots.count": 3, "targets.count": 2}
    aec = aia.aec_env(DEFAULT, overrides=small)
    par = aia.parallel_env(DEFAULT, overrides=small)
    aec.reset(seed=6)
    par.reset(seed=6)
    rng = np.random.default_rng(0)
    turns = 0
    while aec.agents:
        round_actions = {a: int(rng.integers(4)) for a in par.agents}
        _, rewards, terms, truncs, _ = par.step(round_actions)
        acted = set()
        while len(acted) < len(round_actions):
            a = aec.agent_selection
            obs, _, term, trunc, info = aec.last()
            assert not (term or trunc) and a not in acted
            assert aec.observation_space(a).contains(obs)
            assert aec.unwrapped.mission.steps == par.mission.steps - 1
            aec.step(round_actions[a])
            acted.add(a)
            turns += 1
        assert aec.unwrapped.mission.steps == par.mission.steps
        for a in round_actions:
            assert aec.rewards[a] == rewards[a]
            assert aec.terminations[a] == terms[a]
            assert aec.truncations[a] == truncs[a]
        # Ended agents are stepped with None, then leave.
        while aec.agents and (aec.terminations[aec.agent_selection] or
                              aec.truncations[aec.agent_selection]):
            with pytest.raises(aia.InputError, match="step it with None"):
                aec.step(0)
            aec.step(None)
        if turns > 3 * 400:
            break
    assert not aec.agents and not par.agents
    assert aec.agent_selection is None


def test_pettingzoos_own_parallel_api_test():
    test = pytest.importorskip("pettingzoo.test")
    env = aia.parallel_env(DEFAULT, seed=1,
                           overrides={"robots.count": 3, "targets.count": 2,
                                      "mission.max_steps": 30})
    test.parallel_api_test(env, num_cycles=40)


def test_an_async_mission_is_not_an_env():
    with pytest.raises(aia.InputError, match="mission.decisions: async"):
        aia.parallel_env(DEFAULT, overrides={"mission.decisions": "async"})


def test_the_env_keeps_the_scenario_it_was_made_from(tmp_path, monkeypatch):
    """Resets restart the scenario as read when the env was made: not as
    edited since, and not read again from another working directory."""
    scenario = tmp_path / "s.yaml"
    scenario.write_text(Path(DEFAULT).read_text())
    monkeypatch.chdir(tmp_path)
    env = aia.parallel_env("s.yaml", seed=4)
    first, _ = env.reset(seed=4)
    scenario.write_text("robots: {count: 4}\n")
    monkeypatch.chdir(SOURCE)
    again, _ = env.reset(seed=4)
    assert sorted(again) == sorted(first) == env.possible_agents
    for a in first:
        for k in first[a]:
            assert np.array_equal(first[a][k], again[a][k]), (a, k)


def test_the_env_names_itself_and_warns_once():
    with pytest.raises(aia.InputError, match=r"^aia\.parallel_env: seed: "):
        aia.parallel_env(DEFAULT, seed=-1)
    with pytest.raises(aia.InputError,
                       match=r"^aia\.parallel_env: overrides: foo\.bar: "
                             r"unknown key"):
        aia.parallel_env(DEFAULT, overrides={"foo.bar": 1})
    with pytest.warns(aia.ScenarioWarning) as said:
        env = aia.parallel_env(DEFAULT,
                               overrides={"communication.range": 3})
        env.reset()
        env.reset()
    assert len(said) == 1
    assert str(said[0].message).startswith(
        "aia.parallel_env: overrides: communication.range: ")


def test_a_closed_env_refuses_its_spaces_and_the_aec_env_has_no_agents():
    env = aia.parallel_env(DEFAULT)
    env.reset(seed=1)
    assert aia.Move.LEFT in env.action_space("robot_0")
    assert aia.Move.STAY not in env.action_space("robot_0")  # 4 moves
    env.close()
    for call in (env.action_space, env.observation_space):
        with pytest.raises(aia.InputError, match="the env is closed"):
            call("robot_0")
    aec = aia.aec_env(DEFAULT)
    aec.reset(seed=1)
    assert aec.agents
    aec.close()
    assert aec.agents == [] and aec.agent_selection is None
    assert list(aec.agent_iter()) == []


def test_the_aec_env_names_itself():
    aec = aia.aec_env(DEFAULT)
    with pytest.raises(aia.InputError, match=r"^aia\.AECEnv\.state: call "
                                             r"reset\(\) before state\(\)"):
        aec.state()
    with pytest.raises(aia.InputError, match=r"^aia\.AECEnv\.reset: seed: "):
        aec.reset(seed=-1)
    with pytest.raises(aia.InputError,
                       match=r"^aia\.AECEnv\.reset: options: "):
        aec.reset(options={"x": 1})
    aec.reset(seed=2)
    assert aec.state().shape == aec.state_space.shape


def test_the_envs_render_names_the_env():
    # It named aia.Mission.render, which the caller did not call.
    env = aia.parallel_env(DEFAULT, seed=1, render_mode="rgb_array")
    env.reset()
    with pytest.raises(aia.InputError,
                       match=r"^aia\.ParallelEnv\.render: width: must be an "
                             r"integer in \[16, 8192\], got 0$"):
        env.render(0, 0)
    aec = aia.aec_env(DEFAULT, seed=1, render_mode="rgb_array")
    with pytest.raises(aia.InputError, match=r"^aia\.AECEnv\.render: call "
                                             r"reset\(\) before render\(\)"):
        aec.render()
    aec.reset()
    with pytest.raises(aia.InputError,
                       match=r"^aia\.AECEnv\.render: height: must be an "
                             r"integer in \[16, 8192\], got 8$"):
        aec.render(64, 8)
    assert aec.render(64, 48).shape == (48, 64, 3)


def test_a_tracking_mission_runs_past_success_to_its_horizon():
    # mission.stop_at_success false: success does not end the mission, so
    # the horizon truncates it (it terminated every agent at the first
    # success, and Mission.step told the horizon's end as terminated).
    tracking = str(SOURCE / "scenarios" / "tracking.yaml")
    greedy = aia.builtin_policy("greedy")
    mission = aia.Mission(tracking, seed=0,
                          overrides={"mission.max_steps": 60})
    while not mission.done:
        result = mission.step(greedy.decide(mission))
        assert result.steps == 60 or not result.done
    assert result.success and result.steps == 60
    assert result.truncated and not result.terminated

    env = aia.parallel_env(tracking, seed=0,
                           overrides={"mission.max_steps": 60})
    env.reset(seed=0)
    steps, succeeded = 0, False
    while env.agents:
        moves = greedy.decide(env.mission)
        _, _, term, trunc, _ = env.step(
            {a: int(moves[env.possible_agents.index(a)]) % 4
             for a in env.agents})
        steps += 1
        succeeded = succeeded or env.mission.success
    assert succeeded and steps == 60
    assert all(trunc.values()) and not any(term.values())


def test_a_closed_env_refuses_the_spaces_dicts_and_its_state_space():
    env = aia.parallel_env(DEFAULT)
    aec = aia.aec_env(DEFAULT)
    assert env.observation_spaces["robot_0"] is env.observation_space("robot_0")
    assert aec.observation_spaces["robot_0"] is aec.observation_space("robot_0")
    env.close()
    aec.close()
    for name in ("observation_spaces", "action_spaces", "state_space"):
        with pytest.raises(aia.InputError,
                           match=rf"^aia.ParallelEnv.{name}: the env is "):
            getattr(env, name)
        with pytest.raises(aia.InputError,
                           match=rf"^aia.AECEnv.{name}: the env is "):
            getattr(aec, name)
    with pytest.raises(aia.InputError,
                       match=r"^aia.AECEnv.observation_space: the env is"):
        aec.observation_space("robot_0")


def test_channel_settings_are_named_as_the_envs_argument():
    for make, name in ((aia.parallel_env, "aia.parallel_env"),
                       (aia.aec_env, "aia.aec_env")):
        with pytest.raises(aia.InputError) as e:
            make(DEFAULT, channels={"window": -1})
        assert str(e.value).startswith(
            f"{name}: channels: window: must be an integer in [4, 512]"), \
            str(e.value)


def test_scenario_warnings_point_at_the_callers_line():
    import warnings
    for make in (aia.parallel_env, aia.aec_env, aia.Mission):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            make(DEFAULT, overrides={"communication.range": 5})
        told = [w for w in seen if issubclass(w.category, aia.ScenarioWarning)]
        assert len(told) == 1, [str(w.message) for w in seen]
        assert told[0].filename == __file__, (make, told[0].filename)


def test_the_stand_in_spaces_read_as_gymnasiums():
    from aia import env as env_module
    space = env_module._observation_space((3, 4, 4), 2)
    if not isinstance(space, env_module.Dict):
        pytest.skip("gymnasium's own spaces are in use")
    assert list(space) == ["channels", "vector"] == list(space.keys())
    assert len(space) == 2 and dict(space.items())["vector"] is space["vector"]
    # A list is read as the Box's dtype; a string is not a member.
    assert space["vector"].contains([0.1, 0.2])
    assert not space["vector"].contains([0.1, 0.2, 0.3])
    assert not space["vector"].contains(["a", "b"])
    # seed(None) draws a seed and says which, as gymnasium's.
    action = env_module._action_space()
    (drawn,) = action.seed()
    assert isinstance(drawn, int)
    first = [action.sample() for _ in range(20)]
    assert action.seed(drawn) == [drawn]
    assert [action.sample() for _ in range(20)] == first
    assert action.seed(7) == [7]
    reference = np.random.default_rng(7)
    assert [action.sample() for _ in range(5)] == \
        [int(reference.integers(4)) for _ in range(5)]


def test_the_envs_mission_is_stepped_by_the_env_only():
    # A step of env.mission behind the env's back left its agents, rewards
    # and ends behind (the next env reward covered two steps).
    env = aia.parallel_env(DEFAULT, seed=0, overrides={"mission.max_steps": 3})
    env.reset(seed=2)
    with pytest.raises(aia.InputError, match=r"^aia.Mission.step: this is "
                       r"the mission of an aia.ParallelEnv: step it with"):
        env.mission.step([4] * len(env.possible_agents))
    assert env.mission.steps == 0
    env.step({a: 0 for a in env.agents})
    assert env.mission.steps == 1
    env.mission.state()  # read freely


def test_an_unknown_agents_space_is_bad_input_and_a_key_error():
    env = aia.parallel_env(DEFAULT)
    for call, what in ((env.observation_space, "observation_space"),
                       (env.action_space, "action_space"),
                       (aia.aec_env(DEFAULT).observation_space,
                        "observation_space")):
        for kind in (aia.InputError, KeyError):
            with pytest.raises(kind) as e:
                call("nobody")
            assert str(e.value).endswith(
                f"{what}: agent: unknown agent 'nobody'; agents are robot_0 "
                f".. robot_9"), str(e.value)
