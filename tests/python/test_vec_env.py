"""overtake.VecEnv: the learning environment's arrays, spaces, determinism, autoreset, bad
actions and the GIL."""

import math
import sys
import threading

import numpy as np
import pytest

import overtake
from conftest import interrupt_script
from overtake import learning


def test_shapes_spaces_and_the_observation_layout():
    env = overtake.VecEnv(4, seed=1, minutes=0.2)
    assert env.num_envs == 4 and env.lanes == 3 and env.observation_size == 31
    assert len(learning.observation_names(3)) == 31
    assert env.single_observation_space.shape == (31,)
    assert env.observation_space.shape == (4, 31)
    assert env.single_action_space.n == 5
    obs, info = env.reset()
    assert obs.shape == (4, 31) and obs.dtype == np.float32
    assert np.all(np.abs(obs) <= 2.0)
    assert info["episode_seed"].tolist() == [1, 2, 3, 4]
    obs, reward, terminated, truncated, info = env.step(np.zeros(4, dtype=np.int64))
    assert obs.shape == (4, 31) and reward.shape == (4,) and reward.dtype == np.float32
    assert terminated.dtype == np.bool_ and truncated.dtype == np.bool_
    assert set(info) >= {"time_s", "distance_m", "speed_mps", "lane", "episode_return"}
    assert info["time_s"] == pytest.approx([0.2] * 4)
    for kind, shape in (("continuous", (2,)), ("path", (500, 2))):
        e = overtake.VecEnv(2, actions=kind, minutes=0.1)
        assert e.single_action_space.shape == shape
        assert e.action_space.shape == (2,) + shape


def run(env, calls, seed):
    rng = np.random.default_rng(seed)
    out = [env.reset()[0]]
    for _ in range(calls):
        a = rng.integers(0, 5, size=env.num_envs)
        obs, reward, terminated, truncated, _ = env.step(a)
        out += [obs, reward, terminated, truncated]
    return out


def test_the_same_seeds_give_the_same_arrays_byte_for_byte():
    a = run(overtake.VecEnv(3, seed=7, minutes=0.3, threads=1), 100, seed=0)
    b = run(overtake.VecEnv(3, seed=7, minutes=0.3, threads=2), 100, seed=0)
    assert all(x.tobytes() == y.tobytes() for x, y in zip(a, b))
    c = run(overtake.VecEnv(3, seed=8, minutes=0.3), 100, seed=0)
    assert any(x.tobytes() != y.tobytes() for x, y in zip(a, c))  # other seeds, other traffic


def test_n_worlds_in_one_vec_env_are_n_one_world_envs():
    many = overtake.VecEnv(3, seed=30, minutes=0.2)
    alone = [overtake.VecEnv(1, seed=30 + i, minutes=0.2) for i in range(3)]
    obs = many.reset()[0]
    for i, e in enumerate(alone):
        assert e.reset()[0][0].tobytes() == obs[i].tobytes()
    rng = np.random.default_rng(1)
    for _ in range(70):  # the episodes end at 60 decisions: autoreset included
        a = rng.integers(0, 5, size=3)
        obs, reward, term, trunc, _ = many.step(a)
        for i, e in enumerate(alone):
            o, r, te, tr, _ = e.step(a[i:i + 1])
            assert o[0].tobytes() == obs[i].tobytes()
            assert r[0] == reward[i] and te[0] == term[i] and tr[0] == trunc[i]


def test_next_step_autoreset_and_the_episode_report():
    env = overtake.VecEnv(2, seed=4, minutes=0.1)  # 30 decisions
    env.reset()
    for call in range(30):
        obs, reward, terminated, truncated, info = env.step([0, 0])
    assert truncated.all() and not terminated.any()
    assert info["_final_report"].all()
    report = info["final_report"][0]
    assert report["config"]["policy"] == "agent" and report["config"]["seed"] == 4
    assert report["end"] == "completed"
    assert report["distance_miles"] * 1609.344 == pytest.approx(info["distance_m"][0], abs=0.01)
    assert info["episode"]["l"].tolist() == [30, 30]
    obs, reward, terminated, truncated, info = env.step([1, 2])
    assert reward.tolist() == [0.0, 0.0] and not truncated.any() and not terminated.any()
    assert info["was_reset"].all() and info["episode"].tolist() == [2, 2]
    fresh = overtake.VecEnv(1, seed=4 + 2**32, minutes=0.1)
    assert fresh.reset()[0][0].tobytes() == obs[0].tobytes()


