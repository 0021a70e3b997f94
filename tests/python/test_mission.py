"""aia.Mission and aia.builtin_policy against the C++ loop (docs/python.md).

Run by ctest (tests/CMakeLists.txt) with PYTHONPATH=build/python, AIA_BINARY
the CLI and AIA_SOURCE_DIR the checkout.
"""

import csv
import json
import os
import pickle
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

import aia

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
BINARY = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
DEFAULT = str(SOURCE / "scenarios" / "default.yaml")


def run_cli(*args):
    return subprocess.run([BINARY, *args], capture_output=True, text=True)


def test_state_holds_what_the_robots_know_and_the_truth_apart():
    m = aia.Mission(DEFAULT, seed=5, overrides={"robots.count": 4,
                                                "targets.count": 3})
    s = m.state()
    n, k = 4, 3
    assert (m.num_robots, m.num_targets) == (n, k)
    assert s["steps"] == 0 and m.steps == 0 and not m.done
    assert s["positions"].shape == (n, 2) and s["positions"].dtype == np.float64
    assert s["lattice"].shape == (n,) and s["cells"].shape == (n, 2)
    assert s["active"].dtype == np.bool_ and s["active"].all()
    assert s["neighbors"].shape == (n, n)
    assert not s["neighbors"].diagonal().any()
    assert (s["neighbors"] == s["neighbors"].T).all()
    assert s["mean"].shape == (n, k, 2) and s["cov"].shape == (n, k, 2, 2)
    assert s["det"].shape == (n, k)
    # det Sigma of the position block from the covariance given.
    np.testing.assert_allclose(np.linalg.det(s["cov"]), s["det"], rtol=1e-9)
    assert s["log_det_prior"].shape == (k,)
    # The ground truth is only under "truth".
    assert set(s["truth"]) == {"target_positions"}
    assert s["truth"]["target_positions"].shape == (k, 2)
    # The lattice cell holds the robot's position (0.5 m cells at default).
    step = 0.5
    np.testing.assert_allclose((s["cells"] + 0.5) * step, s["positions"],
                               atol=step / 2)


def trace_rows(path):
    """trace.csv as {(step, target): [det_r0, ...]} in its printed form."""
    rows = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            dets = [v for c, v in r.items() if c.startswith("det_r")]
            rows[(int(r["step"]), int(r["target"]))] = dets
    return rows


@pytest.mark.parametrize("scenario,seed,policy", [
    ("default.yaml", 3, "greedy"),
    ("robustness.yaml", 2, "greedy"),  # robot failures, packet loss
    ("tracking.yaml", 1, "random"),    # a moving target
])
def test_delegating_every_step_repeats_aia_run(scenario, seed, policy):
    path = str(SOURCE / "scenarios" / scenario)
    with tempfile.TemporaryDirectory() as out:
        r = run_cli("run", path, "--seed", str(seed), "--policy", policy,
                    "--out", out, "--quiet", "--trace", "full")
        assert r.returncode == 0, r.stderr
        trace = trace_rows(os.path.join(out, "trace.csv"))
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
    m = aia.Mission(path, seed=seed)
    p = aia.builtin_policy(policy)
    seen = 0
    while True:
        s = m.state()
        for k in range(m.num_targets):
            assert ["%.6e" % d for d in s["det"][:, k]] == \
                trace[(s["steps"], k)], (s["steps"], k)
            seen += 1
        if m.done:
            break
        m.step(p.decide(m))
    assert seen == len(trace)
    mine = m.summary()
    for key in ("success", "flowtime", "steps", "invalid_moves",
                "localized_share", "final_min_det", "failed_robots"):
        assert mine[key] == summary[key], key
    assert mine["policy"] == "python"


@pytest.mark.parametrize("scenario,seed,policy", [
    ("wheeled.yaml", 2, "random"),  # robots decide on arrival, step repeats
    ("default.yaml", 6, "greedy"),
])
def test_deciding_every_round_repeats_aia_run_in_async(scenario, seed, policy):
    # In async a step counts the slowest robot's decisions and repeats over
    # rounds: a builtin policy restarted at each repeat (its random streams
    # and memory lost) once took 24 of 35 missions elsewhere.
    path = str(SOURCE / "scenarios" / scenario)
    sets = ["--set", "mission.decisions=async", "--max-steps", "30"]
    with tempfile.TemporaryDirectory() as out:
        r = run_cli("run", path, "--seed", str(seed), "--policy", policy,
                    "--out", out, "--quiet", *sets)
        assert r.returncode == 0, r.stderr
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        with open(os.path.join(out, "diagnostics.json")) as f:
            moves = json.load(f)["moves"]
    m = aia.Mission(path, seed=seed, overrides={
        "mission.decisions": "async", "mission.max_steps": 30})
    p = aia.builtin_policy(policy)
    while not m.done:
        m.step(p.decide(m))
    mine = m.summary()
    for key in ("success", "flowtime", "steps", "invalid_moves",
                "localized_share", "final_min_det"):
        assert mine[key] == summary[key], key
    assert m.diagnostics["moves"] == moves


