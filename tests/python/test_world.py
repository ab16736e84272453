"""overtake.World: the telemetry as the original sends it, steps, incidents, the report."""
import math
import subprocess
import sys

import numpy as np
import pytest

import overtake
from conftest import comparable, path_onto_a_car_ahead

ORIGINAL_KEYS = ["x", "y", "yaw", "speed", "s", "d", "previous_path_x", "previous_path_y",
                 "end_path_s", "end_path_d", "sensor_fusion"]
MPH_PER_MPS = 2.23693629


def straight_path(t, speed_mps, n=50):
    """n points ahead of the car along its yaw, spaced for speed_mps."""
    yaw = math.radians(t["yaw"])
    step = speed_mps * overtake.STEP_S
    xs = [t["x"] + step * (i + 1) * math.cos(yaw) for i in range(n)]
    ys = [t["y"] + step * (i + 1) * math.sin(yaw) for i in range(n)]
    return xs, ys


def test_reset_gives_the_originals_fields_and_units():
    w = overtake.World(seed=1)
    t = w.reset()
    assert list(t)[:len(ORIGINAL_KEYS)] == ORIGINAL_KEYS
    assert t["speed"] == 0  # at rest, in mph
    assert 0 <= t["yaw"] < 360 and t["yaw"] == round(t["yaw"])  # whole degrees at the start
    assert t["previous_path_x"] == [] and t["previous_path_y"] == []
    assert t["end_path_s"] == 0 and t["end_path_d"] == 0
    assert 4 < t["d"] < 8  # the middle lane
    assert t["sensor_fusion"], "traffic is reported"
    for i, row in enumerate(t["sensor_fusion"]):
        assert len(row) == 7 and row[0] == i and isinstance(row[0], int)
    fusion = t["sensor_fusion_array"]
    assert fusion.dtype == np.float64 and fusion.shape == (len(t["sensor_fusion"]), 7)
    np.testing.assert_array_equal(fusion, np.array(t["sensor_fusion"], dtype=float))
    assert t["previous_path_array"].shape == (0, 2)


def test_speed_is_in_mph_and_yaw_in_degrees():
    w = overtake.World(seed=2, steps_per_call=5, traffic="calm")
    t = w.reset()
    start_yaw = t["yaw"]
    xs, ys = straight_path(t, 10.0)
    t, info = w.step(xs, ys)
    assert info["steps_this_call"] == 5
    assert t["speed"] == pytest.approx(10.0 * MPH_PER_MPS, rel=1e-3)
    assert t["yaw"] == pytest.approx(start_yaw, abs=0.01)
    # what is left of the path comes back, rounded as the wire rounds it
    assert len(t["previous_path_x"]) == 45
    assert t["previous_path_x"][0] == pytest.approx(xs[5], abs=1e-3)
    np.testing.assert_array_equal(t["previous_path_array"][:, 1], t["previous_path_y"])


@pytest.mark.parametrize("k", [1, 3, 7])
def test_a_step_advances_k_steps_of_0_02_s(k):
    w = overtake.World(seed=3, steps_per_call=k)
    t = w.reset()
    for call in range(1, 4):
        t, info = w.step(*straight_path(t, 5.0))
        assert info["steps"] == call * k and info["steps_this_call"] == k
        assert info["time_s"] == pytest.approx(call * k * 0.02)
        assert w.time_s == info["time_s"]


def test_steps_per_reply_are_drawn_from_the_seed():
    draws = []
    for _ in range(2):
        w = overtake.World(seed=4)
        t = w.reset()
        ks = []
        for _ in range(30):
            t, info = w.step(*straight_path(t, 5.0))
            ks.append(info["steps_this_call"])
        draws.append(ks)
    assert draws[0] == draws[1]
    assert set(draws[0]) <= {1, 2, 3} and len(set(draws[0])) > 1


def test_a_path_into_a_car_is_a_collision():
    w = overtake.World(seed=1, steps_per_call=1)
    t = w.reset()
    car, path = None, None
    while path is None:  # traffic is placed around the car after the start
        t, info = w.step([t["x"]], [t["y"]])
        car, path = path_onto_a_car_ahead(t)
    xs, ys = path
    collisions = 0
    for _ in range(len(xs)):
        t, info = w.step(xs, ys)
        collisions = info["incident_counts"]["collision"]
        if collisions:
            break
        xs, ys = xs[1:], ys[1:]
    assert collisions >= 1
    hit = [i for i in info["incidents"] if i["type"] == "collision"]
    assert hit and hit[0]["unit"] == "car_id" and hit[0]["value"] == car[0]
    assert w.report()["incident_counts"]["collision"] == collisions


