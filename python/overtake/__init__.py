"""overtake from Python: the headless highway simulator, stepped or driven by Python planners.

- ``World``: the world stepped one planner reply at a time (``reset``, ``step``, ``report``),
  exactly as ``overtake drive`` steps it.
- ``Env``: the same world behind a Gymnasium-style interface (``reset``, ``step``).
- ``VecEnv``: the learning environment, many worlds a call, numpy arrays in and out, decisions
  carried out by the reference planner (``overtake.learning``; ``HighwayEnv`` one world).
- ``drive``: a whole drive in C++ with a Python callable (or a built-in policy) as the planner;
  returns the report ``overtake drive --json`` writes.
- ``builtin_policy``: a built-in policy as a Python callable (telemetry dict in, path out).
- ``compare``: two ``overtake bench`` output folders compared run for run (``overtake
  compare``); ``bench_summary``: a bench folder's figures with their intervals.
- ``risk``: the rate of a rare event per 100 miles for a built-in policy (``overtake risk``).

The telemetry is a dict with the original simulator's fields and units: x, y, s, d (m), yaw
(degrees), speed (mph), previous_path_x/_y, end_path_s/_d, sensor_fusion (rows [id, x, y,
vx, vy, s, d], vx and vy in m/s), plus numpy arrays "previous_path_array" (N, 2) and
"sensor_fusion_array" (N, 7). A planner answers (path_x, path_y): lists or numpy arrays.
"""

import os

from ._overtake import BuiltinPolicy, policies
from ._overtake import World as _World
from ._overtake import bench_summary as _bench_summary
from ._overtake import compare as _compare
from ._overtake import drive as _drive
from ._overtake import risk as _risk
from .learning import Driver, HighwayEnv, VecEnv

__all__ = ["World", "Env", "VecEnv", "HighwayEnv", "Driver", "drive", "builtin_policy", "policies", "BuiltinPolicy", "compare",
           "bench_summary", "risk", "STEP_S"]

STEP_S = 0.02
"""The simulator's step time, seconds."""


def _path(p):
    return None if p is None else os.fspath(p)


class World(_World):
    """The world, stepped from Python one planner reply at a time.

    World(map=None, seed=1, traffic="faithful", config=None, steps_per_call=None,
    minutes=30, name="python")

    - map: a map file in the original's format (None: the built-in track); config: a config
      file (None: the defaults); traffic: "faithful" or "calm".
    - steps_per_call: world steps per reply (None: drawn per reply from the seed, as the
      drive does); minutes: the run's duration; name: the policy's name in the report.

    ``reset(seed=None)`` starts a run and returns the telemetry dict; ``step(path_x,
    path_y)`` applies a path as the simulator applies a reply, advances the world, and
    returns ``(telemetry, info)``: info has time_s, steps, steps_this_call, distance_m,
    incident_counts (by type), incidents (so far, as in the report), new_incidents (this
    call's), done, end ("running", "completed", "planner_failed") and ended_early (a reason
    or None). A malformed path (NaN, unequal lengths) ends the run as planner_failed, as in a
    drive. ``report()`` is the run's report, the dict ``overtake drive --json`` writes.

    A World is for one thread at a time: a call made while another call of the same World
    has not returned (from another thread) raises RuntimeError. Several Worlds may be used
    from several threads.
    """

    def __init__(self, map=None, seed=1, traffic="faithful", config=None,
                 steps_per_call=None, minutes=30.0, name="python"):
        super().__init__(map=_path(map), seed=seed, traffic=traffic, config=_path(config),
                         steps_per_call=steps_per_call, minutes=float(minutes), name=name)


def drive(policy, map=None, seed=1, traffic="faithful", minutes=30.0, config=None,
          steps_per_call=None, name=None):
    """Runs a whole drive in C++ and returns its report (the dict ``overtake drive --json``
    writes).

    policy: a built-in policy's name ("reference", "walkthrough", ...) or a callable taking
    the telemetry dict and returning (path_x, path_y); a class is instantiated once per run.
    name: the planner's name in the report (default: the callable's __name__). An exception
    in the callable ends the run as planner_failed, with the Python error in ``ended_early``;
    but KeyboardInterrupt and SystemExit stop the run and are raised again from drive() (the
    same exception). Ctrl-C stops a drive of a built-in policy too, within a fraction of a
    second, with KeyboardInterrupt.
    """
    return _drive(policy, map=_path(map), seed=seed, traffic=traffic, minutes=float(minutes),
                  config=_path(config), steps_per_call=steps_per_call, name=name)


def compare(before, after, pairs=None, figures=None):
    """Compares two ``overtake bench --out`` folders as ``overtake compare`` does and returns
    the result as a dict: "comparisons" (per policy and traffic profile: "seeds" paired and
    "figures", each with "base", "candidate", "difference", "ci" [lo, hi] (None below 8
    seeds), "p_value" and "p_adjusted" (Holm over every figure compared),
    "probability_of_improvement" (P(after better than before) over all pairs of runs) with
    "probability_of_improvement_ci", and "verdict": "better", "worse", "no difference" or
    "too few seeds"), "verdicts" (how they were reached), "worse" (the figures that got
    significantly worse), "withheld" (comparisons with too few seeds to judge) and "notes".

    pairs: {old: new} or ["OLD=NEW", ...] to compare policies of other names (default: every
    policy both ran, by name). figures: names to compare, e.g. ["mean_speed_mph",
    "at_fault_collisions_per_100mi"] (default: all). A bad pair or figure raises ValueError;
    a folder without a bench, or runs that are not pairs (another map), RuntimeError.
    """
    if isinstance(pairs, dict):
        pairs = [f"{old}={new}" for old, new in pairs.items()]
    if figures is not None and not isinstance(figures, str):
        figures = ",".join(figures)
    return _compare(os.fspath(before), os.fspath(after), list(pairs or []), figures)


