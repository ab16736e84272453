"""overtake.risk: a rare event's rate from Python, the same estimate `overtake risk` writes."""
import json
import subprocess

import pytest

import overtake


def test_risk_from_python_is_the_command_lines(binary, tmp_path):
    r = overtake.risk(event="outside_lane", minutes=1, max_runs=3, rel_error=0,
                      out=tmp_path / "py", jobs=2)
    for key in ("event", "rate_per_100mi", "ci95_per_100mi", "simulated_hours",
                "plain_mc_hours", "gain", "runs"):
        assert key in r
    assert r["runs"] == 3
    assert r["event"] == "outside_lane"
    lo, hi = r["ci95_per_100mi"]
    assert 0 <= lo <= r["rate_per_100mi"] <= hi
    subprocess.run([binary, "risk", "--event", "outside_lane", "--minutes", "1", "--max-runs",
                    "3", "--rel-error", "0", "--jobs", "1", "--quiet", "--out",
                    str(tmp_path / "cli")], check=True, timeout=600)
    cli = json.loads((tmp_path / "cli" / "risk.json").read_text())
    assert cli["rate_per_100mi"] == r["rate_per_100mi"]
    assert cli["ci95_per_100mi"] == r["ci95_per_100mi"]
    assert cli["miles"] == r["miles"]


def test_bad_arguments_are_value_errors(tmp_path):
    with pytest.raises(ValueError, match="--event: 'crash'"):
        overtake.risk(event="crash", out=tmp_path / "a")
    with pytest.raises(ValueError, match="--minutes"):
        overtake.risk(minutes=0.1, out=tmp_path / "b")
    with pytest.raises(ValueError, match="--policy: 'nobody'"):
        overtake.risk(policy="nobody", out=tmp_path / "c")
