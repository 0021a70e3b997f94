"""The PettingZoo APIs over aia.Mission (docs/python.md): ParallelEnv, and
AECEnv, its turn-by-turn form.

Agents are robot_0 ... robot_{N-1}. Each agent observes its I-GBNet
channels (what its own belief, its neighbours and the map show around it)
and a few numbers; its action is a move, 0 left, 1 right, 2 up, 3 down
(infos[agent]["action_mask"] says which stay on the lattice; the stay,
move 4, which Mission.step takes, is not an action here: the paper's four
moves, so that a team cannot learn to idle). Its reward at
a step is the drop of its own summed log det Sigma (each target counted
down to log eps only, as the greedy policy counts gains), less
`step_penalty`. At success every agent terminates and `agents` is empty
(unless mission.stop_at_success is false: a tracking mission runs on);
past mission.max_steps every agent is truncated; a failed robot terminates
and leaves `agents`.

gymnasium's spaces are used when gymnasium imports; else the small
stand-ins below, with shape, dtype, n, sample(), contains() and seed().
"""

import numpy as np

from . import InputError, Mission, Move, _integer, _pairs, _retitled, _shown

try:  # pragma: no cover - gymnasium is not packaged in Debian 12
    from gymnasium import spaces as _spaces
except ImportError:
    _spaces = None


def _seeded(seed):
    """A generator and its seed, as gymnasium's seeding.np_random: the same
    draws as numpy.random.default_rng(seed), and the seed drawn from the
    operating system's entropy when none is given."""
    sequence = np.random.SeedSequence(seed)
    return np.random.Generator(np.random.PCG64(sequence)), sequence.entropy


class Discrete:
    """{0, ..., n-1}, as gymnasium.spaces.Discrete."""

    def __init__(self, n, seed=None):
        self.n = int(n)
        self.shape = ()
        self.dtype = np.dtype(np.int64)
        self._rng = np.random.default_rng(seed)

    def seed(self, seed=None):
        self._rng, seed = _seeded(seed)
        return [seed]

    def sample(self, mask=None):
        """A uniform draw, among the actions whose mask entry is 1 when a
        mask (int8, shape (n,)) is given; 0 when the mask allows none, as
        gymnasium's Discrete.sample(mask) does."""
        if mask is None:
            return int(self._rng.integers(self.n))
        mask = np.asarray(mask)
        if mask.shape != (self.n,) or mask.dtype != np.int8 or \
                not np.all((mask == 0) | (mask == 1)):
            raise InputError(f"Discrete.sample: mask: must be an int8 array "
                             f"of shape ({self.n},) of 0 and 1, got "
                             f"{_shown(mask)}")
        allowed = np.flatnonzero(mask)
        if allowed.size == 0:
            return 0
        return int(self._rng.choice(allowed))

    def __contains__(self, x):
        return self.contains(x)

    def contains(self, x):
        """Integers only (an int, numpy integer or aia.Move, not a bool or
        a float), as gymnasium's Discrete."""
        if isinstance(x, (bool, np.bool_)):
            return False
        if isinstance(x, Move):
            return 0 <= int(x) < self.n
        if isinstance(x, (int, np.integer)):
            return 0 <= int(x) < self.n
        if isinstance(x, np.ndarray) and x.shape == () and \
                np.issubdtype(x.dtype, np.integer):
            return 0 <= int(x) < self.n
        return False

    def __eq__(self, other):
        return isinstance(other, Discrete) and other.n == self.n

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
        self._rng, seed = _seeded(seed)
        return [seed]

    def sample(self, mask=None):
        if mask is not None:
            raise InputError("Box.sample: mask: a Box takes no mask, as "
                             "gymnasium's Box")
        lo = np.where(np.isfinite(self.low), self.low, -1.0)
        hi = np.where(np.isfinite(self.high), self.high, lo + 1.0)
        return self._rng.uniform(lo, hi).astype(self.dtype)

    def contains(self, x):
        # A list or a number is read as this space's dtype, as gymnasium's.
        if not isinstance(x, np.ndarray):
            try:
                x = np.asarray(x, dtype=self.dtype)
            except (TypeError, ValueError):
                return False
        return (x.shape == self.shape and np.can_cast(x.dtype, self.dtype)
                and bool(np.all(x >= self.low)) and bool(np.all(x <= self.high)))

    def __contains__(self, x):
        return self.contains(x)

    def __eq__(self, other):
        return (isinstance(other, Box) and other.shape == self.shape and
                other.dtype == self.dtype and
                np.array_equal(other.low, self.low) and
                np.array_equal(other.high, self.high))

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

    # A mapping, as gymnasium's Dict.
    def __iter__(self):
        return iter(self.spaces)

    def __len__(self):
        return len(self.spaces)

    def keys(self):
        return self.spaces.keys()

    def values(self):
        return self.spaces.values()

    def items(self):
        return self.spaces.items()

    def seed(self, seed=None):
        seeds = []
        for i, s in enumerate(self.spaces.values()):
            seeds += s.seed(None if seed is None else seed + i)
        return seeds

    def sample(self, mask=None):
        if mask is not None:
            raise InputError("Dict.sample: mask: the stand-in Dict takes no "
                             "mask")
        return {k: s.sample() for k, s in self.spaces.items()}

    def __contains__(self, x):
        return self.contains(x)

    def contains(self, x):
        return (isinstance(x, dict) and set(x) == set(self.spaces) and
                all(s.contains(x[k]) for k, s in self.spaces.items()))

    def __eq__(self, other):
        return isinstance(other, Dict) and other.spaces == self.spaces

    def __repr__(self):
        return f"Dict({self.spaces})"