def test_same_seed_same_states():
    def states():
        m = aia.Mission(DEFAULT, seed=11, overrides={"mission.max_steps": 5})
        r = aia.builtin_policy("random")
        out = []
        while not m.done:
            out.append(m.state()["det"].copy())
            m.step(r.decide(m))
        return out
    a, b = states(), states()
    assert len(a) == 5
    for x, y in zip(a, b):
        assert (x == y).all()


def test_moves_are_checked():
    m = aia.Mission(DEFAULT, seed=1, overrides={"robots.count": 2,
                                                "targets.count": 1})
    with pytest.raises(aia.InputError, match=r"one move per robot, got "
                       r"shape \(1,\)"):
        m.step([0])
    with pytest.raises(aia.InputError, match=r"moves\[1\]: must be 0 "
                       r"\(left\)"):
        m.step([0, 7])
    # 4 (stay) is a valid decision: the robot keeps its lattice point.
    before = m.state()["lattice"].copy()
    changed = m.step([4, 4])
    assert changed.steps == 1 == m.steps == m.state()["steps"]
    assert changed.invalid_moves == 0
    assert not (changed.terminated or changed.truncated or changed.done)
    assert (m.state()["lattice"] == before).all()
    m2 = aia.Mission(DEFAULT, seed=1, overrides={"mission.max_steps": 1})
    last = m2.step(np.zeros(m2.num_robots, dtype=int))
    assert m2.done and last.done and last.truncated and not last.terminated
    assert "truncated=True" in repr(last)
    with pytest.raises(aia.InputError, match="the mission is done"):
        m2.step(np.zeros(m2.num_robots, dtype=int))


def test_success_terminates():
    m = aia.Mission(DEFAULT, seed=3)
    greedy = aia.builtin_policy("greedy")
    while not m.done:
        r = m.step(greedy.decide(m))
    assert r.success and r.terminated and not r.truncated
    assert r.steps == m.steps == m.flowtime


def expectation(path):
    first = Path(path).read_text(errors="replace").split("\n", 1)[0]
    m = re.match(r"^# expect: ([0-9]+): ([^:]+): (.*)$", first)
    assert m, f"{path} lacks its '# expect:' line"
    return int(m[1]), m[2], m[3]


def test_a_bad_scenario_is_the_clis_one_line_error():
    files = sorted((SOURCE / "tests" / "data" / "bad").glob("*.yaml"))
    assert len(files) > 100
    for f in files:
        line, key, substring = expectation(f)
        with pytest.raises(aia.InputError) as e:
            aia.Mission(str(f))
        text = str(e.value)
        prefix = f"{f}" + (f":{line}" if line > 0 else "") + f": {key}: "
        assert text.startswith(prefix), (text, prefix)
        assert substring in text and "\n" not in text, text
    # The same line as the CLI's, for one of them.
    f = str(SOURCE / "tests" / "data" / "bad" / "duplicate_key.yaml")
    with pytest.raises(aia.InputError) as e:
        aia.Mission(f)
    assert run_cli("run", f, "--quiet").stderr == f"error: {e.value}\n"
    assert isinstance(e.value, ValueError)


def test_overrides_and_params_are_checked_as_keys():
    with pytest.raises(aia.InputError, match="overrides: sensor.range: must "
                       r"be a number in \[0.001, 10000\], got -1"):
        aia.Mission(DEFAULT, overrides={"sensor.range": -1})
    with pytest.raises(aia.InputError, match="unknown policy 'nope'"):
        aia.builtin_policy("nope")
    with pytest.raises(aia.InputError, match=r"p_v: must be a number in "
                       r"\[0, 1\], got 2"):
        aia.builtin_policy("decsb", p_v=2)
    with pytest.raises(aia.InputError, match="not a scenario value"):
        aia.Mission(DEFAULT, overrides={"seed": object()})
    # Lists go as YAML flow sequences, booleans as true/false.
    m = aia.Mission(DEFAULT, overrides={
        "robots.count": 2, "robots.start": [[1.25, 1.25], [3.25, 1.25]],
        "mission.stop_at_success": False})
    np.testing.assert_allclose(m.state()["positions"],
                               [[1.25, 1.25], [3.25, 1.25]], atol=1e-6)


