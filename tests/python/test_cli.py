"""`overtake drive|bench --policy-py`: Python planners in the binary's embedded interpreter."""
import json
import os

from conftest import PLANNERS, SOURCE, comparable

# The planners import the overtake module from the build (delegate.py) and their own folder.
ENV = {"PYTHONPATH": os.environ.get("PYTHONPATH", "")}


def test_drive_with_a_python_planner_reports_as_the_builtin(run_binary):
    code, report, err = run_binary("drive", "--policy-py", "delegate:plan", "--seed", "3",
                                   "--minutes", "1", cwd=PLANNERS, env=ENV)
    assert code == 0, err
    assert report["config"]["policy"] == "delegate"
    assert report["config"]["planner"] == {"kind": "python", "source": "delegate:plan"}
    assert report["plan_status"] is None  # it answers points only: how it planned is unknown
    code, builtin, err = run_binary("drive", "--policy", "walkthrough", "--seed", "3",
                                    "--minutes", "1")
    assert code == 0, err
    assert comparable(report) == comparable(builtin)


def test_a_file_path_and_a_name(run_binary, tmp_path):
    code, report, err = run_binary("drive", "--policy-py",
                                   f"mine={PLANNERS / 'delegate.py'}:Walkthrough", "--minutes",
                                   "0.5", cwd=tmp_path, env=ENV)
    assert code == 0, err
    assert report["config"]["policy"] == "mine" and report["end"] == "completed"


def test_the_example_planner_from_its_folder(run_binary):
    code, report, err = run_binary("drive", "--policy-py", "planner:plan", "--minutes", "1",
                                   "--seed", "2", cwd=SOURCE / "examples/python")
    assert code == 0, err
    assert report["incident_counts"]["collision"] == 0 and report["distance_miles"] > 0.4


def test_the_embedded_python_is_the_build_s_whatever_python3_is_first_on_path(run_binary,
                                                                                tmp_path):
    # A python3 of another installation first on PATH (a pyenv, conda or virtual
    # environment's) must not become the embedded interpreter's home: here one that is no
    # Python at all. The example planner still imports numpy from the build's Python.
    fake = tmp_path / "bin"
    fake.mkdir()
    (fake / "python3").write_text("#!/bin/sh\nexit 3\n")
    (fake / "python3").chmod(0o755)
    env = {"PATH": str(fake) + os.pathsep + os.environ.get("PATH", "")}
    code, report, err = run_binary("drive", "--policy-py", "planner:plan", "--minutes", "0.5",
                                   cwd=SOURCE / "examples/python", env=env)
    assert code == 0, err
    assert report["end"] == "completed"


def test_a_planner_that_raises_ends_the_run_as_planner_failed(run_binary):
    code, report, err = run_binary("drive", "--policy-py", "broken:raises", "--minutes", "1",
                                   cwd=PLANNERS)
    assert code == 1
    assert report["end"] == "planner_failed"
    assert "ValueError: boom at s=" in report["ended_early"]
    assert "broken.py, line" in report["ended_early"]


def test_a_nan_ends_the_run_as_planner_failed(run_binary):
    code, report, _ = run_binary("drive", "--policy-py", "broken:nan", "--minutes", "1",
                                 cwd=PLANNERS)
    assert code == 1 and report["end"] == "planner_failed"
    assert "path_x[1] is not a finite number" in report["ended_early"]


def test_a_point_beyond_the_world_ends_the_run_as_planner_failed(run_binary):
    code, report, _ = run_binary("drive", "--policy-py", "broken:far", "--minutes", "1",
                                 cwd=PLANNERS)
    assert code == 1 and report["end"] == "planner_failed"
    assert "point 1 is (1e+300, " in report["ended_early"]
    assert "beyond 1,000 km" in report["ended_early"]
    assert report["distance_miles"] is not None and report["distance_miles"] >= 0


def test_loading_errors_are_usage_errors(run_binary):
    for spec, words in [("no_such_module:plan", ["no_such_module", "ModuleNotFoundError"]),
                        ("import_fails:plan", ["import_fails", "not installed"]),
                        ("broken:missing", ["broken", "has no 'missing'"]),
                        ("broken:not_callable", ["not callable"]),
                        ("nocolon", ["MODULE:FUNCTION"])]:
        code, report, err = run_binary("drive", "--policy-py", spec, "--minutes", "1",
                                       cwd=PLANNERS)
        assert code == 2, (spec, err)
        assert report is None
        for w in words:
            assert w in err, (spec, err)