def test_bad_actions_get_a_clear_error_and_the_interpreter_lives():
    env = overtake.VecEnv(2, minutes=0.1)
    with pytest.raises(RuntimeError, match="reset"):
        env.step([0, 0])
    env.reset()
    with pytest.raises(ValueError, match="env 1 is 7"):
        env.step([0, 7])
    with pytest.raises(ValueError, match="dimension 0 is 3, not 2"):
        env.step([0, 0, 0])
    with pytest.raises(ValueError, match="whole number"):
        env.step([0.5, 1.0])
    with pytest.raises(ValueError, match="whole number"):
        env.step([math.nan, 1.0])
    with pytest.raises(TypeError):
        env.step(["left", "right"])
    cont = overtake.VecEnv(1, actions="continuous", minutes=0.1)
    cont.reset()
    with pytest.raises(ValueError, match="target speed"):
        cont.step([[1.5, 0.0]])
    with pytest.raises(ValueError, match="target lane"):
        cont.step([[0.5, math.nan]])
    with pytest.raises(ValueError, match="2 dimensions"):
        cont.step([0.5, 0.0])
    path = overtake.VecEnv(1, actions="path", minutes=0.1)
    path.reset()
    with pytest.raises(ValueError, match="not finite"):
        path.step(np.array([[[1.0, math.inf]]]))
    with pytest.raises(ValueError, match="at most max_path_points"):
        path.step(np.zeros((1, 501, 2)))
    with pytest.raises(ValueError, match="not a kind of action"):
        overtake.VecEnv(1, actions="steer")
    with pytest.raises(ValueError, match="num_envs"):
        overtake.VecEnv(0)
    with pytest.raises(ValueError, match="traffic profile"):
        overtake.VecEnv(1, traffic="heavy")
    # after every refusal the environment still steps
    obs, *_ = env.step([0, 0])
    assert obs.shape == (2, 31)


def test_the_worlds_step_with_the_gil_released():
    env = overtake.VecEnv(128, minutes=5.0)
    env.reset()
    ticks = [0]
    running = threading.Event()
    stop = threading.Event()

    def count():
        running.set()
        while not stop.is_set():
            ticks[0] += 1

    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)
    counter = threading.Thread(target=count)
    counter.start()
    running.wait()
    try:
        during = []
        for _ in range(5):
            before = ticks[0]
            env.step(np.zeros(128, dtype=np.int64))  # a few milliseconds of C++
            during.append(ticks[0] - before)
    finally:
        stop.set()
        counter.join()
        sys.setswitchinterval(old)
    # Python ran in the other thread while the worlds stepped.
    assert max(during) > 100, during


def test_ctrl_c_stops_a_loop_of_steps_of_many_worlds_at_once():
    # 512 worlds a call: a step lasts tens of milliseconds; Ctrl-C lands when the step in
    # progress returns.
    out, err, code, waited_s = interrupt_script("""
        import numpy as np
        import overtake
        env = overtake.VecEnv(512, seed=5, minutes=30, threads=2)
        env.reset()
        actions = np.zeros(512, dtype=np.int64)
        print("stepping", flush=True)
        for _ in range(100000):
            env.step(actions)
        print("finished", flush=True)
    """, "stepping", timeout_s=120)
    assert "KeyboardInterrupt" in err and "finished" not in out, err[-2000:]
    assert code != 0
    assert waited_s < 1.0, f"the steps went on for {waited_s:.2f} s after Ctrl-C"


