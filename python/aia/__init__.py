"""aia from Python: missions of the C++ testbed, stepped by your code.

    import aia
    m = aia.Mission("scenarios/default.yaml", seed=3)
    greedy = aia.builtin_policy("greedy")
    while not m.done:
        m.step(greedy.decide(m))
    print(m.success, m.flowtime, m.summary()["steps"])

Moves are ints: 0 left, 1 right, 2 up, 3 down, 4 stay. A mission is the
same loop as `aia run` (world, physics, sensing, DKF, world rule); what the
robots know is in `state()`, the ground truth under its "truth" key, for
scoring only. docs/python.md is the reference.
"""

import json as _json
import math as _math
import os
import re

from . import _aia

__all__ = ["Dataset", "InputError", "Mission", "VectorMissions",
           "builtin_policy", "evaluate", "parallel_env", "policy_names"]

InputError = _aia.InputError


def _yaml_text(key, value):
    """A Python value as the YAML text of a scenario key's override."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if _math.isnan(value):
            return ".nan"
        if _math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple, dict)):
        return _json.dumps(value)
    raise TypeError(f"{key}: a value of type {type(value).__name__} is not a "
                    "scenario value (give a bool, number, string, list or dict)")


def _pairs(mapping, what):
    if mapping is None:
        return []
    if not isinstance(mapping, dict):
        raise TypeError(f"{what}: must be a dict of keys to values, got "
                        f"{type(mapping).__name__}")
    return [(str(k), _yaml_text(k, v)) for k, v in mapping.items()]


class Mission:
    """One mission: `scenario` a YAML file, `seed` its seed (default: the
    file's), `overrides` a dict of `--set` keys to values, e.g.
    {"sensor.range": 3, "robots.count": 5}."""

    def __init__(self, scenario, seed=None, overrides=None):
        self._m = _aia.Mission(str(scenario), seed,
                               _pairs(overrides, "overrides"))

    @classmethod
    def _view(cls, core):
        """A Python Mission around a core one: a decision inside
        aia.evaluate (read-only, valid during the call, no "truth"), or a
        mission of VectorMissions."""
        m = cls.__new__(cls)
        m._m = core
        return m

    def state(self):
        """What the robots know now, as numpy arrays (N robots, M targets):
        step; positions (N, 2) metres; lattice (N,) lattice indices and
        cells (N, 2) their (ix, iy); active (N,); neighbors (N, N) this
        step's communication graph; mean (N, M, 2), cov (N, M, 2, 2) and
        det (N, M) of each robot's fused belief (position part); the
        targets' log_det_prior (M,); eps; workspace (width, height) in
        metres. The ground truth, for scoring
        only, under "truth": target_positions (M, 2)."""
        return self._m.state()

    def channels(self, frame=None, **params):
        """I-GBNet's input of every robot, an (N, C, H, W) float32 array
        from the C++ renderer: obstacles, neighbours, the heat of the
        robot's own fused belief, the robot itself (and with geodesic=True
        the reach channel, from its belief's means). `frame` is "centred"
        (a window around each robot, the default) or "global"; `params` are
        the other channel settings (window, cell, blur, cutoff, geodesic,
        ...; docs/learning.md, Channels), checked as a model's are."""
        if frame is not None:
            params["frame"] = frame
        return self._m.channels(_pairs(params, "channels"))

    def render(self, width=640, height=480):
        """An RGB frame, an (H, W, 3) uint8 array, of the physics now with
        `aia render`'s overlays (estimates, sensing, messages, trails from
        the first render() on). Made offscreen (OSMesa), on this thread."""
        return self._m.render(int(width), int(height))

    def valid_moves(self):
        """(N, 4) bool: which of each robot's moves (left, right, up, down)
        stay on the lattice (the world rule replaces the others)."""
        return self._m.valid_moves()

    def step(self, moves):
        """Applies one move per robot (4 stays in place; the world rule
        replaces a move off the lattice), runs the physics, senses and fuses. Returns what changed:
        step, invalid_moves (replaced this step), localized (targets below
        eps in the team's best estimate), done, success."""
        import numpy as np
        return self._m.step(np.asarray(moves, dtype=np.int64).reshape(-1))

    @property
    def done(self):
        return self._m.done

    @property
    def success(self):
        return self._m.success

    @property
    def flowtime(self):
        """Steps to success; None until then."""
        f = self._m.flowtime
        return None if f < 0 else f

    @property
    def num_robots(self):
        return self._m.num_robots

    @property
    def num_targets(self):
        return self._m.num_targets

    @property
    def steps(self):
        """Decision steps taken."""
        return self._m.step_count

    @property
    def max_steps(self):
        return self._m.max_steps

    @property
    def seed(self):
        return self._m.seed

    @property
    def diagnostics(self):
        """diagnostics.json's content (as `aia run` writes it; the policy
        statuses and counters are those of the moves given, policy
        "python")."""
        return _json.loads(self._m.diagnostics_json())

    def summary(self):
        """summary.json's content (policy "python", wall_s 0)."""
        return _json.loads(self._m.summary_json())


class VectorMissions:
    """n missions of one scenario, seeds seed .. seed + n - 1 (default: the
    file's seed + i), stepped together on C++ threads (threads 0: all
    cores) with the GIL released. missions[i] is each one's Mission."""

    def __init__(self, n, scenario, seed=None, overrides=None, threads=0):
        n = int(n)
        if n < 1:
            raise ValueError(f"n: must be at least 1, got {n}")
        if seed is None:
            seed = Mission(scenario, overrides=overrides).seed
        seeds = [int(seed) + i for i in range(n)]
        self._v = _aia.VectorMissions(str(scenario), seeds,
                                      _pairs(overrides, "overrides"),
                                      int(threads))
        self.missions = [Mission._view(self._v.mission(i)) for i in range(n)]

    def __len__(self):
        return len(self.missions)

    @property
    def num_robots(self):
        return self._v.num_robots

    @property
    def done(self):
        """(n,) bool: each mission's done."""
        import numpy as np
        return np.array([m.done for m in self.missions])

    def step(self, moves):
        """moves: (n, robots) ints; a mission already done ignores its
        row. Returns stacked arrays: step, done, success, invalid_moves."""
        import numpy as np
        return self._v.step(np.ascontiguousarray(moves, dtype=np.int64))

    def states(self):
        """Every mission's state(), stacked: each array gains a first axis
        of n (the ground truth under "truth" likewise)."""
        import numpy as np
        states = [m.state() for m in self.missions]
        out = {k: np.stack([s[k] for s in states])
               for k in states[0] if k != "truth"}
        out["truth"] = {k: np.stack([s["truth"][k] for s in states])
                        for k in states[0]["truth"]}
        return out


class Dataset:
    """The samples of `aia dataset` folders or shard files, their channels
    rendered by the C++ renderer as `aia train` renders them. `channels`
    are the channel settings (frame, window, cell, geodesic, ...; a model's
    are aia.network.channel_params(meta)).

    labels, useful, acted, world, episode, step, robot: (n,) arrays per
    sample (label: the expert's move; useful: the robot still had useful
    work in the expert's plan)."""

    def __init__(self, paths, **channels):
        if isinstance(paths, (str, os.PathLike)):
            paths = [paths]
        self._d = _aia.Dataset([str(p) for p in paths],
                               _pairs(channels, "channels"))
        samples = self._d.samples()
        self.labels = samples["label"]
        self.useful = samples["useful"]
        self.acted = samples["acted"]
        self.world = samples["world"]
        self.episode = samples["episode"]
        self.step = samples["step"]
        self.robot = samples["robot"]

    def __len__(self):
        return len(self._d)

    @property
    def num_worlds(self):
        return self._d.num_worlds

    def split(self, val_share=0.1, seed=1):
        """(train, validation) sample indices, split by world as `aia train
        --val-share --seed` splits (its defaults)."""
        import numpy as np
        held = self._d.validation_worlds(float(val_share), int(seed))
        val = held[self.world]
        return np.flatnonzero(~val), np.flatnonzero(val)

    def batch(self, indices):
        """(images (B, C, H, W) float32, labels (B,) int64) of these
        samples."""
        import numpy as np
        return self._d.batch(np.asarray(indices, dtype=np.int64).tolist())


class _BuiltinPolicy:
    """A registered policy: decide(mission) -> one move per robot."""

    def __init__(self, name, params):
        self._p = _aia.BuiltinPolicy(str(name), _pairs(params, "params"))

    @property
    def name(self):
        return self._p.name

    @property
    def centralized(self):
        """Whether it decides from the team's belief (the expert)."""
        return self._p.centralized

    @property
    def last_status(self):
        """The status of the last decision: ok, no_valid_move, ..."""
        return self._p.last_status

    def decide(self, mission):
        """Moves for this step from what the robots know (the team's belief
        only for a centralized policy). Deciding at every step of a mission
        repeats `aia run` with this policy."""
        return self._p.decide(mission._m)

    def __call__(self, mission):
        return self.decide(mission)

    def __repr__(self):
        return f"aia.builtin_policy({self.name!r})"


def builtin_policy(name, **params):
    """Any registered policy (random, greedy, expert, decsb, igbnet) with
    its parameters, e.g. builtin_policy("igbnet", max_reversals=0)."""
    return _BuiltinPolicy(name, params)


_NAME = re.compile(r"^[A-Za-z0-9_.-]{1,64}$")


def evaluate(policy, sizes, seeds, seed_base=0, out=None, name=None,
             threads=0, overrides=None, centralized=False, progress=True):
    """Scores `policy` exactly as `aia eval` scores the built-ins: the same
    generated worlds (`sizes` like ["10x10"], seeds seed_base ..
    seed_base + seeds - 1), the same F* from the expert and horizon 3 F*,
    the same out/runs.csv and out/summary.csv rows (under `name`),
    resumable, and kill-safe: Ctrl-C writes the finished rows and raises
    KeyboardInterrupt; calling again goes on. Rows already in `out` (of
    `aia eval`, say) stay, and summary.csv covers every row there (every
    size, seed and policy).

    `policy` is a callable policy(mission) -> moves or an object with
    decide(mission). The mission it is given is a view of one decision:
    state() without "truth", valid during the call. `centralized=True`
    gives it the team's belief too (for builtin_policy("expert")).
    `overrides` are `--set` keys for every instance. `threads` 0: all
    cores (the expert's F* runs in parallel; Python calls take turns).
    Returns summary.csv's rows as dicts."""
    decide = getattr(policy, "decide", policy)
    if not callable(decide):
        raise TypeError("policy: must be callable, or have decide(mission)")
    if name is None:
        name = getattr(policy, "name", None) or getattr(policy, "__name__", "")
        if not isinstance(name, str) or not _NAME.match(name):
            name = "python"
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(f"name: must be 1 to 64 letters, digits, '_', '.' "
                         f"or '-', got {name!r}")
    if isinstance(sizes, str):
        sizes = [sizes]
    if out is None:
        import tempfile
        out = tempfile.mkdtemp(prefix="aia_evaluate_")
    sets = [f"{k}={v}" for k, v in _pairs(overrides, "overrides")]
    rc = _aia.evaluate(lambda view: decide(Mission._view(view)), name,
                       bool(centralized), [str(s) for s in sizes], int(seeds),
                       int(seed_base), str(out), int(threads), sets,
                       bool(progress))
    if rc == 130:
        raise KeyboardInterrupt(f"aia.evaluate: interrupted; the finished "
                                f"rows are in {out}/runs.csv: call again "
                                "with the same arguments to go on")
    return _read_summary(os.path.join(str(out), "summary.csv"))


def _read_summary(path):
    import csv
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            row = {}
            for k, v in r.items():
                if k in ("size", "policy"):
                    row[k] = v
                elif v == "":
                    row[k] = None
                elif k in ("instances", "no_expert_plan",
                           "longest_reversal_run"):
                    row[k] = int(v)
                else:
                    row[k] = float(v)
            rows.append(row)
    return rows


def parallel_env(scenario, seed=None, overrides=None, render_mode=None,
                 **kwargs):
    """The PettingZoo ParallelEnv API over a mission (aia.env.ParallelEnv:
    observations, rewards and spaces are documented there)."""
    from .env import ParallelEnv
    return ParallelEnv(scenario, seed=seed, overrides=overrides,
                       render_mode=render_mode, **kwargs)


def policy_names():
    """The registered policies' names."""
    return list(_aia.policy_names())
