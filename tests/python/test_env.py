"""overtake.Env: the Gymnasium-style interface."""
import math

import pytest

import overtake


def test_reset_and_step_follow_gymnasium():
    env = overtake.Env(seed=3, minutes=0.5)
    obs, info = env.reset(seed=3)
    assert obs["speed"] == 0 and info["time_s"] == 0 and info["seed"] == 3
    policy = overtake.builtin_policy("walkthrough")
    total, distance = 0.0, 0.0
    terminated = truncated = False
    while not (terminated or truncated):
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        total += reward
    assert truncated and not terminated
    assert info["time_s"] == pytest.approx(30.0) and info["end"] == "completed"
    # no incidents: the rewards add up to the distance driven
    assert sum(info["incident_counts"].values()) == 0
    assert total == pytest.approx(info["distance_m"]) and total > 200
    with pytest.raises(RuntimeError):
        env.step(policy(obs))


def test_a_collision_terminates_with_a_penalty():
    env = overtake.Env(seed=1, steps_per_call=1, collision_penalty=100.0)
    obs, _ = env.reset()
    car = min(obs["sensor_fusion"], key=lambda c: math.hypot(c[1] - obs["x"], c[2] - obs["y"]))
    xs = [car[1] + car[3] * 0.02 * (i + 1) for i in range(50)]
    ys = [car[2] + car[4] * 0.02 * (i + 1) for i in range(50)]
    for _ in range(5):
        obs, reward, terminated, truncated, info = env.step((xs, ys))
        if terminated:
            break
        xs, ys = xs[1:], ys[1:]
    assert terminated and not truncated
    assert info["incident_counts"]["collision"] >= 1
    assert reward < -50


def test_a_malformed_action_terminates():
    env = overtake.Env(seed=1)
    obs, _ = env.reset()
    obs, reward, terminated, truncated, info = env.step(([obs["x"], obs["x"] + 1], [obs["y"]]))
    assert terminated and not truncated and info["end"] == "planner_failed"
    assert "path_y" in info["ended_early"]


def test_reset_with_a_seed_reproduces_the_episode():
    env = overtake.Env(seed=1, minutes=0.2)
    policy = overtake.builtin_policy("walkthrough")
    firsts = []
    for _ in range(2):
        obs, _ = env.reset(seed=9)
        firsts.append([row[:] for row in obs["sensor_fusion"]])
    assert firsts[0] == firsts[1]
    obs, _ = env.reset(seed=10)
    assert [row for row in obs["sensor_fusion"]] != firsts[0]
    del policy
