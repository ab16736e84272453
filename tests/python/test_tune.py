"""`overtake tune --policy-py`: a Python planner's keyword argument searched."""
import json
import subprocess

from conftest import PLANNERS


def test_tune_searches_a_python_planners_keyword(binary, tmp_path):
    # No --policy: the one planner from outside is the one searched.
    out = tmp_path / "tune"
    p = subprocess.run([binary, "tune", "--policy-py", f"kw={PLANNERS / 'keyword_speed.py'}:Planner",
                        "--param", "speed_mps=8:20@10", "--seeds", "1",
                        "--minutes", "0.5", "--trials", "4", "--jobs", "1", "--constraint", "none",
                        "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    trials = [json.loads(line) for line in (out / "trials.jsonl").read_text().splitlines()]
    assert len(trials) == 4
    assert trials[0]["params"] == {"speed_mps": 10.0}
    best = max(trials, key=lambda t: t["objective"])
    assert best["params"]["speed_mps"] > 10.0 and best["objective"] > trials[0]["objective"]
    assert json.loads((out / "best.json").read_text()) == best["params"]


def test_a_keyword_the_planner_does_not_take_is_refused(binary, tmp_path):
    p = subprocess.run([binary, "tune", "--policy-py", f"kw={PLANNERS / 'keyword_speed.py'}:Planner",
                        "--policy", "kw", "--param", "sped_mps=8:20", "--seeds", "1",
                        "--out", str(tmp_path / "tune")], capture_output=True, text=True,
                       timeout=600)
    assert p.returncode == 2
    assert "sped_mps" in p.stderr and "unexpected keyword" in p.stderr
    assert not (tmp_path / "tune" / "trials.jsonl").exists()


def test_without_policy_the_planner_searched_must_be_the_only_one_from_outside(binary, tmp_path):
    two = ["--policy-py", f"kw={PLANNERS / 'keyword_speed.py'}:Planner",
           "--policy-py", f"other={PLANNERS / 'keyword_speed.py'}:Planner"]
    for planners in (two, []):
        p = subprocess.run([binary, "tune", *planners, "--param", "speed_mps=8:20", "--seeds", "1",
                            "--out", str(tmp_path / "tune")], capture_output=True, text=True,
                           timeout=600)
        assert p.returncode == 2, p.stderr
        assert "--policy: name the planner searched" in p.stderr
        assert not (tmp_path / "tune" / "trials.jsonl").exists()
