"""overtake.compare and overtake.bench_summary: a bench's evaluation from Python, the same as
`overtake compare` and summary.json give."""
import json
import shutil
import subprocess

import pytest

import overtake


@pytest.fixture(scope="module")
def benches(binary, tmp_path_factory):
    """Two identical benches, one of a slower reference planner (walkthrough and reference,
    seeds 1-8, a minute of faithful traffic) and one of only three seeds."""
    root = tmp_path_factory.mktemp("benches")
    config = root / "slow.json"
    defaults = json.loads(subprocess.run([binary, "config"], check=True, capture_output=True,
                                         text=True).stdout)
    defaults["planner"]["reference"]["behaviour"]["cruise_speed_mps"] = 18.0
    config.write_text(json.dumps(defaults))
    out = {}
    for name, seeds, extra in (("a", "1-8", []), ("b", "1-8", []),
                               ("slow", "1-8", ["--config", str(config)]), ("few", "1-3", [])):
        out[name] = root / name
        subprocess.run([binary, "bench", "--policies", "walkthrough,reference", "--seeds", seeds,
                        "--minutes", "1", "--traffic", "faithful", "--jobs", "2", "--quiet",
                        "--out", str(out[name]), *extra], check=True, timeout=600)
    return out


def test_an_identical_bench_is_no_difference(benches):
    r = overtake.compare(benches["a"], benches["b"])
    assert r["worse"] == []
    assert r["withheld"] == []
    assert [(c["candidate_policy"], c["traffic"], c["seeds"]) for c in r["comparisons"]] == [
        ("walkthrough", "faithful", 8), ("reference", "faithful", 8)]
    for c in r["comparisons"]:
        for name, f in c["figures"].items():
            assert f["verdict"] == "no difference", name
            assert f["difference"] == 0.0 and f["ci"][0] <= 0.0 <= f["ci"][1], name
            assert f["probability_of_improvement"] == 0.5, name
    assert r["comparisons"][0]["figures"]["mean_speed_mph"]["ci"] == [0.0, 0.0]
    assert r["verdicts"]["correction"] == "Holm" and r["verdicts"]["min_seeds"] == 8


def test_a_slower_planner_is_worse_in_speed(benches):
    r = overtake.compare(benches["a"], benches["slow"], figures=["mean_speed_mph"])
    ref = next(c for c in r["comparisons"] if c["candidate_policy"] == "reference")
    speed = ref["figures"]["mean_speed_mph"]
    assert speed["difference"] < -1.0
    assert speed["ci"][1] < 0 and speed["verdict"] == "worse"
    assert speed["p_adjusted"] < 0.05 and speed["p_adjusted"] >= speed["p_value"]
    lo, hi = speed["probability_of_improvement_ci"]
    assert lo <= speed["probability_of_improvement"] <= hi and hi < 0.5
    assert "reference / faithful: mean_speed_mph" in r["worse"]
    assert any("parameters differ" in n for n in r["notes"])
    # The walkthrough policy has no such parameter: unchanged.
    walk = next(c for c in r["comparisons"] if c["candidate_policy"] == "walkthrough")
    assert walk["figures"]["mean_speed_mph"]["verdict"] == "no difference"


def test_pairs_by_hand_and_what_is_refused(benches):
    r = overtake.compare(benches["a"], benches["b"], pairs={"walkthrough": "reference"})
    assert len(r["comparisons"]) == 1
    c = r["comparisons"][0]
    assert (c["base_policy"], c["candidate_policy"], c["seeds"]) == ("walkthrough", "reference", 8)
    rows = {row["policy"]: row for row in overtake.bench_summary(benches["a"])["rows"]}
    speed = c["figures"]["mean_speed_mph"]
    assert speed["difference"] == pytest.approx(
        rows["reference"]["mean_speed_mph"] - rows["walkthrough"]["mean_speed_mph"], abs=1e-9)
    assert speed["ci"][0] <= speed["difference"] <= speed["ci"][1]
    with pytest.raises(ValueError, match="has no runs of policy 'nope'"):
        overtake.compare(benches["a"], benches["b"], pairs=["reference=nope"])
    with pytest.raises(ValueError, match="unknown figure 'speed'"):
        overtake.compare(benches["a"], benches["b"], figures=["speed"])
    with pytest.raises(RuntimeError, match="no such folder"):
        overtake.compare(benches["a"], benches["a"] / "missing")


def test_too_few_seeds_give_no_verdict(benches):
    r = overtake.compare(benches["a"], benches["few"])
    assert r["worse"] == []
    assert r["withheld"] == ["walkthrough / faithful: too few seeds: 3, need at least 8",
                             "reference / faithful: too few seeds: 3, need at least 8"]
    speed = r["comparisons"][0]["figures"]["mean_speed_mph"]
    assert speed["verdict"] == "too few seeds" and speed["ci"] is None


def test_the_summary_is_the_benchs_own(benches):
    s = overtake.bench_summary(benches["a"])
    written = json.loads((benches["a"] / "summary.json").read_text())
    assert s["rows"] == written["rows"] and s["pairs"] == written["pairs"]
    row = s["rows"][0]
    lo, hi = row["mean_speed_mph_ci"]
    assert lo <= row["mean_speed_mph"] <= hi
    assert row["collisions"]["at_fault"] is not None
    assert s["verdicts"] == written["verdicts"]


def test_a_bench_json_nested_too_deep_is_an_error_not_a_crash(benches, tmp_path):
    broken = tmp_path / "deep"
    shutil.copytree(benches["a"], broken)
    (broken / "bench.json").write_text('{"minutes": ' + "[" * 100000 + "]" * 100000 + "}")
    with pytest.raises(Exception) as e:
        overtake.compare(str(benches["a"]), str(broken))
    assert "bench.json" in str(e.value) and "nested deeper than 64 levels" in str(e.value)