def test_bench_runs_python_planners_on_several_threads(binary, tmp_path):
    import subprocess
    out = tmp_path / "bench"
    env = dict(os.environ)
    p = subprocess.run([binary, "bench", "--policy-py", "delegate:Walkthrough",
                        "--policies", "delegate,walkthrough", "--seeds", "1-4", "--minutes",
                        "0.5", "--jobs", "3", "--out", str(out), "--quiet"], cwd=PLANNERS,
                       env=env, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    runs = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    by = {}
    for r in runs:
        report = r.get("report", r)
        by[(report["config"]["policy"], report["config"]["seed"])] = report
    assert len(by) == 8
    for seed in range(1, 5):
        python, builtin = by[("delegate", seed)], by[("walkthrough", seed)]
        assert python["end"] == "completed"
        python.pop("index", None), builtin.pop("index", None)  # the row number in the bench
        assert comparable(python) == comparable(builtin)


# A planner file that imports a module beside it, and says whose it is and whether its folder
# is still on sys.path when it plans (by failing with that message).
PLANNER_WITH_A_SIBLING = """import os
import sys

import {sibling}

HERE = os.path.dirname(os.path.abspath(__file__))


def plan(telemetry):
    raise ValueError("the planner of %s; its folder on sys.path: %s" % ({sibling}.WHO,
                                                                          HERE in sys.path))
"""


def test_two_planner_files_of_one_name_each_run_their_own_code(run_binary, tmp_path):
    files = {}
    for who in ("a", "b"):
        folder = tmp_path / who
        folder.mkdir()
        (folder / f"sibling_{who}.py").write_text(f"WHO = {who!r}\n")
        files[who] = folder / "planner.py"
        files[who].write_text(PLANNER_WITH_A_SIBLING.format(sibling=f"sibling_{who}"))
    for chosen in ("a", "b"):
        code, report, err = run_binary("drive", "--policy-py", f"A={files['a']}:plan",
                                       "--policy-py", f"B={files['b']}:plan", "--policy",
                                       chosen.upper(), "--minutes", "0.1", cwd=tmp_path)
        assert code == 1, err
        assert report["config"]["policy"] == chosen.upper()
        assert f"the planner of {chosen}; its folder on sys.path: False" in report["ended_early"]
    # Unnamed, a planner file is named after its stem.
    code, report, err = run_binary("drive", "--policy-py", f"{files['b']}:plan", "--minutes",
                                   "0.1", cwd=tmp_path)
    assert report["config"]["policy"] == "planner", err
    assert "the planner of b" in report["ended_early"]


def test_a_planner_that_never_answers_is_interrupted(run_binary):
    code, report, err = run_binary("drive", "--policy-py", "interruptible.py:spin", "--minutes",
                                   "0.1", "--planner-reply-timeout", "1", cwd=PLANNERS)
    assert code == 1, err
    assert report["end"] == "planner_failed"
    assert ("did not answer in time and was interrupted (TimeoutError at interruptible.py, line"
            in report["ended_early"])


def test_planner_params_give_a_python_planner_its_keywords(run_binary, tmp_path):
    planner = f"kw={PLANNERS / 'keyword_speed.py'}:Planner"
    code, slow, err = run_binary("drive", "--policy-py", planner, "--planner-params",
                                 'kw={"speed_mps":8}', "--seed", "1", "--minutes", "1",
                                 cwd=tmp_path, env=ENV)
    assert code == 0, err
    assert slow["config"]["planner"]["params"] == {"speed_mps": 8.0}
    code, default, err = run_binary("drive", "--policy-py", planner, "--seed", "1", "--minutes",
                                    "1", cwd=tmp_path, env=ENV)
    assert code == 0, err
    assert "params" not in default["config"]["planner"]
    # 8 m/s is 17.9 mph; the planner's own default (15 m/s) is far faster.
    assert slow["mean_speed_mph"] < 18.0 < default["mean_speed_mph"] - 5.0


def test_a_keyword_the_python_planner_cannot_take_is_refused_before_any_run(run_binary,
                                                                            tmp_path):
    code, _, err = run_binary("drive", "--policy-py", f"kw={PLANNERS / 'keyword_speed.py'}:Planner",
                              "--planner-params", 'kw={"sped_mps":8}', "--minutes", "0.5",
                              cwd=tmp_path, env=ENV)
    assert code == 2
    assert "--planner-params" in err and "sped_mps" in err
