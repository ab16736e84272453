#!/usr/bin/env python3
"""Steps per second of a Python planner driving overtake.World: two simulated minutes with a
trivial planner (a straight path) and with the example planner (examples/python/planner.py).

    PYTHONPATH=build/noweb/python /usr/bin/python3 bench/python_steps.py [--minutes 2]

Prints, per planner, world steps per second and planner calls (replies) per second of wall
time. A world step is 0.02 s of simulated time; a reply is followed by 1-3 steps, drawn from
the seed, as in `overtake drive`.
"""
import argparse
import importlib.util
import math
import pathlib
import time

try:
    import overtake
except ImportError:
    raise SystemExit(f"{__file__}: no overtake module: build it (make build) and set "
                     "PYTHONPATH=build/release/python")

ROOT = pathlib.Path(__file__).resolve().parents[1]


def straight(t):
    yaw = math.radians(t["yaw"])
    n = 50 - len(t["previous_path_x"])
    x0 = t["previous_path_x"][-1] if t["previous_path_x"] else t["x"]
    y0 = t["previous_path_y"][-1] if t["previous_path_y"] else t["y"]
    step = 0.1  # 5 m/s
    return (list(t["previous_path_x"]) + [x0 + step * (i + 1) * math.cos(yaw) for i in range(n)],
            list(t["previous_path_y"]) + [y0 + step * (i + 1) * math.sin(yaw) for i in range(n)])


def example():
    spec = importlib.util.spec_from_file_location("planner", ROOT / "examples/python/planner.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.plan


def measure(name, plan, minutes, seed):
    world = overtake.World(seed=seed, minutes=minutes)
    t = world.reset()
    calls = 0
    start = time.perf_counter()
    while not world.done:
        t, _ = world.step(*plan(t))
        calls += 1
    wall = time.perf_counter() - start
    print(f"{name:>12}: {world.steps / wall:9.0f} steps/s, {calls / wall:8.0f} replies/s "
          f"({world.steps} steps, {calls} replies, {wall:.2f} s wall)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    measure("no-op", lambda t: (t["previous_path_x"], t["previous_path_y"]), args.minutes,
            args.seed)
    measure("straight", straight, args.minutes, args.seed)
    measure("example", example(), args.minutes, args.seed)
    measure("walkthrough", overtake.builtin_policy("walkthrough"), args.minutes, args.seed)


if __name__ == "__main__":
    main()
