"""overtake.Env: the Gymnasium-style interface."""

import math

import pytest

import overtake
from conftest import path_onto_a_car_ahead


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
    path = None
    while path is None:  # traffic is placed around the car after the start
        obs, _, _, _, info = env.step(([obs["x"]], [obs["y"]]))
        _, path = path_onto_a_car_ahead(obs)
    xs, ys = path
    terminated = truncated = False
    for _ in range(len(xs)):
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


def test_a_point_beyond_the_world_terminates_with_a_finite_reward():
    env = overtake.Env(seed=1)
    obs, _ = env.reset()
    obs, reward, terminated, truncated, info = env.step(([obs["x"], 1e300], [obs["y"], 0.0]))
    assert terminated and not truncated and info["end"] == "planner_failed"
    assert "beyond 1,000 km" in info["ended_early"]
    assert math.isfinite(reward)
    assert all(math.isfinite(obs[k]) for k in ("x", "y", "s", "d", "speed"))


def test_reset_with_a_seed_reproduces_the_episode():
    env = overtake.Env(seed=1, minutes=0.2)
    firsts = []
    for seed in (9, 9, 10):
        policy = overtake.builtin_policy("walkthrough")  # a fresh policy state per episode
        obs, _ = env.reset(seed=seed)
        for _ in range(100):
            obs, *_ = env.step(policy(obs))
        firsts.append(obs["sensor_fusion"])
    assert firsts[0] == firsts[1]
    assert firsts[2] != firsts[0]