def test_builtin_policies_decide_for_the_team():
    assert set(aia.policy_names()) >= {"random", "greedy", "expert", "decsb",
                                       "igbnet"}
    m = aia.Mission(DEFAULT, seed=4, overrides={"robots.count": 3,
                                                "targets.count": 2})
    for name in aia.policy_names():
        p = aia.builtin_policy(name)
        moves = p.decide(m)
        assert moves.shape == (3,) and moves.dtype == np.int64, name
        assert ((moves >= 0) & (moves <= 4)).all(), name
        assert p.centralized == (name == "expert")
        assert p.last_status in ("ok", "no_valid_move", "budget_exhausted")


def test_a_step_result_pickles():
    # What a worker process sends back through a pipe.
    m = aia.Mission(DEFAULT, seed=1, overrides={"robots.count": 3,
                                                "targets.count": 3,
                                                "mission.max_steps": 2})
    for _ in range(2):
        r = m.step([0, 1, 4])
        back = pickle.loads(pickle.dumps(r))
        assert type(back) is type(r) and repr(back) == repr(r)
        assert back.done == r.done
    assert back.truncated and back.steps == 2


def test_async_steps_use_the_ready_robots_moves_only():
    lock = aia.Mission(DEFAULT, seed=3, overrides={"robots.count": 4})
    assert lock.ready.dtype == np.bool_ and lock.ready.all()
    m = aia.Mission(DEFAULT, seed=3, overrides={
        "robots.count": 4, "robots.model": "diff_drive",
        "mission.decisions": "async"})
    greedy = aia.builtin_policy("greedy")
    assert m.ready.all()  # every robot decides at the start
    partial = 0
    for _ in range(30):
        if m.done:
            break
        ready = m.ready.copy()
        before = m.state()["lattice"].copy()
        m.step(greedy.decide(m))
        partial += int(not m.ready.all())
        # A robot that did not decide kept the point it was driving to.
        after = m.state()["lattice"]
        for i in np.flatnonzero(~ready):
            if not m.ready[i]:
                assert after[i] == before[i]
    # Wheeled robots turn and drive for different times.
    assert partial > 0


def test_the_package_names_only_what_it_exports():
    # `from aia import *` and tab completion show the API, not the modules
    # the package itself imports (os, re, ...): every public name is in
    # __all__ or is one of the package's own submodules.
    submodules = {"env", "network"}
    public = {n for n in dir(aia) if not n.startswith("_")}
    assert public - submodules == set(aia.__all__)


def test_reserved_points_keep_wheeled_robots_apart_when_moves_time_out(
        tmp_path):
    """Async, reservations, wheeled moves cut short by a tight timeout: a
    robot whose move ends between two points stands at the nearer point it
    holds, not at the nearest free one, which another robot may hold (two
    robots of radius 0.1 came to 0.171 m)."""
    scenario = tmp_path / "crowd.yaml"
    scenario.write_text(
        "seed: 2\nworkspace: {size: [2.0, 2.0]}\n"
        "robots: {count: 12, radius: 0.1, step: 0.5, model: diff_drive,"
        " diff_drive: {track: 0.15}}\n"
        "sensor: {range: 0.5}\ntargets: {list: [{position: [1.0, 1.0]}]}\n"
        "mission: {eps: 1.0e-12, max_steps: 150, decisions: async}\n"
        "physics: {step_timeout: 1.0}\npolicy: {name: random}\n")
    m = aia.Mission(scenario)
    random = aia.builtin_policy("random")
    closest = np.inf
    while not m.done:
        m.step(random.decide(m))
        p = m.state()["positions"]
        d = np.sqrt(((p[:, None, :] - p[None, :, :]) ** 2).sum(-1))
        np.fill_diagonal(d, np.inf)
        closest = min(closest, d.min())
    assert sum(m.diagnostics["physics"]["robot_timeouts"]) > 0
    assert closest > 2 * 0.1 - 0.02, closest