def test_telemetry_observations_and_the_one_world_env():
    env = overtake.VecEnv(2, minutes=0.1, observation="telemetry")
    obs, _ = env.reset()
    assert isinstance(obs, list) and len(obs) == 2 and "sensor_fusion" in obs[0]
    one = overtake.HighwayEnv(seed=3, minutes=0.1)
    o, info = one.reset()
    assert o.shape == (31,) and info["episode_seed"] == 3
    done = False
    steps = 0
    while not done:
        o, r, terminated, truncated, info = one.step(0)
        done = terminated or truncated
        steps += 1
    assert steps == 30 and truncated and info["final_report"]["config"]["seed"] == 3
    with pytest.raises(RuntimeError, match="over"):
        one.step(0)


def test_params_files_change_the_decisions_and_reward(tmp_path):
    params = tmp_path / "learn.json"
    params.write_text('{"decision_steps": 5, "reward": {"progress": 2.0}}')
    env = overtake.VecEnv(1, seed=2, minutes=0.1, params=params)
    assert env.params["decision_steps"] == 5 and env.params["reward"]["progress"] == 2.0
    env.reset()
    _, _, _, _, info = env.step([0])
    assert info["time_s"][0] == pytest.approx(0.1)
    params.write_text('{"reward": {"progres": 2.0}}')
    with pytest.raises(ValueError, match="reward.progres: is not a key"):
        overtake.VecEnv(1, params=params)


def test_a_learned_policy_drives_as_a_planner_as_it_drove_in_the_environment():
    # A policy that changes lanes and speeds now and then, by its observation's clock.
    calls = []

    def policy(obs):
        calls.append(obs)
        k = len(calls) % 60
        return 1 if k == 20 else 2 if k == 40 else 3 if k == 50 else 4 if k == 10 else 0

    env = overtake.VecEnv(1, seed=5, minutes=0.5)
    obs, _ = env.reset()
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step([policy(obs[0])])
        done = terminated[0] or truncated[0]
    in_env = info["final_report"][0]
    in_env_observations = calls[:]
    calls.clear()
    driver = overtake.Driver(policy)
    # One decision a call, ten steps a call: the environment's cadence.
    report = overtake.drive(driver, seed=5, minutes=0.5, steps_per_call=10, name="agent")
    assert len(calls) == len(in_env_observations) == 150
    # The same observations, so the same decisions, and the same drive (the telemetry reaches
    # a Python planner through its dict, in the original's units: equal to float precision).
    for a, b in zip(calls, in_env_observations):
        np.testing.assert_allclose(a, b, atol=1e-5)
    assert report["distance_miles"] == pytest.approx(in_env["distance_miles"], rel=1e-6)
    assert report["lane_changes"] == in_env["lane_changes"]
    assert report["collisions"] == in_env["collisions"]
    # At the drive's own cadence (1-3 steps a call) it decides every 10 steps, planning on between.
    calls.clear()
    report = overtake.drive(overtake.Driver(policy), seed=5, minutes=0.5)
    assert 140 <= len(calls) <= 150 and report["end"] == "completed"


def test_a_driver_refuses_bad_actions_and_path_policies():
    with pytest.raises(ValueError, match="paths itself"):
        overtake.Driver(lambda o: 0, actions="path")
    with pytest.raises(TypeError):
        overtake.Driver(3)
    report = overtake.drive(overtake.Driver(lambda o: 9), seed=1, minutes=0.1)
    assert report["end"] == "planner_failed" and "meta-action" in report["ended_early"]


def test_a_learned_policy_drives_from_the_command_line(run_binary, tmp_path):
    planner = tmp_path / "learned.py"
    planner.write_text(
        "import overtake\n\n"
        "def keep(observation):\n"
        "    return 0\n\n"
        "class Learned(overtake.Driver):\n"
        "    def __init__(self):\n"
        "        super().__init__(keep)\n")
    code, report, err = run_binary("drive", "--policy-py", f"{planner}:Learned", "--minutes", "0.5",
                                   "--seed", "3")
    assert code == 0, err
    assert report["end"] == "completed" and report["mean_speed_mph"] > 20
    assert report["incident_counts"]["collision"] == 0
