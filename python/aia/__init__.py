"""aia from Python: missions of the C++ testbed, stepped by your code.

    import aia
    m = aia.Mission("scenarios/default.yaml", seed=3)
    greedy = aia.builtin_policy("greedy")
    while not m.done:
        m.step(greedy.decide(m))
    print(m.success, m.flowtime, m.summary()["steps"])

Moves are ints (or aia.Move): 0 left, 1 right, 2 up, 3 down, 4 stay (the
robot keeps its lattice point). A mission is the
same loop as `aia run` (world, physics, sensing, DKF, world rule); what the
robots know is in `state()`, the ground truth under its "truth" key, for
scoring only. docs/python.md is the reference.
"""

import json as _json
import math as _math
import operator as _operator
import os as _os
import re as _re
import sys as _sys
import warnings as _warnings

import numpy as _np

from . import _aia

__all__ = ["Dataset", "InputError", "Mission", "Move", "ScenarioWarning",
           "StepResult", "VectorMissions", "VectorStepResult", "aec_env",
           "builtin_policy", "evaluate", "parallel_env", "policy_names"]

InputError = _aia.InputError
Move = _aia.Move
StepResult = _aia.StepResult
VectorStepResult = _aia.VectorStepResult


class ScenarioWarning(UserWarning):
    """A scenario key given a value that changes nothing where it stands
    (communication.range with the full graph, robots.diff_drive keys on
    point robots, ...): the text is "FILE:LINE: key: what", the line aia's
    commands print after "warning: "."""

# An installed package (cmake --install, or a wheel) says where its own
# plugins and models are, relative to itself (_install.py, written at
# install time), so that it never loads a build tree's.
try:
    from . import _install
except ImportError:  # the build tree's package
    _install = None
if _install is not None:
    _here = _os.path.dirname(_os.path.abspath(__file__))
    _aia._use_installed(
        _os.path.normpath(_os.path.join(_here, _install.PLUGIN_DIR)),
        _os.path.normpath(_os.path.join(_here, _install.DATA_DIR)))


def _retitled(text, old, new):
    """`text` with its leading "OLD: " (the caller a message names) made
    "NEW: "; other texts as they are."""
    if text.startswith(old + ": "):
        return new + ": " + text[len(old) + 2:]
    return text


def _warn_scenario(core, where):
    """The scenario's warnings (what aia's commands print as "warning: ..."
    lines) as ScenarioWarning, an override's named as the argument, each
    told at the caller's line (the first frame outside this package, however
    deep the call: aia.parallel_env makes its Mission in env.py)."""
    package = _os.path.dirname(_os.path.abspath(__file__)) + _os.sep
    frame, level = _sys._getframe(1), 2
    while frame is not None and \
            _os.path.abspath(frame.f_code.co_filename).startswith(package):
        frame, level = frame.f_back, level + 1
    for text in core.scenario_warnings:
        _warnings.warn(_retitled(text, "command line", where),
                       ScenarioWarning, stacklevel=level)


def _shown(value):
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def _integer(value, where, arg, low=0, high=None):
    """`value` as an int if it is an integer (an int or numpy integer, not
    a bool or a float) in [low, high]; else aia.InputError."""
    expect = f"an integer >= {low}" if high is None else \
        f"an integer in [{low}, {high}]"
    # An array (numpy's, torch's) only as a single integer of no shape:
    # one of shape (1,) is not converted silently.
    if isinstance(value, (bool, _np.bool_)) or \
            not hasattr(type(value), "__index__") or \
            getattr(value, "ndim", 0) != 0:
        raise InputError(f"{where}: {arg}: must be {expect}, got "
                         f"{_shown(value)}")
    try:
        v = _operator.index(value)
    except TypeError:  # e.g. a float array of no shape
        raise InputError(f"{where}: {arg}: must be {expect}, got "
                         f"{_shown(value)}") from None
    if v < low or (high is not None and v > high):
        raise InputError(f"{where}: {arg}: must be {expect}, got {v}")
    return v


_SEED_MAX = 2 ** 64 - 1


