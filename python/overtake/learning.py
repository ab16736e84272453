"""The learning environment: many worlds stepped per call, numpy arrays in and out, with
Gymnasium's conventions (docs/learning.md).

- ``VecEnv(num_envs, seed=0, actions="meta", ...)``: a vector environment of ``num_envs``
  worlds, stepped together in C++ threads with the GIL released; next-step autoreset as
  Gymnasium 1.x vector environments do.
- ``HighwayEnv(...)``: the one-world form, a Gymnasium ``Env`` (registered as
  ``overtake/Highway-v0`` when gymnasium is importable).
- ``Box``, ``Discrete``: small self-describing spaces, used when gymnasium is not there.

Observation: float32, ``observation_size`` = 7 + lanes x 2 x 4 (31 on three lanes): the ego's
speed, offset from its lane's centre, lane, acceleration, time in the current manoeuvre,
target speed and target lane (relative); then for each lane (0 first) its nearest car ahead
and behind: present, gap, relative speed, offset from that lane's centre (0 where there is
none). ``observation="telemetry"`` gives each world's telemetry dict instead.

Actions: "meta" (0 keep, 1 left, 2 right, 3 faster, 4 slower; carried out by the reference
planner's trajectory layer), "continuous" ([target speed in 0..1 of the cruise speed, target
lane in -1..1 across the road]) or "path" (an array (num_envs, P, 2) of map points; a row of
two NaN ends a path early).
"""

import numpy as np

from ._overtake import EGO_FEATURES, META_ACTIONS, SLOT_FEATURES
from ._overtake import PolicyDriverCore as _DriverCore
from ._overtake import VecEnvCore as _Core

try:  # real spaces and a registration when gymnasium is there; small ones otherwise
    import gymnasium as _gym
    from gymnasium import spaces as _spaces
except ImportError:  # pragma: no cover - depends on the machine
    _gym = None
    _spaces = None

__all__ = ["VecEnv", "HighwayEnv", "Driver", "Box", "Discrete", "META_ACTIONS", "META_ACTION_NAMES",
           "observation_names"]

META_ACTION_NAMES = ("keep", "left", "right", "faster", "slower")

_EGO_NAMES = ("ego_speed", "ego_lane_offset", "ego_lane", "ego_accel", "ego_manoeuvre_time",
              "ego_target_speed", "ego_target_lane")
_SLOT_NAMES = ("present", "gap", "rel_speed", "lane_offset")


def observation_names(lanes=3):
    """The name of each float of an observation, in order."""
    names = list(_EGO_NAMES)
    for lane in range(lanes):
        for where in ("ahead", "behind"):
            names += [f"lane{lane}_{where}_{n}" for n in _SLOT_NAMES]
    assert len(names) == EGO_FEATURES + lanes * 2 * SLOT_FEATURES
    return names


class Box:
    """A box of shape ``shape`` between ``low`` and ``high`` (gymnasium.spaces.Box's fields)."""

    def __init__(self, low, high, shape, dtype):
        self.shape = tuple(shape)
        self.dtype = np.dtype(dtype)
        self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), self.shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), self.shape).copy()
        self._rng = np.random.default_rng()

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def sample(self):
        low = np.where(np.isfinite(self.low), self.low, -1e3)
        high = np.where(np.isfinite(self.high), self.high, 1e3)
        return self._rng.uniform(low, high).astype(self.dtype)

    def contains(self, x):
        x = np.asarray(x)
        return (x.shape == self.shape and bool(np.all(x >= self.low))
                and bool(np.all(x <= self.high)))

    def __repr__(self):
        return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"


class Discrete:
    """The integers 0 .. n-1 (gymnasium.spaces.Discrete's fields)."""

    def __init__(self, n):
        self.n = int(n)
        self.shape = ()
        self.dtype = np.dtype(np.int64)
        self._rng = np.random.default_rng()

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def sample(self):
        return np.int64(self._rng.integers(self.n))

    def contains(self, x):
        return isinstance(x, (int, np.integer)) and 0 <= int(x) < self.n

    def __repr__(self):
        return f"Discrete({self.n})"


class _MultiDiscrete(Discrete):
    """num_envs integers 0 .. n-1 (the batched meta-action space without gymnasium)."""

    def __init__(self, nvec):
        super().__init__(int(nvec[0]))
        self.nvec = np.asarray(nvec, dtype=np.int64)
        self.shape = self.nvec.shape

    def sample(self):
        return self._rng.integers(self.nvec)

    def contains(self, x):
        x = np.asarray(x)
        return x.shape == self.shape and bool(np.all((x >= 0) & (x < self.nvec)))

    def __repr__(self):
        return f"MultiDiscrete({self.nvec.tolist()})"


