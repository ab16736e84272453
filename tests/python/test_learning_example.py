"""examples/learning: PPO trained on VecEnv learns measurably in a short run on fixed seeds,
the same seed trains the same weights, and the policy it saves drives as a planner."""
import json
import subprocess
import sys

import pytest

from conftest import SOURCE

EXAMPLE = SOURCE / "examples" / "learning"


def train(out, *extra):
    p = subprocess.run([sys.executable, str(EXAMPLE / "train.py"), "--out", str(out), "--seed", "7",
                        "--envs", "32", "--rollout", "32", "--minutes", "1", "--heldout-runs", "16",
                        "--heldout-minutes", "2", *extra], capture_output=True, text=True,
                       timeout=900)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads((out / "heldout.json").read_text()), p.stdout


def test_a_short_training_run_learns_measurably_and_repeats_byte_for_byte(tmp_path):
    # All five meta-actions: an untrained policy (one update of nearly nothing) slows down at
    # random and is hit; after 40 updates it has learned not to. Both are judged as they were
    # trained (actions drawn from the policy, seeded) on the same held-out seeds.
    five = ("--actions", "keep,left,right,faster,slower")
    before, _ = train(tmp_path / "before", *five, "--decisions", "1024", "--learning-rate", "1e-9")
    after, out = train(tmp_path / "after", *five, "--decisions", "40960")
    assert "gain over keeping the lane" in out
    assert after["keep_lane"] == before["keep_lane"]
    assert after["sampled"]["mean_speed_mph"] >= before["sampled"]["mean_speed_mph"] + 4.0, (before, after)
    curve = (tmp_path / "after" / "curve.csv").read_text().splitlines()
    assert curve[0].startswith("update,decisions,seconds") and len(curve) == 41
    assert (tmp_path / "after" / "curve.svg").read_text().startswith("<svg")
    again, _ = train(tmp_path / "again", "--decisions", "4096")
    once, _ = train(tmp_path / "once", "--decisions", "4096")
    assert (tmp_path / "again" / "policy.json").read_bytes() == (tmp_path / "once" / "policy.json").read_bytes()
    assert again == once


def test_the_saved_policy_drives_from_the_command_line(run_binary, tmp_path):
    train(tmp_path / "p", "--decisions", "2048")
    code, report, err = run_binary("drive", "--policy-py", f"{EXAMPLE / 'planner.py'}:Learned",
                                   "--minutes", "0.5", "--seed", "3",
                                   env={"OVERTAKE_LEARNED_POLICY": str(tmp_path / "p" / "policy.json"),
                                        # The binary finds its build's overtake module itself.
                                        "PYTHONPATH": ""})
    assert code == 0, err
    assert report["end"] == "completed" and report["config"]["policy"] == "planner"
    code, report, err = run_binary("drive", "--policy-py", f"{EXAMPLE / 'planner.py'}:KeepLane",
                                   "--minutes", "0.5", "--seed", "3")
    assert code == 0, err
    assert report["lane_changes"] == 0


def test_bad_settings_and_files_are_refused_by_name(tmp_path, run_binary):
    p = subprocess.run([sys.executable, str(EXAMPLE / "train.py"), "--out", str(tmp_path),
                        "--envs", "0"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "envs must be at least 1" in p.stderr
    p = subprocess.run([sys.executable, str(EXAMPLE / "train.py"), "--out", str(tmp_path),
                        "--actions", "keep,jump"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "actions: 'keep,jump'" in p.stderr
    bogus = tmp_path / "bogus.json"
    bogus.write_text('{"format": "something else"}')
    code, report, err = run_binary("drive", "--policy-py", f"{EXAMPLE / 'planner.py'}:Learned",
                                   "--minutes", "0.1", env={"OVERTAKE_LEARNED_POLICY": str(bogus)})
    assert code != 0 and "not a policy file train.py wrote" in err