# A letter, "_" or "/" first (or "." then one of them: "./x.yaml", not
# ".5", which YAML reads as a number).
_PLAIN_WORD = _re.compile(r"\.?[A-Za-z_/][A-Za-z0-9_./-]*")
_YAML_WORDS = {"true", "false", "yes", "no", "on", "off", "y", "n", "null",
               ".nan", ".inf", "-.inf", ".na"}


def _yaml_text(key, value):
    """A Python value as the YAML text of a scenario key's override. A str
    is a YAML string (quoted: "run # 2" stays that, "3" is not a number);
    numpy's scalars count as the Python numbers and bools they hold."""
    if isinstance(value, _np.bool_):
        value = bool(value)
    elif isinstance(value, _np.integer):
        value = int(value)
    elif isinstance(value, _np.floating):
        value = float(value)
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
        # A word (a name, an enum's value, a path) as itself; anything YAML
        # would read as another type or cut ("3", "true", "run # 2", "a: b",
        # "[1, 2]") quoted, so that it stays the string it is (a JSON
        # string is a YAML quoted one).
        if _PLAIN_WORD.fullmatch(value) and \
                value.lower() not in _YAML_WORDS:
            return value
        return _json.dumps(value)
    if isinstance(value, _np.ndarray):
        value = value.tolist()
    # Containers in YAML's flow style, each item by these rules, so that a
    # word inside stays a word: [{robot: random, step: 3}] (JSON would quote
    # it, and a quoted keyword is a string, not the keyword).
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_yaml_text(key, v) for v in value) + "]"
    if isinstance(value, dict):
        items = []
        for k, v in value.items():
            if not isinstance(k, str):
                raise InputError(f"{key}: a mapping's keys are strings, got "
                                 f"{_shown(k)}")
            items.append(f"{_yaml_text(key, k)}: {_yaml_text(key, v)}")
        return "{" + ", ".join(items) + "}"
    raise InputError(f"{key}: a value of type {type(value).__name__} is not "
                     "a scenario value (give a bool, number, string, list or "
                     "dict)")


def _pairs(mapping, what, where="aia"):
    if mapping is None:
        return []
    if not isinstance(mapping, dict):
        raise InputError(f"{where}: {what}: must be a dict of keys to "
                         f"values, got {_shown(mapping)}")
    out = []
    for k, v in mapping.items():
        try:
            out.append((str(k), _yaml_text(k, v)))
        except InputError as e:
            raise InputError(f"{where}: {what}: {e}") from None
    return out