def test_a_cut_wheeled_move_ends_at_the_free_point_nearest_to_the_robot(
        tmp_path):
    """Async, reservations, a lone wheeled robot whose moves a tight
    timeout cuts while it rolls: it stands at the lattice point nearest to
    it (at most half a diagonal away), not at one of the points it held,
    which it may have drifted past (1.1 m from its body before)."""
    scenario = tmp_path / "one.yaml"
    scenario.write_text(
        "seed: 4\nworkspace: {size: [6.0, 6.0]}\n"
        "robots: {count: 1, model: diff_drive}\ntargets: {count: 3}\n"
        "sensor: {range: 0.6}\n"
        "mission: {eps: 1.0e-6, max_steps: 60, decisions: async,"
        " stop_at_success: false}\nphysics: {step_timeout: 0.5}\n")
    m = aia.Mission(scenario)
    random = aia.builtin_policy("random")
    worst = 0.0
    while not m.done:
        m.step(random.decide(m))
        s = m.state()
        if m.ready[0]:
            point = (s["cells"][0] + 0.5) * 0.5
            worst = max(worst, np.linalg.norm(s["positions"][0] - point))
    assert sum(m.diagnostics["physics"]["robot_timeouts"]) > 0
    assert worst <= 0.5 * np.sqrt(0.5) + 1e-9, worst


def test_a_robot_that_fails_mid_move_keeps_teammates_two_radii_away(
        tmp_path):
    """Async, reservations: robot 0 fails between (0.75, 0.25) and (1.25,
    0.25), 0.27 m from the second point; robot 2 then asks to move onto
    it. The failed robot holds every point within two radii of where it
    stopped, so robot 2 waits (it drove into it before: 0.294 m apart)."""
    scenario = tmp_path / "fail_mid.yaml"
    scenario.write_text(
        "seed: 1\nworkspace: {size: [4.0, 1.0]}\n"
        "robots: {count: 3, model: point,"
        " start: [[0.75, 0.25], [3.25, 0.75], [1.75, 0.25]]}\n"
        "targets: {list: [{position: [2.0, 0.9]}]}\n"
        "sensor: {range: 0.3, rate: 200}\n"
        "mission: {eps: 1.0e-9, max_steps: 300, decisions: async,"
        " stop_at_success: false}\n"
        "communication: {failures: [{robot: 0, step: 1}]}\n")
    m = aia.Mission(scenario)
    stays, asked, rounds, closest = 0, False, 0, np.inf
    while not m.done and rounds < 5000:
        s = m.state()
        moves = [4, 4, 4]
        if m.ready[0]:  # stays 28 times, then moves right
            moves[0] = 4 if stays < 28 else 1
            stays += 1
        if m.ready[1] and rounds == 0:  # completes step 1: robot 0 fails
            moves[1] = 0
        if m.ready[2] and not s["active"][0] and not asked:
            moves[2] = 0  # left, toward the failed robot
            asked = True
            stopped_at = s["positions"][0][0]
        m.step(moves)
        rounds += 1
        p = m.state()["positions"]
        closest = min(closest, np.linalg.norm(p[0] - p[2]))
    assert asked and 0.75 < stopped_at < 1.25 - 0.15, stopped_at
    assert closest >= 2 * 0.15, closest


def test_async_missions_are_judged_as_lockstep_ones_at_their_ends(tmp_path):
    """Async: a mission whose last robot fails between ticks has a last tick
    (no robot active: no estimate, as in lockstep); a target first
    localized during the first moves gives F = 1, not the F = 0 of a
    mission localized at the start."""
    failed = tmp_path / "failed.yaml"
    failed.write_text(
        "seed: 1\nworkspace: {size: [4.0, 4.0]}\n"
        "robots: {count: 1, start: [[0.25, 0.25]]}\n"
        "targets: {list: [{position: [1.0, 1.0]}]}\n"
        "mission: {eps: 0.1, max_steps: 20, stop_at_success: false,"
        " decisions: async}\n"
        "communication: {failures: [{robot: 0, step: 3}]}\n"
        "policy: {name: random}\n")
    first = tmp_path / "first.yaml"
    first.write_text(
        "seed: 1\nworkspace: {size: [4.0, 1.0]}\n"
        "robots: {count: 1, start: [[0.25, 0.25]]}\n"
        "sensor: {range: 1.0, rate: 100}\n"
        "targets: {list: [{position: [1.4, 0.25]}]}\n"
        "mission: {eps: 0.1, max_steps: 10, decisions: async}\n"
        "policy: {name: greedy}\n")
    first_lockstep = tmp_path / "first_lockstep.yaml"
    first_lockstep.write_text(first.read_text().replace(
        "sensor: {range: 1.0, rate: 100}", "sensor: {range: 1.0}"))
    summaries = {}
    for name, decisions, path in (("failed", "async", failed),
                                  ("failed", "lockstep", failed),
                                  ("first", "async", first),
                                  ("first", "lockstep", first_lockstep)):
        out = tmp_path / f"{name}_{decisions}"
        done = run_cli("run", str(path), "--quiet", "--out", str(out),
                       "--set", f"mission.decisions={decisions}")
        assert done.returncode == 0, done.stderr
        summaries[name, decisions] = json.loads(
            (out / "summary.json").read_text())
    for decisions in ("async", "lockstep"):
        s = summaries["failed", decisions]
        assert s["final_min_det"] == [None], (decisions, s)
        assert s["localized_at_end"] == 0, (decisions, s)
    assert summaries["first", "async"]["flowtime"] == 1
    assert summaries["first", "async"]["steps"] == 0
    assert summaries["first", "lockstep"]["flowtime"] == 1


