"""overtake.drive: a whole drive in C++ with a Python callable as the planner."""
import importlib.util
import sys

import pytest

import overtake
from conftest import PLANNERS, SOURCE, comparable, interrupt_script

sys.path.insert(0, str(PLANNERS))
import broken  # noqa: E402
import delegate  # noqa: E402


def test_a_python_callable_drives_as_the_builtin_policy():
    builtin = overtake.drive(policy="walkthrough", seed=2, minutes=1)
    delegate._policy = None
    via_python = overtake.drive(policy=delegate.plan, seed=2, minutes=1)
    assert comparable(via_python) == comparable(builtin)
    assert via_python["config"]["policy"] == "plan"
    assert via_python["config"]["planner"] == {"kind": "python", "source": "delegate:plan"}
    assert via_python["end"] == "completed"


def test_a_class_gets_one_instance_per_run():
    first = overtake.drive(policy=delegate.Walkthrough, seed=2, minutes=0.5, name="walk-class")
    second = overtake.drive(policy=delegate.Walkthrough, seed=2, minutes=0.5, name="walk-class")
    assert first["config"]["policy"] == "walk-class"
    assert comparable(first) == comparable(second)
    assert comparable(first) == comparable(overtake.drive("walkthrough", seed=2, minutes=0.5))


@pytest.mark.parametrize("planner, message", [
    (broken.raises, "ValueError: boom at s="),
    (broken.nan, "not a finite number"),
    (broken.one_list, "not a pair (path_x, path_y)"),
    (broken.unequal, "path_x has 2 points but path_y has 1"),
])
def test_a_failing_planner_ends_the_run(planner, message):
    report = overtake.drive(policy=planner, seed=1, minutes=1)
    assert report["end"] == "planner_failed"
    assert message in report["ended_early"]
    assert report["duration_s"] == 0


def test_the_failure_names_the_line():
    report = overtake.drive(policy=broken.raises, minutes=1)
    assert "broken.py, line" in report["ended_early"] and "in raises" in report["ended_early"]


def test_unknown_builtin_and_non_callables_are_value_errors():
    with pytest.raises(ValueError, match="unknown policy"):
        overtake.drive(policy="nope", minutes=1)
    with pytest.raises(ValueError, match="callable"):
        overtake.drive(policy=42, minutes=1)


def test_policies_lists_the_builtins():
    names = overtake.policies()
    assert "walkthrough" in names and "reference" in names


def load_example():
    spec = importlib.util.spec_from_file_location("example_planner",
                                                  SOURCE / "examples/python/planner.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("traffic", ["faithful", "calm"])
def test_the_example_planner_drives_a_lap_without_an_incident(traffic):
    example = load_example()
    report = overtake.drive(policy=example.plan, seed=1, traffic=traffic, minutes=8)
    assert report["end"] == "completed"
    assert sum(report["incident_counts"].values()) == 0, report["incidents"]
    assert report["distance_miles"] > 4.32  # the built-in loop is 6945.554 m


@pytest.mark.parametrize("stop", [KeyboardInterrupt("at the 10th call"), SystemExit(3)],
                         ids=["KeyboardInterrupt", "SystemExit"])
def test_keyboard_interrupt_and_system_exit_stop_the_drive_and_come_back(stop):
    walkthrough = overtake.builtin_policy("walkthrough")
    calls = []

    def plan(telemetry):
        calls.append(telemetry["s"])
        if len(calls) == 10:
            raise stop
        return walkthrough(telemetry)

    driven = []
    with pytest.raises(type(stop)) as raised:
        for seed in (1, 2):  # a loop over seeds ends at the first
            overtake.drive(policy=plan, seed=seed, minutes=1)
            driven.append(seed)
    assert raised.value is stop
    assert driven == [] and len(calls) == 10


def test_a_class_that_raises_keyboard_interrupt_when_made_stops_the_drive():
    class Planner:
        def __init__(self):
            raise KeyboardInterrupt

        def __call__(self, telemetry):
            return [], []

    with pytest.raises(KeyboardInterrupt):
        overtake.drive(policy=Planner, minutes=1)


def test_ctrl_c_stops_a_long_drive_of_a_builtin_policy():
    out, err, code, waited_s = interrupt_script("""
        import overtake
        print("driving", flush=True)
        overtake.drive("reference", minutes=60)
        print("finished", flush=True)
    """, "driving")
    assert "KeyboardInterrupt" in err and "finished" not in out, err[-2000:]
    assert code != 0
    assert waited_s < 2.0, f"the drive went on for {waited_s:.1f} s after Ctrl-C"