class Mission:
    """One mission: `scenario` a YAML file, `seed` its seed (default: the
    file's), `overrides` a dict of `--set` keys to values, e.g.
    {"sensor.range": 3, "robots.count": 5}."""

    def __init__(self, scenario, seed=None, overrides=None, *,
                 _where="aia.Mission"):
        # The file is read here, once: its later edits and a change of the
        # working directory do not reach the envs' resets (_restart).
        self._m = _aia.Mission(_path(scenario, _where, "scenario"),
                               seed, _pairs(overrides, "overrides", _where),
                               _where)
        _warn_scenario(self._m, _where)

    # The env whose mission this is (aia.parallel_env's): it steps it.
    _stepped_by = None

    def _restart(self, seed, where):
        """Step 0 again at `seed`, of the scenario as it was read."""
        self._m._restart(seed, where)

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
        steps (decision steps taken); positions (N, 2) metres; lattice
        (N,) lattice indices and cells (N, 2) their (ix, iy); active (N,);
        neighbors (N, N) this step's communication graph; mean (N, M, 2),
        cov (N, M, 2, 2) and det (N, M) of each robot's fused belief
        (position part); the targets' log_det_prior (M,); eps; workspace
        (width, height) in metres. The ground truth, for scoring only,
        under "truth": target_positions (M, 2)."""
        return self._m.state()

    def channels(self, frame=None, **params):
        """I-GBNet's input of every robot, an (N, C, H, W) float32 array
        from the C++ renderer: obstacles, neighbours, the heat of the
        robot's own fused belief, the robot itself (and with geodesic=True
        the reach channel, from its belief's means). `frame` is "centred"
        (a window around each robot, the default) or "global"; `params` are
        the other channel settings (window, cell, blur, cutoff, geodesic,
        ...; docs/learning.md, Channels), checked as a model's are. As the
        igbnet policy does, they are rendered at one pixel per lattice
        step (where robots.step is not `cell`, the pixel is the step and
        geodesic_length, reach_detour and reach_broad scale with it) and
        with observe_range cut to sensor.range where that is shorter."""
        if frame is not None:
            params["frame"] = frame
        return self._m.channels(_pairs(params, "channels",
                                       "aia.Mission.channels"))

    def render(self, width=640, height=480):
        """An RGB frame, an (H, W, 3) uint8 array, of the physics now with
        `aia render`'s overlays (estimates, sensing, messages, trails from
        the first render() on). Made offscreen (OSMesa), on this thread."""
        return self._m.render(width, height)

    def valid_moves(self):
        """(N, 4) bool: which of each robot's moves (left, right, up, down)
        stay on the lattice (the world rule replaces the others)."""
        return self._m.valid_moves()

    @property
    def asynchronous(self):
        """True when mission.decisions is async (each robot decides when
        its own move ends; see ready)."""
        return self._m.asynchronous

    @property
    def ready(self):
        """(N,) bool: the robots whose moves the next step() uses: all of
        them in lockstep; with mission.decisions async, those whose last
        move has ended (one step() is then one round: physics until the next
        robot's move ends), the others driving on."""
        return self._m.ready

    def step(self, moves):
        """Applies one move per robot: a list or numpy array of integers
        0..4 of shape (num_robots,) exactly (4 stays in place; the world
        rule replaces a move off the lattice); floats, bools and any other
        shape are refused (aia.InputError). Runs the physics, senses and
        fuses. Returns a StepResult: steps, invalid_moves (replaced this
        step), localized (targets below eps in the team's best estimate),
        terminated (success, or no robot left), truncated (past
        mission.max_steps), success, done (terminated or truncated)."""
        if self._stepped_by is not None:
            raise InputError(
                f"aia.Mission.step: this is the mission of an "
                f"{self._stepped_by}: step it with the env's step() (a step "
                f"here would leave the env's agents, rewards and ends "
                f"behind); read it here")
        return self._m.step(moves)

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
        """Decision steps taken (state()["steps"], StepResult.steps)."""
        return self._m.steps

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


def _path(value, where, arg):
    if not isinstance(value, (str, _os.PathLike)):
        raise InputError(f"{where}: {arg}: must be a path (str or "
                         f"os.PathLike), got {_shown(value)}")
    path = _os.fspath(value)
    if (b"\0" if isinstance(path, bytes) else "\0") in path:
        raise InputError(f"{where}: {arg}: a path cannot hold a NUL byte, "
                         f"got {_shown(value)}")
    if isinstance(path, str):
        try:
            path.encode("utf-8")
        except UnicodeEncodeError:
            # A name os.listdir decoded with surrogates: its bytes pass.
            path = _os.fsencode(path)
    return path


class VectorMissions:
    """n missions of one scenario, seeds seed .. seed + n - 1 (default: the
    file's seed + i), stepped together on C++ threads (threads 0: all
    cores) with the GIL released. missions[i] is each one's Mission.

    With autoreset=True a mission that ends at a step restarts at once with
    the next seed (seed + n, seed + n + 1, ... in the order they end), as
    Gymnasium's vector environments do; that step's result still shows how
    it ended, and its info holds its last summary and state."""

    def __init__(self, n, scenario, seed=None, overrides=None, threads=0,
                 autoreset=False):
        where = "aia.VectorMissions"
        # Memory refuses far fewer (after the first two missions).
        n = _integer(n, where, "n", 1, 2 ** 31 - 1)
        scenario = _path(scenario, where, "scenario")
        if seed is None:
            with _warnings.catch_warnings():  # said once, below
                _warnings.simplefilter("ignore", ScenarioWarning)
                seed = Mission(scenario, overrides=overrides,
                               _where=where).seed
        seed = _integer(seed, where, "seed", 0, _SEED_MAX - n + 1)
        threads = _integer(threads, where, "threads", 0)
        if not isinstance(autoreset, (bool, _np.bool_)):
            raise InputError(f"{where}: autoreset: must be True or False, "
                             f"got {_shown(autoreset)}")
        self._v = _aia.VectorMissions(
            scenario, seed, n, _pairs(overrides, "overrides", where), threads,
            bool(autoreset))
        self.missions = [Mission._view(self._v.mission(i)) for i in range(n)]
        _warn_scenario(self._v.mission(0), where)

    def __len__(self):
        return len(self.missions)

    @property
    def num_robots(self):
        return self._v.num_robots

    @property
    def autoreset(self):
        return self._v.autoreset

    @property
    def done(self):
        """(n,) bool: each mission's done."""
        return _np.array([m.done for m in self.missions])

    @property
    def seeds(self):
        """(n,) uint64: each mission's seed now."""
        return _np.array([m.seed for m in self.missions], dtype=_np.uint64)

    def reset(self, seed=None, options=None):
        """Every mission restarted: at seeds seed .. seed + n - 1, else at
        the n seeds after the last one used. Returns (states(), info) with
        info["seeds"], as Gymnasium's reset returns (observation, info).
        `options` must be None or an empty dict: there are none."""
        n = len(self)
        if options is not None and (not isinstance(options, dict) or
                                    options):
            raise InputError(f"aia.VectorMissions.reset: options: this "
                             f"takes no options (None or {{}}), got "
                             f"{_shown(options)}")
        if seed is None:
            # The seeds after the last used, wrapping past 2^64 - 1 as the
            # vector's own next seed does (as an env's reset does).
            first = self._v.next_seed
            self._v.reset([(first + i) % 2 ** 64 for i in range(n)])
            return self.states(), {"seeds": self.seeds}
        seed = _integer(seed, "aia.VectorMissions.reset", "seed", 0,
                        _SEED_MAX - n + 1)
        self._v.reset([seed + i for i in range(n)])
        return self.states(), {"seeds": self.seeds}

    def step(self, moves):
        """moves: (n, robots) integers 0..4 (a list of lists or an integer
        array; floats, bools and other shapes are refused). Returns a
        VectorStepResult: steps, invalid_moves, localized, terminated,
        truncated, success and done as (n,) arrays, and info. Without
        autoreset a mission already done ignores its row; with it, info
        holds final_info (the summary() of each mission that ended at this
        step, else None), final_state (its last state()) and _final_info
        (the mask). A mission over at step 0 (restarted so, too) is not
        stepped: this step reports it done with steps 0."""
        return self._v.step(moves)

    def channels(self, frame=None, **params):
        """Every mission's Mission.channels(frame, **params), one (n, N, C,
        H, W) float32 array, rendered on the vector's threads (the GIL let
        go): the same numbers as the missions' own calls, without a
        Python loop over the missions."""
        if frame is not None:
            params["frame"] = frame
        return self._v.channels(_pairs(params, "channels",
                                       "aia.VectorMissions.channels"))

    def states(self):
        """Every mission's state(), stacked: each array gains a first axis
        of n (the ground truth under "truth" likewise)."""
        states = [m.state() for m in self.missions]
        out = {k: _np.stack([s[k] for s in states])
               for k in states[0] if k != "truth"}
        out["truth"] = {k: _np.stack([s["truth"][k] for s in states])
                        for k in states[0]["truth"]}
        return out


class Dataset:
    """The samples of `aia dataset` folders or shard files, their channels
    rendered by the C++ renderer as `aia train` renders them. `channels`
    are the channel settings (frame, window, cell, geodesic, ...; a model's
    are aia.network.channel_params(meta)).

    labels, useful, acted, world, episode, step, robot: (n,) arrays per
    sample (label: the expert's move; useful: the robot still had useful
    work in the expert's plan); valid: (n, 4) bool, the moves that stay on
    the lattice from the robot's lattice point (Mission.valid_moves() of
    that state), e.g. to train the network's choice among the moves the
    igbnet policy chooses from."""

    def __init__(self, paths, **channels):
        if isinstance(paths, (str, _os.PathLike)):
            paths = [paths]
        if not isinstance(paths, (list, tuple)) or not paths:
            raise InputError(f"aia.Dataset: paths: must be a path or a "
                             f"non-empty list of paths, got {_shown(paths)}")
        self._d = _aia.Dataset(
            [_path(p, "aia.Dataset", "paths") for p in paths],
            _pairs(channels, "channels", "aia.Dataset"))
        samples = self._d.samples()
        self.labels = samples["label"]
        self.useful = samples["useful"]
        self.acted = samples["acted"]
        self.world = samples["world"]
        self.episode = samples["episode"]
        self.step = samples["step"]
        self.robot = samples["robot"]
        self.valid = samples["valid"]

    def __len__(self):
        return len(self._d)

    @property
    def num_worlds(self):
        return self._d.num_worlds

    def split(self, val_share=0.1, seed=1):
        """(train, validation) sample indices, split by world as `aia train
        --val-share --seed` splits (its defaults)."""
        held = self._d.validation_worlds(val_share, seed)
        val = held[self.world]
        return _np.flatnonzero(~val), _np.flatnonzero(val)

    def batch(self, indices):
        """(images (B, C, H, W) float32, labels (B,) int64) of these
        samples: a list or integer array of indices in [0, len)."""
        return self._d.batch(indices)


class _BuiltinPolicy:
    """A registered policy: decide(mission) -> one move per robot."""

    def __init__(self, name, params):
        if not isinstance(name, str):
            raise InputError(f"aia.builtin_policy: name: must be a str, got "
                             f"{_shown(name)}")
        self._p = _aia.BuiltinPolicy(name, _pairs(params, "params",
                                                  "aia.builtin_policy"))

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
        if not isinstance(mission, Mission):
            raise InputError(f"{self!r}.decide: mission: must be an "
                             f"aia.Mission, got {_shown(mission)}")
        return self._p.decide(mission._m)

    def __call__(self, mission):
        return self.decide(mission)

    def __repr__(self):
        return f"aia.builtin_policy({self.name!r})"


def builtin_policy(name, **params):
    """Any registered policy (random, greedy, expert, decsb, igbnet) with
    its parameters, e.g. builtin_policy("igbnet", max_reversals=0)."""
    return _BuiltinPolicy(name, params)


_NAME = _re.compile(r"^[A-Za-z0-9_.-]{1,64}$")


def _runs_done(out, name, sizes, seeds, seed_base):
    """How many of this evaluation's runs of `name` out/runs.csv holds."""
    import csv
    path = _os.path.join(out, "runs.csv")
    if not _os.path.isfile(path):
        return 0
    wanted = set(sizes)
    done = set()
    try:
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                try:
                    seed = int(r["seed"])
                except (KeyError, TypeError, ValueError):
                    continue
                if r.get("policy") == name and r.get("size") in wanted and \
                        seed_base <= seed < seed_base + seeds:
                    done.add((r["size"], seed))
    except (OSError, UnicodeDecodeError, csv.Error):
        return 0
    return len(done)


class _ProgressBar:
    """A one-line progress bar on sys.stderr, as tqdm draws one."""

    def __init__(self, name):
        self.name = name
        self.shown = False

    def __call__(self, done, total):
        width = 24
        filled = width * done // max(total, 1)
        _sys.stderr.write(f"\r[aia.evaluate] {self.name} "
                          f"|{'#' * filled}{'.' * (width - filled)}| "
                          f"{done}/{total} runs")
        _sys.stderr.flush()
        self.shown = True

    def end(self, out):
        if self.shown:
            _sys.stderr.write(f"  -> {out}\n")
            _sys.stderr.flush()


# The worlds one evaluation takes at most, as `aia eval`.
_MAX_WORLDS = _aia.MAX_EVAL_WORLDS


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

    Nothing is printed to stdout. `progress`: True draws a bar on
    sys.stderr; False is silent; a callable is called as progress(done,
    total) with this policy's runs (those already in `out` counted done).
    Notes of `aia eval` (rows dropped from a damaged runs.csv) come as
    RuntimeWarnings. Returns summary.csv's rows as dicts."""
    where = "aia.evaluate"
    decide = getattr(policy, "decide", policy)
    if not callable(decide):
        raise InputError(f"{where}: policy: must be callable, or have "
                         f"decide(mission), got {_shown(policy)}")
    if name is None:
        name = getattr(policy, "name", None) or getattr(policy, "__name__", "")
        if not isinstance(name, str) or not _NAME.match(name):
            name = "python"
    if not isinstance(name, str) or not _NAME.match(name):
        raise InputError(f"{where}: name: must be 1 to 64 letters, digits, "
                         f"'_', '.' or '-', got {name!r}")
    if isinstance(sizes, str):
        sizes = [sizes]
    if not isinstance(sizes, (list, tuple)) or \
            not all(isinstance(s, str) for s in sizes):
        raise InputError(f"{where}: sizes: must be a list of sizes like "
                         f"'10x10', got {_shown(sizes)}")
    seeds = _integer(seeds, where, "seeds", 1, 2 ** 31 - 1)
    seed_base = _integer(seed_base, where, "seed_base", 0, _SEED_MAX)
    if seed_base + seeds - 1 > _SEED_MAX:
        raise InputError(f"{where}: seed_base: the last seed, seed_base + "
                         f"seeds - 1, must fit in 64 bits")
    total = len(sizes) * seeds
    if total > _MAX_WORLDS:
        raise InputError(f"{where}: seeds: {len(sizes)} sizes x {seeds} "
                         f"seeds are {total} worlds, more than one "
                         f"evaluation takes ({_MAX_WORLDS}): split the seeds "
                         "over several calls with seed_base "
                         "(docs/sweeps.md)")
    threads = _integer(threads, where, "threads", 0, 4096)
    if not isinstance(centralized, (bool, _np.bool_)):
        raise InputError(f"{where}: centralized: must be True or False, got "
                         f"{_shown(centralized)}")
    bar = None
    if progress is True:
        bar = _ProgressBar(name)
        report = bar
    elif progress is False or progress is None:
        report = None
    elif callable(progress):
        report = progress
    else:
        raise InputError(f"{where}: progress: must be True, False or a "
                         f"callable progress(done, total), got "
                         f"{_shown(progress)}")
    if out is None:
        import tempfile
        out = tempfile.mkdtemp(prefix="aia_evaluate_")
    out = _path(out, where, "out")
    sets = [f"{k}={v}" for k, v in _pairs(overrides, "overrides", where)]
    # The bar's first line comes from C++ once the inputs are checked.
    done_before = _runs_done(out, name, sizes, seeds, seed_base)
    rc, notes = _aia.evaluate(lambda view: decide(Mission._view(view)), name,
                              bool(centralized), list(sizes), seeds,
                              seed_base, out, threads, sets, report,
                              done_before, total)
    for line in notes.splitlines():
        if line.strip() and "interrupted;" not in line:
            _warnings.warn(line, RuntimeWarning, stacklevel=2)
    if rc == 130:
        if bar is not None:
            bar.end(out)
        if _aia._exiting():  # stopped by the interpreter's exit
            return None
        raise KeyboardInterrupt(f"aia.evaluate: interrupted; the finished "
                                f"rows are in {out}/runs.csv: call again "
                                "with the same arguments to go on")
    if report is not None:
        report(total, total)
    if bar is not None:
        bar.end(out)
    return _read_summary(_os.path.join(out, "summary.csv"))


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


def aec_env(scenario, seed=None, overrides=None, render_mode=None, **kwargs):
    """The PettingZoo AEC API over parallel_env (aia.env.AECEnv: agents act
    in turn; the mission steps when every live agent has acted)."""
    from .env import AECEnv, ParallelEnv
    try:
        parallel = ParallelEnv(scenario, seed=seed, overrides=overrides,
                               render_mode=render_mode, **kwargs)
    except InputError as e:
        # The function the caller called, not the one under it.
        raise InputError(_retitled(str(e), "aia.parallel_env",
                                   "aia.aec_env")) from None
    return AECEnv(parallel)


def policy_names():
    """The registered policies' names."""
    return list(_aia.policy_names())
