"""The PettingZoo ParallelEnv API over aia.Mission (docs/python.md).

Agents are robot_0 ... robot_{N-1}. Each agent observes its I-GBNet
channels (what its own belief, its neighbours and the map show around it)
and a few numbers; its action is a move, 0 left, 1 right, 2 up, 3 down.
Its reward at a step is the drop of its own summed log det Sigma (each
target counted down to log eps only, as the greedy policy counts gains),
less `step_penalty`. At success every agent terminates and `agents` is
empty; past mission.max_steps every agent is truncated; a failed robot
terminates and leaves `agents`.

gymnasium's spaces are used when gymnasium imports; else the small
stand-ins below, with shape, dtype, n, sample(), contains() and seed().
"""

import numpy as np

from . import Mission

try:  # pragma: no cover - gymnasium is not packaged in Debian 12
    from gymnasium import spaces as _spaces
except ImportError:
    _spaces = None


class Discrete:
    """{0, ..., n-1}, as gymnasium.spaces.Discrete."""

    def __init__(self, n, seed=None):
        self.n = int(n)
        self.shape = ()
        self.dtype = np.dtype(np.int64)
        self._rng = np.random.default_rng(seed)

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def sample(self):
        return int(self._rng.integers(self.n))

    def contains(self, x):
        try:
            v = int(x)
        except (TypeError, ValueError):
            return False
        return v == x and 0 <= v < self.n

    def __repr__(self):
        return f"Discrete({self.n})"


class Box:
    """Arrays of `shape` within [low, high], as gymnasium.spaces.Box."""

    def __init__(self, low, high, shape, dtype=np.float32, seed=None):
        self.shape = tuple(shape)
        self.dtype = np.dtype(dtype)
        self.low = np.full(self.shape, low, dtype=self.dtype)
        self.high = np.full(self.shape, high, dtype=self.dtype)
        self._rng = np.random.default_rng(seed)

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def sample(self):
        lo = np.where(np.isfinite(self.low), self.low, -1.0)
        hi = np.where(np.isfinite(self.high), self.high, lo + 1.0)
        return self._rng.uniform(lo, hi).astype(self.dtype)

    def contains(self, x):
        x = np.asarray(x)
        return (x.shape == self.shape and np.can_cast(x.dtype, self.dtype)
                and bool(np.all(x >= self.low)) and bool(np.all(x <= self.high)))

    def __repr__(self):
        return f"Box({self.shape}, {self.dtype})"


class Dict:
    """A mapping of named spaces, as gymnasium.spaces.Dict."""

    def __init__(self, spaces):
        self.spaces = dict(spaces)
        self.shape = None
        self.dtype = None

    def __getitem__(self, key):
        return self.spaces[key]

    def seed(self, seed=None):
        for i, s in enumerate(self.spaces.values()):
            s.seed(None if seed is None else seed + i)

    def sample(self):
        return {k: s.sample() for k, s in self.spaces.items()}

    def contains(self, x):
        return (isinstance(x, dict) and set(x) == set(self.spaces) and
                all(s.contains(x[k]) for k, s in self.spaces.items()))

    def __repr__(self):
        return f"Dict({self.spaces})"


def _make_spaces(channels_shape, vector_size):
    if _spaces is not None:  # pragma: no cover
        obs = _spaces.Dict({
            "channels": _spaces.Box(0.0, np.inf, channels_shape, np.float32),
            "vector": _spaces.Box(-np.inf, np.inf, (vector_size,),
                                  np.float32)})
        return obs, _spaces.Discrete(4)
    obs = Dict({"channels": Box(0.0, np.inf, channels_shape, np.float32),
                "vector": Box(-np.inf, np.inf, (vector_size,), np.float32)})
    return obs, Discrete(4)


# The vector features of an agent's observation, in order.
VECTOR_FEATURES = ("x_share", "y_share", "step_share", "localized_share")