def _box(low, high, shape, dtype):
    if _spaces is not None:
        return _spaces.Box(low=low, high=high, shape=shape, dtype=dtype)
    return Box(low, high, shape, dtype)


def _discrete(n):
    return _spaces.Discrete(n) if _spaces is not None else Discrete(n)


def _multi_discrete(nvec):
    return _spaces.MultiDiscrete(nvec) if _spaces is not None else _MultiDiscrete(nvec)


def _fspath(p):
    import os
    return None if p is None else os.fspath(p)


class VecEnv:
    """``num_envs`` worlds stepped together (Gymnasium's vector environment conventions).

    VecEnv(num_envs, seed=0, actions="meta", map=None, traffic="faithful", config=None,
    params=None, minutes=5.0, threads=0, observation="array", name="agent")

    - seed: env i's first episode is the drive of seed + i (``overtake drive --seed``); its
      later episodes are drawn from it. ``reset(seed=s)`` starts them again from s + i.
    - actions: "meta", "continuous" or "path" (see the module's doc).
    - params: a file of config/learn.json's keys (decision steps, observation scales, the
      reward's weights); config: the world's and planner's parameters; minutes: an episode's
      length (truncated there); threads: 0 for one per core.
    - observation: "array" (float32, (num_envs, observation_size)) or "telemetry" (a list of
      each world's telemetry dict).

    ``step(actions)`` returns (observation, reward, terminated, truncated, info): float32,
    float32, bool and bool arrays of num_envs, and a dict of arrays (episode_seed, episode,
    time_s, distance_m, speed_mps, lane, target_lane, target_speed_mps, collisions, at_fault,
    incidents, episode_return, episode_length, was_reset); where an episode ended,
    info["final_report"][i] is its report (the dict ``overtake drive --json`` writes) with
    info["_final_report"][i] True, and info["episode"] its return and length. The call after
    an episode ends begins the next one in that env (its action is not taken: reward 0,
    neither terminated nor truncated, was_reset True).
    """

    metadata = {"autoreset_mode": "NextStep", "render_modes": []}

    def __init__(self, num_envs=1, seed=0, actions="meta", map=None, traffic="faithful",
                 config=None, params=None, minutes=5.0, threads=0, observation="array",
                 name="agent"):
        if observation not in ("array", "telemetry"):
            raise ValueError(f"observation: '{observation}' is not 'array' or 'telemetry'")
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)):
            raise TypeError("num_envs must be a whole number")
        if num_envs < 1:
            raise ValueError(f"num_envs must be at least 1 (got {num_envs})")
        if seed is None:
            seed = 0
        self._core = _Core(int(num_envs), int(seed), str(actions), _fspath(map), str(traffic),
                           _fspath(config), _fspath(params), float(minutes), int(threads),
                           str(name))
        self.num_envs = self._core.num_envs
        self.observation_mode = observation
        self.observation_size = self._core.observation_size
        self.lanes = self._core.lanes
        self.actions = self._core.actions
        self.single_observation_space = _box(-2.0, 2.0, (self.observation_size,), np.float32)
        self.observation_space = _box(-2.0, 2.0, (self.num_envs, self.observation_size),
                                      np.float32)
        if self.actions == "meta":
            self.single_action_space = _discrete(META_ACTIONS)
            self.action_space = _multi_discrete([META_ACTIONS] * self.num_envs)
        elif self.actions == "continuous":
            low, high = np.array([0.0, -1.0]), np.array([1.0, 1.0])
            self.single_action_space = _box(low, high, (2,), np.float32)
            self.action_space = _box(np.tile(low, (self.num_envs, 1)),
                                     np.tile(high, (self.num_envs, 1)), (self.num_envs, 2),
                                     np.float32)
        else:
            points = self._core.max_path_points
            self.single_action_space = _box(-np.inf, np.inf, (points, 2), np.float64)
            self.action_space = _box(-np.inf, np.inf, (self.num_envs, points, 2), np.float64)
        self._closed = False
        self._started = False

    @property
    def params(self):
        """The environment's parameters in effect (config/learn.json's keys)."""
        return self._core.params

    def _observation(self, obs):
        if self.observation_mode == "array":
            return obs
        return [self._core.telemetry(i) for i in range(self.num_envs)]

    def _info(self):
        return self._core.status()

    def reset(self, seed=None, options=None):
        """Begins an episode in every world; returns (observation, info)."""
        del options  # none yet
        self._check_open()
        if seed is not None and not isinstance(seed, (int, np.integer)):
            raise TypeError("seed must be a whole number or None (one seed: env i gets seed + i)")
        obs = self._core.reset(None if seed is None else int(seed))
        self._started = True
        return self._observation(obs), self._info()

    def step(self, actions):
        """One decision in every world; returns (observation, reward, terminated, truncated,
        info)."""
        self._check_open()
        if not self._started:
            raise RuntimeError("step() before reset(): call reset() first")
        obs, reward, terminated, truncated = self._core.step(actions)
        info = self._info()
        done = terminated | truncated
        if done.any():
            reports = np.empty(self.num_envs, dtype=object)
            for i in np.flatnonzero(done):
                reports[i] = self._core.last_report(int(i))
            info["final_report"] = reports
            info["_final_report"] = done.copy()
            info["episode"] = {"r": info["episode_return"].copy(),
                               "l": info["episode_length"].copy()}
            info["_episode"] = done.copy()
        return self._observation(obs), reward, terminated, truncated, info

    def report(self, env=0):
        """The report of env's episode so far (the dict ``overtake drive --json`` writes)."""
        return self._core.report(int(env))

    def telemetry(self, env=0):
        """What env's planner is told now (the telemetry dict of ``overtake.World``)."""
        return self._core.telemetry(int(env))

    def close(self):
        self._closed = True

    def _check_open(self):
        if self._closed:
            raise RuntimeError("the environment is closed")

    def __repr__(self):
        return (f"overtake.VecEnv(num_envs={self.num_envs}, actions={self.actions!r}, "
                f"observation_size={self.observation_size})")