@pytest.mark.parametrize("tolerance", [0.03, 0.1])
@pytest.mark.parametrize("decisions", ["lockstep", "async"])
def test_a_wheeled_robot_on_open_floor_never_stalls(tmp_path, tolerance,
                                                    decisions):
    """A lone wheeled robot, 60 random moves on an empty floor, with a
    tolerance above the default: no move may end as stalled. Declared
    arrived that far from its point, the robot still rolls (about 8 x the
    tolerance, m/s) and a move the other way first brakes through rest;
    turning in place gains a few centimetres a window. Before: 15 stalls at
    0.03 and 53 at 0.1."""
    scenario = tmp_path / "one.yaml"
    scenario.write_text(
        "seed: 4\nworkspace: {size: [6.0, 6.0]}\n"
        "robots: {count: 1, model: diff_drive}\ntargets: {count: 3}\n"
        "sensor: {range: 0.6}\n"
        "mission: {eps: 1.0e-6, max_steps: 60, stop_at_success: false}\n"
        f"physics: {{tolerance: {tolerance}}}\npolicy: {{name: random}}\n")
    out = tmp_path / "out"
    done = run_cli("run", str(scenario), "--quiet", "--out", str(out),
                   "--set", f"mission.decisions={decisions}")
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 60
    assert summary["robot_stalls"] == 0, summary


def test_channels_from_a_kept_renderer_are_a_fresh_ones():
    # A mission keeps one channel renderer for the settings last asked for
    # (making it every call was a third of the call): what it draws at every
    # step, with settings switched back and forth and across a restart, is
    # what a mission that never drew before draws.
    maze = str(SOURCE / "scenarios" / "maze.yaml")
    settings = [{}, {"geodesic": True, "trail": True}, {"window": 24}]
    kept = aia.Mission(maze, seed=3)
    greedy = aia.builtin_policy("greedy")
    moves = []
    for step in range(6):
        for s in settings[step % 2:]:
            drawn = kept.channels(**s)
            fresh = aia.Mission(maze, seed=3)
            for m in moves:
                fresh.step(m)
            assert np.array_equal(drawn, fresh.channels(**s)), (step, s)
        moves.append(greedy.decide(kept))
        kept.step(moves[-1])
    kept._restart(4, "test")
    other = aia.Mission(maze, seed=4)
    assert np.array_equal(kept.channels(), other.channels())


DTYPE = """
import sys, torch
import aia
if sys.argv[2] == "64":
    torch.set_default_dtype(torch.float64)
m = aia.Mission(sys.argv[1])
p = aia.builtin_policy("igbnet")
moves = []
for _ in range(4):
    mv = p.decide(m)
    moves.append([int(x) for x in mv])
    m.step(mv)
print(moves, torch.get_default_dtype())
"""


def test_the_programs_torch_default_dtype_changes_no_decision():
    """A program that made float64 its torch default (the same libtorch as
    aia's) loaded the model into float64 parameters: 'tensor ... is not
    finite'. The model is float32 whatever the default, which is left as
    the program set it."""
    pytest.importorskip("torch")
    import sys
    out = {}
    for bits in ("32", "64"):
        r = subprocess.run([sys.executable, "-c", DTYPE, DEFAULT, bits],
                           capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        out[bits] = r.stdout.split()
    assert out["64"][-1] == "torch.float64"
    assert out["64"][:-1] == out["32"][:-1]