def _observation_space(channels_shape, vector_size):
    if _spaces is not None:  # pragma: no cover
        return _spaces.Dict({
            "channels": _spaces.Box(0.0, np.inf, channels_shape, np.float32),
            "vector": _spaces.Box(-np.inf, np.inf, (vector_size,),
                                  np.float32)})
    return Dict({"channels": Box(0.0, np.inf, channels_shape, np.float32),
                 "vector": Box(-np.inf, np.inf, (vector_size,), np.float32)})


def _action_space():
    if _spaces is not None:  # pragma: no cover
        return _spaces.Discrete(4)
    return Discrete(4)


def _box(size):
    if _spaces is not None:  # pragma: no cover
        return _spaces.Box(-np.inf, np.inf, (size,), np.float32)
    return Box(-np.inf, np.inf, (size,), np.float32)


# The vector features of an agent's observation, in order.
VECTOR_FEATURES = ("x_share", "y_share", "step_share", "localized_share")


class _UnknownAgent(InputError, KeyError):
    """An agent not among possible_agents: bad input (aia.InputError, as
    python.md says) and a KeyError, as a dict of the agents' spaces says."""

    def __str__(self):  # the message, not KeyError's quoted repr of it
        return str(self.args[0]) if self.args else ""


class ParallelEnv:
    """aia as a PettingZoo ParallelEnv; see the module's doc."""

    metadata = {"render_modes": ["rgb_array"], "name": "aia_v0",
                "is_parallelizable": True}

    def __init__(self, scenario, seed=None, overrides=None, render_mode=None,
                 channels=None, step_penalty=0.01):
        where = "aia.parallel_env"
        if render_mode not in (None, "rgb_array"):
            raise InputError(f"{where}: render_mode: must be None or "
                             f"'rgb_array', got {render_mode!r}")
        if channels is not None and not isinstance(channels, dict):
            raise InputError(f"{where}: channels: must be a dict of channel "
                             f"settings, got {_shown(channels)}")
        if isinstance(step_penalty, (bool, np.bool_)) or \
                not isinstance(step_penalty,
                               (int, float, np.integer, np.floating)) or \
                not np.isfinite(step_penalty):
            raise InputError(f"{where}: step_penalty: must be a finite "
                             f"number, got {_shown(step_penalty)}")
        self.render_mode = render_mode
        self._scenario = scenario
        _pairs(overrides, "overrides", where)  # a dict, or InputError
        self._overrides = dict(overrides or {})
        self._channels = dict(channels or {})
        self._step_penalty = float(step_penalty)
        first = Mission(self._scenario, seed=seed, overrides=self._overrides,
                        _where=where)
        if first.asynchronous:
            raise InputError(f"{where}: mission.decisions: async is not "
                             "an env's step (every agent acts at once); "
                             "step an aia.Mission, whose ready says who "
                             "decides")
        self._seed = first.seed
        self._next_seed = first.seed
        n, m = first.num_robots, first.num_targets
        self.possible_agents = [f"robot_{i}" for i in range(n)]
        self._robot = {a: i for i, a in enumerate(self.possible_agents)}
        self.agents = []
        try:
            shape = first.channels(**self._channels).shape[1:]
        except InputError as e:  # named as this function's argument
            raise InputError(_retitled(str(e), "aia.Mission.channels",
                                       where)) from None
        # One space object per agent: seeding one seeds that one only.
        self._observation_spaces = {
            a: _observation_space(shape, len(VECTOR_FEATURES))
            for a in self.possible_agents}
        self._action_spaces = {a: _action_space()
                               for a in self.possible_agents}
        # state(): positions (N, 2) and active (N,) of the robots; per
        # target the team's best clipped log det share and its mean (M, 2);
        # the step share.
        self._state_space = _box(3 * n + 3 * m + 1)
        # Every reset restarts this one mission: the scenario is the file as
        # read now (not as edited later, nor read from another working
        # directory), and its warnings were said once, above.
        self._made = first
        first._stepped_by = "aia.ParallelEnv"
        self._mission = None
        self._closed = False
        self._left = {}

    @property
    def num_agents(self):
        return len(self.agents)

    @property
    def max_num_agents(self):
        return len(self.possible_agents)

    @property
    def unwrapped(self):
        return self

    # The spaces, refused after close() as every call is.
    @property
    def observation_spaces(self):
        self._open("observation_spaces")
        return self._observation_spaces

    @property
    def action_spaces(self):
        self._open("action_spaces")
        return self._action_spaces

    @property
    def state_space(self):
        self._open("state_space")
        return self._state_space

    def observation_space(self, agent, _api="ParallelEnv"):
        self._open("observation_space", _api)
        return self._observation_spaces[self._agent(agent, "observation_space",
                                                    _api)]

    def action_space(self, agent, _api="ParallelEnv"):
        self._open("action_space", _api)
        return self._action_spaces[self._agent(agent, "action_space", _api)]

    def _agent(self, agent, what, api):
        if agent not in self._robot:
            raise _UnknownAgent(
                f"aia.{api}.{what}: agent: unknown agent {agent!r}; agents "
                f"are robot_0 .. robot_{len(self.possible_agents) - 1}")
        return agent

    def _open(self, what, api="ParallelEnv"):
        if self._closed:
            raise InputError(f"aia.{api}.{what}: the env is closed "
                             "(close() was called): make another one")

    def _started(self, what, api="ParallelEnv"):
        self._open(what, api)
        if self._mission is None:
            raise InputError(f"aia.{api}.{what}: call reset() before "
                             f"{what}()")

    def reset(self, seed=None, options=None, *, _api="ParallelEnv"):
        """A new mission: at `seed`, else the constructor's seed at the first
        reset and the previous one + 1 after. A mission already over at
        step 0 (every target localized by the prior and the first
        measurements, or no robot active) has no agents: `agents` is empty
        and both dicts are empty; reset again for the next seed. `options`
        must be None or an empty dict: this env takes no options."""
        self._open("reset", _api)
        where = f"aia.{_api}.reset"
        if options is not None and (not isinstance(options, dict) or
                                    options):
            raise InputError(f"{where}: options: this env takes no options "
                             f"(None or {{}}), got {_shown(options)}")
        if seed is not None:
            self._next_seed = _integer(seed, where, "seed", 0, 2 ** 64 - 1)
        self._made._restart(self._next_seed, where)
        self._mission = self._made
        self._next_seed = (self._next_seed + 1) % 2 ** 64
        state = self._mission.state()
        self._log_det = self._own_log_det(state)
        # Over already (success at step 0): no agent to step.
        self.agents = [] if self._mission.done else [
            a for i, a in enumerate(self.possible_agents)
            if state["active"][i]]
        self._left = {}
        observations = self._observations(state)
        masks = self._mission.valid_moves().astype(np.int8)
        infos = {a: {"seed": self._mission.seed,
                     "action_mask": masks[self._robot[a]]}
                 for a in self.agents}
        return observations, infos

    def _own_log_det(self, state):
        log_eps = np.log(state["eps"])
        with np.errstate(divide="ignore"):
            return np.maximum(np.log(state["det"]), log_eps).sum(axis=1)

    def _observations(self, state, agents=None):
        m = self._mission
        channels = m.channels(**self._channels)
        localized = (state["det"] < state["eps"]).mean(axis=1)
        step_share = state["steps"] / max(m.max_steps, 1)
        out = {}
        for a in self.agents if agents is None else agents:
            i = self._robot[a]
            x, y = state["positions"][i] / state["workspace"]
            out[a] = {"channels": channels[i],
                      "vector": np.array([x, y, step_share, localized[i]],
                                         dtype=np.float32)}
        return out

    def _moves(self, actions):
        if not isinstance(actions, dict):
            raise InputError(f"aia.ParallelEnv.step: actions: must be a dict "
                             f"of agent -> move, got {_shown(actions)}")
        agents = set(self.agents)  # a list's `in` made a step O(N^2)
        for a in actions:
            if a not in self._robot:
                raise InputError(
                    f"aia.ParallelEnv.step: actions: unknown agent {a!r}; "
                    f"agents are robot_0 .. "
                    f"robot_{len(self.possible_agents) - 1}")
            if a not in agents:
                why = (f"it left at step {self._left[a]}" if a in self._left
                       else "it was not active at reset")
                raise InputError(f"aia.ParallelEnv.step: actions[{a!r}]: "
                                 f"{a} is not among the agents ({why})")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise InputError(f"aia.ParallelEnv.step: actions: no move for "
                             f"{', '.join(missing)}")
        moves = np.full(len(self.possible_agents), 4, dtype=np.int64)
        for a, move in actions.items():
            moves[self._robot[a]] = _integer(
                move, "aia.ParallelEnv.step", f"actions[{a!r}]", 0, 3)
        return moves

    def step(self, actions):
        """actions: {agent: move} for every agent in `agents`, each an
        integer 0 (left), 1 (right), 2 (up) or 3 (down)."""
        self._started("step")
        if not self.agents:
            raise InputError("aia.ParallelEnv.step: the mission is over "
                             "(agents is empty): call reset()")
        result = self._mission._m.step(self._moves(actions))
        state = self._mission.state()
        log_det = self._own_log_det(state)
        drop = self._log_det - log_det
        self._log_det = log_det
        # The mission's own end: success ends it only where it stops at
        # success (a tracking mission runs to its horizon, truncated).
        success, truncated = result.terminated, result.truncated
        masks = self._mission.valid_moves().astype(np.int8)
        alive = self.agents
        rewards, terminations, truncations, infos = {}, {}, {}, {}
        for a in alive:
            i = self._robot[a]
            rewards[a] = float(drop[i]) - self._step_penalty
            failed = not state["active"][i]
            terminations[a] = bool(success or failed)
            truncations[a] = bool(truncated and not failed)
            infos[a] = {"action_mask": masks[i]}
        self.agents = [a for a in alive
                       if not (terminations[a] or truncations[a])]
        for a in alive:
            if terminations[a] or truncations[a]:
                self._left[a] = state["steps"]
        # The agents that left see their last observation too.
        observations = self._observations(state, alive)
        return observations, rewards, terminations, truncations, infos

    def state(self, *, _api="ParallelEnv"):
        """The team's state as one float32 array (state_space), for a
        centralized critic: robot positions / workspace (N, 2), active (N,),
        per target the team's best log det Sigma as a share between log eps
        (0) and the prior (1), that estimate's mean / workspace (M, 2), and
        steps / max_steps. No ground truth (state_dict() has it)."""
        self._started("state", _api)
        s = self._mission.state()
        n, m = s["det"].shape
        size = np.asarray(s["workspace"], dtype=np.float64)
        log_eps = np.log(s["eps"])
        with np.errstate(divide="ignore"):
            log_det = np.maximum(np.log(s["det"]), log_eps)  # (N, M)
        best = np.argmin(log_det, axis=0)                     # (M,)
        span = np.maximum(s["log_det_prior"] - log_eps, 1e-9)
        share = (log_det[best, np.arange(m)] - log_eps) / span
        means = s["mean"][best, np.arange(m)] / size
        return np.concatenate([
            (s["positions"] / size).ravel(), s["active"].astype(np.float64),
            share, means.ravel(),
            [s["steps"] / max(self._mission.max_steps, 1)]]).astype(
                np.float32)

    def state_dict(self):
        """The whole team's state as aia.Mission.state() gives it (the
        ground truth under "truth")."""
        self._started("state_dict")
        return self._mission.state()

    @property
    def mission(self):
        return self._mission

    def render(self, width=640, height=480, *, _api="ParallelEnv"):
        """With render_mode "rgb_array": the mission's frame (H, W, 3)."""
        self._open("render", _api)
        if self.render_mode is None:
            return None
        self._started("render", _api)
        try:
            return self._mission.render(width, height)
        except InputError as e:  # named as this env's render
            raise InputError(_retitled(str(e), "aia.Mission.render",
                                       f"aia.{_api}.render")) from None

    def close(self):
        """Ends the env: every call but close() is refused after."""
        self._mission = None
        self._made = None
        self.agents = []
        self._closed = True