def test_a_nan_path_ends_the_run_as_planner_failed():
    w = overtake.World(seed=1)
    t = w.reset()
    t, info = w.step([t["x"] + 0.4, float("nan")], [t["y"], t["y"]])
    assert info["done"] and info["end"] == "planner_failed"
    assert "not a finite number" in info["ended_early"]
    assert w.report()["end"] == "planner_failed"
    with pytest.raises(RuntimeError):
        w.step([], [])


def test_the_run_completes_at_its_duration():
    w = overtake.World(seed=1, minutes=0.05, steps_per_call=4)  # 3 s: 150 steps
    t = w.reset()
    info = {"done": False}
    calls = 0
    while not info["done"]:
        t, info = w.step(*straight_path(t, 0.5))
        calls += 1
    assert info["steps"] == 150 and calls == 38 and info["end"] == "completed"
    assert w.report()["duration_s"] == pytest.approx(3.0)


def test_stepping_the_walkthrough_gives_the_drives_report(run_binary):
    minutes, seed = 2.0, 5
    w = overtake.World(seed=seed, minutes=minutes)
    policy = overtake.builtin_policy("walkthrough")
    t = w.reset()
    while not w.done:
        t, info = w.step(*policy(t))
    stepped = w.report()
    driven = overtake.drive(policy="walkthrough", seed=seed, minutes=minutes)
    assert stepped["planner_cycles"] == driven["planner_cycles"] > 1000
    assert comparable(stepped) == comparable(driven)
    code, binary_report, _ = run_binary("drive", "--policy", "walkthrough", "--seed", str(seed),
                                        "--minutes", str(minutes))
    assert code == 0
    assert comparable(binary_report) == comparable(driven)
    assert driven["config"]["policy"] == "walkthrough"


def test_bad_arguments_are_value_errors(tmp_path):
    with pytest.raises(ValueError, match="traffic"):
        overtake.World(traffic="heavy")
    with pytest.raises(ValueError):
        overtake.World(map=tmp_path / "missing.csv")
    with pytest.raises(ValueError, match="unknown policy"):
        overtake.builtin_policy("nope")


def test_a_call_from_inside_a_step_is_refused_not_run_under_it():
    w = overtake.World(seed=1, steps_per_call=2)
    t = w.reset()
    refused = []

    class ResetsTheWorld:
        """A path coordinate whose conversion to a number resets the world being stepped."""

        def __float__(self):
            try:
                w.reset()
            except RuntimeError as e:
                refused.append(str(e))
            return t["x"] + 0.8

    t2, info = w.step([t["x"] + 0.4, ResetsTheWorld()], [t["y"], t["y"]])
    assert len(refused) == 1 and "World.reset()" in refused[0]
    assert "another call of this object has not returned" in refused[0]
    assert info["steps"] == 2 and info["end"] == "running"
    assert w.report()["duration_s"] == pytest.approx(0.04)


def test_two_threads_on_one_world_do_not_crash_it():
    # In a process of its own: a crash fails this test, not the whole file.
    code = """if True:
        import math, threading, time
        import overtake

        w = overtake.World(seed=1, minutes=0.5, steps_per_call=1)
        w.reset()
        # Until both have gone round often (however busy the machine), or a minute at most.
        limit = time.monotonic() + 60.0
        refused, counts = [], {"steps": 0, "resets": 0}

        def going():
            enough = counts["steps"] > 100 and counts["resets"] > 100
            return not enough and time.monotonic() < limit

        def stepping():
            while going():
                try:
                    t = w.telemetry()
                    yaw = math.radians(t["yaw"])
                    w.step([t["x"] + 0.2 * (i + 1) * math.cos(yaw) for i in range(50)],
                           [t["y"] + 0.2 * (i + 1) * math.sin(yaw) for i in range(50)])
                    counts["steps"] += 1
                    if w.done:
                        w.reset()
                except RuntimeError as e:
                    refused.append(str(e))

        def resetting():
            while going():
                try:
                    w.reset()
                    counts["resets"] += 1
                except RuntimeError as e:
                    refused.append(str(e))

        threads = [threading.Thread(target=f) for f in (stepping, resetting)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        bad = [r for r in refused if "another call of this object has not returned" not in r]
        assert not bad, bad[:3]
        assert counts["steps"] > 100 and counts["resets"] > 100, counts
        print("ok", counts, len(refused))
    """
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    assert p.stdout.startswith("ok"), p.stdout