def risk(policy="reference", event="at-fault", map=None, traffic="faithful", minutes=10.0,
         first_seed=1, rel_error=0.25, budget_hours=20.0, max_runs=100000, config=None,
         params=None, jobs=0, out="risk-out", resume=False, scenarios=5):
    """Estimates how often `event` ("at-fault", "contact", "near-miss" or a rubric incident
    type) happens to a built-in policy, per 100 miles, as ``overtake risk`` does, and returns
    its risk.json as a dict: "rate_per_100mi", "ci95_per_100mi" [low, high],
    "upper_bound_only" (no event: the interval is [0, bound]), "simulated_hours",
    "plain_mc_hours", "gain", "runs", "events" and the levels' figures. The runs are kept in
    `out` (``resume=True`` goes on with them); the first `scenarios` events of the base runs
    are cut into scenarios in out/events ("scenarios" says how). jobs=0: every core. Bad
    arguments raise ValueError; Ctrl-C stops it (the finished runs kept) and raises
    KeyboardInterrupt.
    """
    return _risk(policy, event, _path(map), traffic, float(minutes), int(first_seed),
                 float(rel_error), float(budget_hours), int(max_runs), _path(config),
                 _path(params), int(jobs), os.fspath(out), bool(resume), int(scenarios))


def bench_summary(folder):
    """A bench output folder's evaluation, as summary.json holds it: "rows" (per policy and
    traffic profile, figures with 95% intervals over the seeds, collisions as contacts by kind
    and at fault, near misses, seeds to halve each interval), "pairs" (every two policies on
    the same seeds, verdicts corrected over the whole table) and "verdicts" (how), computed
    anew from its runs.jsonl."""
    return _bench_summary(os.fspath(folder))


def builtin_policy(name, map=None, config=None):
    """A built-in policy as a callable: telemetry dict in, (path_x, path_y) out. One
    instance keeps its state between calls, as in a drive; make one per run. ``status`` is
    how its last path was found ("normal", "least_bad", "fallback")."""
    return BuiltinPolicy(name, map=_path(map), config=_path(config))


class Env:
    """A Gymnasium-style environment over World (it does not import gymnasium).

    - observation: the telemetry dict (see the module's doc);
    - action: (path_x, path_y), the path in map coordinates (m);
    - reward: the distance driven this step (m, along the road) minus ``collision_penalty``
      per collision and ``incident_penalty`` per other incident (speeding, acceleration,
      jerk, outside the lane) counted this step;
    - terminated: a collision this step (``terminate_on_collision``), or the planner failed
      (a malformed path);
    - truncated: the run reached its duration (``minutes``);
    - info: World.step's info.
    """

    metadata = {"render_modes": []}

    def __init__(self, map=None, seed=1, traffic="faithful", config=None, steps_per_call=None,
                 minutes=30.0, collision_penalty=100.0, incident_penalty=10.0,
                 terminate_on_collision=True):
        self.world = World(map=map, seed=seed, traffic=traffic, config=config,
                           steps_per_call=steps_per_call, minutes=minutes, name="env")
        self.seed = seed
        self.collision_penalty = float(collision_penalty)
        self.incident_penalty = float(incident_penalty)
        self.terminate_on_collision = terminate_on_collision
        self._distance_m = 0.0
        self._over = True

    def reset(self, seed=None, options=None):
        """Starts a run (with a new seed when given); returns (observation, info)."""
        del options  # none yet
        if seed is not None:
            self.seed = seed
        obs = self.world.reset(seed=self.seed)
        self._distance_m = 0.0
        self._over = False
        return obs, {"time_s": self.world.time_s, "steps": self.world.steps, "seed": self.seed}

    def step(self, action):
        """Applies the path ``action`` = (path_x, path_y); returns (observation, reward,
        terminated, truncated, info)."""
        if self._over:
            raise RuntimeError("the episode is over: call reset()")
        path_x, path_y = action
        obs, info = self.world.step(path_x, path_y)
        progressed = info["distance_m"] - self._distance_m
        self._distance_m = info["distance_m"]
        collisions = sum(1 for i in info["new_incidents"] if i["type"] == "collision")
        others = len(info["new_incidents"]) - collisions
        reward = progressed - self.collision_penalty * collisions - self.incident_penalty * others
        failed = info["end"] == "planner_failed"
        terminated = failed or (self.terminate_on_collision and collisions > 0)
        truncated = info["done"] and not terminated
        self._over = terminated or truncated
        return obs, reward, terminated, truncated, info

    def report(self):
        """The run's report so far (as World.report)."""
        return self.world.report()

    def close(self):
        pass