class AECEnv:
    """A ParallelEnv as PettingZoo's AEC API (what pettingzoo's
    parallel_to_aec gives): agents act in turn (agent_selection), the
    mission steps once every live agent has acted; an agent that ended
    stays in `agents` until it is stepped with None."""

    metadata = ParallelEnv.metadata

    def __init__(self, parallel):
        self._env = parallel
        self.possible_agents = list(parallel.possible_agents)
        self.agents = []
        self.agent_selection = None
        self.rewards = {}
        self._cumulative_rewards = {}
        self.terminations = {}
        self.truncations = {}
        self.infos = {}
        self._observations = {}
        self._actions = {}

    @property
    def unwrapped(self):
        return self._env

    @property
    def render_mode(self):
        return self._env.render_mode

    # The spaces, refused after close() as the parallel env's are.
    @property
    def observation_spaces(self):
        self._env._open("observation_spaces", "AECEnv")
        return self._env._observation_spaces

    @property
    def action_spaces(self):
        self._env._open("action_spaces", "AECEnv")
        return self._env._action_spaces

    @property
    def state_space(self):
        self._env._open("state_space", "AECEnv")
        return self._env._state_space

    @property
    def num_agents(self):
        return len(self.agents)

    def agent_iter(self, max_iter=2 ** 63):
        """The agents in turn, agent_selection each time, until none is
        left or max_iter have been given (PettingZoo's loop:
        `for agent in env.agent_iter(): ... env.step(action)`)."""
        for _ in range(max_iter):
            if not self.agents or self.agent_selection is None:
                return
            yield self.agent_selection

    @property
    def max_num_agents(self):
        return len(self.possible_agents)

    def observation_space(self, agent):
        return self._env.observation_space(agent, _api="AECEnv")

    def action_space(self, agent):
        return self._env.action_space(agent, _api="AECEnv")

    def reset(self, seed=None, options=None):
        self._observations, self.infos = self._env.reset(seed, options,
                                                         _api="AECEnv")
        self.agents = list(self._env.agents)
        self.rewards = {a: 0.0 for a in self.agents}
        self._cumulative_rewards = {a: 0.0 for a in self.agents}
        self.terminations = {a: False for a in self.agents}
        self.truncations = {a: False for a in self.agents}
        self._actions = {}
        # The agents the last mission step ended, in order, each still in
        # `agents` until it is stepped with None (from _ended_next on), and
        # whether `rewards` are all 0 since: each turn is O(1), a round
        # O(N) (a pass over the agents per turn made a round of 800
        # agents cost more than the mission's step).
        self._ended_queue, self._ended_next = [], 0
        self._rewards_zeroed = True
        self.agent_selection = self.agents[0] if self.agents else None

    def observe(self, agent):
        """`agent`'s last observation (None if it has had none: it was not
        active at reset)."""
        self._env._open("observe", "AECEnv")
        if agent not in self._env._robot:
            raise InputError(f"aia.AECEnv.observe: agent: unknown agent "
                             f"{agent!r}; agents are robot_0 .. "
                             f"robot_{len(self.possible_agents) - 1}")
        return self._observations.get(agent)

    def last(self, observe=True):
        """The selected agent's observation, cumulative reward,
        termination, truncation and info."""
        self._env._open("last", "AECEnv")
        a = self.agent_selection
        if a is None:
            raise InputError("aia.AECEnv.last: no agent is selected (before "
                             "reset(), or every agent has left): call "
                             "reset()")
        return (self.observe(a) if observe else None,
                self._cumulative_rewards[a], self.terminations[a],
                self.truncations[a], self.infos[a])

    def _ended(self, agent):
        return self.terminations[agent] or self.truncations[agent]

    def step(self, action):
        """The selected agent's move (0 left, 1 right, 2 up, 3 down), or
        None for an agent that has ended. A bad action is refused at once
        and changes nothing."""
        self._env._open("step", "AECEnv")
        a = self.agent_selection
        if a is None:
            raise InputError("aia.AECEnv.step: no agent left: call reset()")
        if self._ended(a):
            if action is not None:
                raise InputError(f"aia.AECEnv.step: action: {a} has ended: "
                                 f"step it with None, got {_shown(action)}")
            self.agents.remove(a)
            for d in (self.rewards, self._cumulative_rewards,
                      self.terminations, self.truncations, self.infos):
                d.pop(a, None)
            self._ended_next += 1
            self.agent_selection = self._next()
            return
        if action is None:
            raise InputError(f"aia.AECEnv.step: action: {a} is live: give "
                             "it a move 0 (left), 1 (right), 2 (up) or 3 "
                             "(down); None is for an agent that has ended")
        action = _integer(action, "aia.AECEnv.step", "action", 0, 3)
        self._cumulative_rewards[a] = 0.0
        self._actions[a] = action
        if len(self._actions) < len(self.agents):
            self.agent_selection = self._next()
            if not self._rewards_zeroed:
                for b in self.rewards:
                    self.rewards[b] = 0.0
                self._rewards_zeroed = True
            return
        obs, rewards, terms, truncs, infos = self._env.step(self._actions)
        self._actions = {}
        self._observations.update(obs)
        for b in rewards:
            self.rewards[b] = rewards[b]
            self._cumulative_rewards[b] += rewards[b]
            self.terminations[b] = terms[b]
            self.truncations[b] = truncs[b]
            self.infos[b] = infos[b]
        self._rewards_zeroed = False
        # Ended agents first (each is stepped with None), then the live.
        self._ended_queue = [b for b in self.agents if self._ended(b)]
        self._ended_next = 0
        self.agent_selection = self._next()

    def _next(self):
        """The next agent to act: an ended one first (in order), else the
        first live agent that has not acted this round. A round's live
        agents act in the order of `agents` once the ended ones are gone,
        so those that acted are the first len(_actions) of `agents`."""
        if self._ended_next < len(self._ended_queue):
            return self._ended_queue[self._ended_next]
        if len(self._actions) < len(self.agents):
            return self.agents[len(self._actions)]
        return None

    def state(self):
        return self._env.state(_api="AECEnv")

    def render(self, width=640, height=480):
        return self._env.render(width, height, _api="AECEnv")

    def close(self):
        self._env.close()
        self.agents = []
        self.agent_selection = None