class Driver:
    """A policy learned on VecEnv as a planner: telemetry dict in, (path_x, path_y) out, so it
    drives, benches and is judged like any other planner (``overtake drive --policy-py
    FILE:NAME``, ``bench``, ``risk``, ``overtake.drive``).

    Driver(policy, actions="meta", map=None, config=None, params=None)

    ``policy(observation)`` is called every ``decision_steps`` world steps (as in the
    environment) with the observation VecEnv gives, and returns an action of the kind
    ``actions`` (a meta-action 0..4, or [speed, lane] for "continuous"); the reference
    planner's trajectory layer carries the decisions out, planning on with the last targets at
    every call between two decisions. map, config and params: those the policy was trained
    with. For ``--policy-py FILE:NAME``, NAME is a class or function making the Driver.
    """

    def __init__(self, policy, actions="meta", map=None, config=None, params=None):
        if not callable(policy):
            raise TypeError("policy must be a callable: observation in, action out")
        self.policy = policy
        self._core = _DriverCore(str(actions), _fspath(map), _fspath(config), _fspath(params))

    def __call__(self, telemetry):
        return self._core(telemetry, self.policy)

    @property
    def targets(self):
        """The lane and speed the decisions so far drive toward."""
        return self._core.targets


_EnvBase = _gym.Env if _gym is not None else object


class HighwayEnv(_EnvBase):
    """One world with Gymnasium's ``Env`` interface: ``reset`` → (obs, info), ``step(a)`` →
    (obs, reward, terminated, truncated, info), no autoreset (call reset after an episode
    ends). Takes VecEnv's keywords (num_envs is 1)."""

    metadata = {"render_modes": []}

    def __init__(self, seed=0, **kwargs):
        self._vec = VecEnv(1, seed=seed, **kwargs)
        self.observation_space = self._vec.single_observation_space
        self.action_space = self._vec.single_action_space
        self._over = True

    def reset(self, seed=None, options=None):
        obs, info = self._vec.reset(seed=seed, options=options)
        self._over = False
        return self._one(obs), {k: v[0] for k, v in info.items()}

    def step(self, action):
        if self._over:
            raise RuntimeError("the episode is over: call reset()")
        batched = np.asarray(action)[None, ...]
        obs, reward, terminated, truncated, info = self._vec.step(batched)
        self._over = bool(terminated[0] or truncated[0])
        one = {k: v[0] for k, v in info.items() if not isinstance(v, dict)}
        if self._over:
            one["final_report"] = info["final_report"][0]
        return self._one(obs), float(reward[0]), bool(terminated[0]), bool(truncated[0]), one

    @staticmethod
    def _one(obs):
        return obs[0]  # the one world's row (or telemetry dict)

    def report(self):
        return self._vec.report(0)

    def close(self):
        self._vec.close()


if _gym is not None:  # pragma: no cover - depends on the machine
    try:
        _gym.register(id="overtake/Highway-v0", entry_point="overtake.learning:HighwayEnv")
    except Exception:  # already registered (a reload)
        pass