class ParallelEnv:
    """aia as a PettingZoo ParallelEnv; see the module's doc."""

    metadata = {"render_modes": ["rgb_array"], "name": "aia_v0",
                "is_parallelizable": True}

    def __init__(self, scenario, seed=None, overrides=None, render_mode=None,
                 channels=None, step_penalty=0.01):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode: must be None or 'rgb_array', got "
                             f"{render_mode!r}")
        self.render_mode = render_mode
        self._scenario = str(scenario)
        self._overrides = dict(overrides or {})
        self._channels = dict(channels or {})
        self._step_penalty = float(step_penalty)
        first = Mission(self._scenario, seed=seed, overrides=self._overrides)
        self._seed = first.seed
        self._next_seed = first.seed
        self.possible_agents = [f"robot_{i}" for i in range(first.num_robots)]
        self._robot = {a: i for i, a in enumerate(self.possible_agents)}
        self.agents = []
        shape = first.channels(**self._channels).shape[1:]
        self._observation_space, self._action_space = _make_spaces(
            shape, len(VECTOR_FEATURES))
        self._mission = None

    @property
    def num_agents(self):
        return len(self.agents)

    @property
    def max_num_agents(self):
        return len(self.possible_agents)

    def observation_space(self, agent):
        self._index(agent)
        return self._observation_space

    def action_space(self, agent):
        self._index(agent)
        return self._action_space

    def _index(self, agent):
        try:
            return self._robot[agent]
        except KeyError:
            raise KeyError(f"unknown agent {agent!r}; agents are robot_0 .. "
                           f"robot_{len(self.possible_agents) - 1}") from None

    def reset(self, seed=None, options=None):
        """A new mission: at `seed`, else the constructor's seed at the first
        reset and the previous one + 1 after."""
        if seed is not None:
            self._next_seed = int(seed)
        self._mission = Mission(self._scenario, seed=self._next_seed,
                                overrides=self._overrides)
        self._next_seed += 1
        state = self._mission.state()
        self._log_det = self._own_log_det(state)
        self.agents = [a for i, a in enumerate(self.possible_agents)
                       if state["active"][i]]
        observations = self._observations(state)
        infos = {a: {"seed": self._mission.seed} for a in self.agents}
        return observations, infos

    def _own_log_det(self, state):
        log_eps = np.log(state["eps"])
        with np.errstate(divide="ignore"):
            return np.maximum(np.log(state["det"]), log_eps).sum(axis=1)

    def _observations(self, state):
        m = self._mission
        channels = m.channels(**self._channels)
        localized = (state["det"] < state["eps"]).mean(axis=1)
        step_share = state["step"] / max(m.max_steps, 1)
        out = {}
        for a in self.agents:
            i = self._robot[a]
            x, y = state["positions"][i] / state["workspace"]
            out[a] = {"channels": channels[i],
                      "vector": np.array([x, y, step_share, localized[i]],
                                         dtype=np.float32)}
        return out

    def step(self, actions):
        """actions: {agent: move} for every agent in `agents`."""
        if self._mission is None:
            raise RuntimeError("call reset() before step()")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(f"actions: no move for {', '.join(missing)}")
        moves = np.full(len(self.possible_agents), 4, dtype=np.int64)
        for a, move in actions.items():
            i = self._index(a)
            if a in self.agents:
                if not self._action_space.contains(move):
                    raise ValueError(f"actions[{a!r}]: must be 0 (left), 1 "
                                     f"(right), 2 (up) or 3 (down), got "
                                     f"{move!r}")
                moves[i] = int(move)
        self._mission.step(moves)
        state = self._mission.state()
        log_det = self._own_log_det(state)
        drop = self._log_det - log_det
        self._log_det = log_det
        success = self._mission.success
        truncated = self._mission.done and not success
        alive = self.agents
        rewards, terminations, truncations, infos = {}, {}, {}, {}
        for a in alive:
            i = self._robot[a]
            rewards[a] = float(drop[i]) - self._step_penalty
            failed = not state["active"][i]
            terminations[a] = bool(success or failed)
            truncations[a] = bool(truncated and not failed)
            infos[a] = {}
        self.agents = [a for a in alive
                       if not (terminations[a] or truncations[a])]
        observations = self._observations(state)
        # The agents that left see their last observation too.
        for a in alive:
            if a not in observations:
                i = self._robot[a]
                observations[a] = self._last_observation(state, i)
        return observations, rewards, terminations, truncations, infos

    def _last_observation(self, state, i):
        agents, self.agents = self.agents, [self.possible_agents[i]]
        try:
            return self._observations(state)[self.possible_agents[i]]
        finally:
            self.agents = agents

    def state(self):
        """The whole team's state (aia.Mission.state), for a critic."""
        return self._mission.state()

    @property
    def mission(self):
        return self._mission

    def render(self, width=640, height=480):
        """With render_mode "rgb_array": the mission's frame (H, W, 3)."""
        if self.render_mode is None:
            return None
        if self._mission is None:
            raise RuntimeError("call reset() before render()")
        return self._mission.render(width, height)

    def close(self):
        self._mission = None
