"""Shared fixtures: the overtake binary (OVERTAKE_BINARY, set by ctest) and the source tree."""
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

HERE = pathlib.Path(__file__).resolve().parent
SOURCE = HERE.parents[1]
PLANNERS = HERE / "planners"

# What differs between two runs of one drive: the planner's timing, and what the report says
# of the planner itself (its name and kind).
VOLATILE = ("timing",)


def comparable(report):
    """The report without the keys that name or time the planner, and its plan status (which
    a planner that answers points only, as a Python one does, cannot give: null)."""
    r = {k: v for k, v in report.items() if k not in VOLATILE and k != "plan_status"}
    r["config"] = {k: v for k, v in report["config"].items() if k not in ("policy", "planner")}
    return r


def path_onto_a_car_ahead(t, steps=40):
    """A straight path from the ego to where the nearest car ahead on the road will be after
    `steps` steps (the original drops path points behind the car, so the car must be ahead).
    (car, (xs, ys)), or (None, None) while no car is ahead."""
    ahead = [c for c in t["sensor_fusion"] if 0 < c[6] < 12 and 0 < c[5] - t["s"] < 200]
    if not ahead:
        return None, None
    car = min(ahead, key=lambda c: c[5] - t["s"])
    gx, gy = car[1] + car[3] * 0.02 * steps, car[2] + car[4] * 0.02 * steps
    xs = [t["x"] + (gx - t["x"]) * (i + 1) / steps for i in range(steps)]
    ys = [t["y"] + (gy - t["y"]) * (i + 1) / steps for i in range(steps)]
    return car, (xs, ys)


def interrupt_script(body, started, wait_s=1.0, timeout_s=300):
    """Runs `body` (Python, indented as a block) in a fresh interpreter with Python's own
    SIGINT handler (a shell may start a background process with SIGINT ignored), waits for it
    to print `started`, then `wait_s` more, and sends Ctrl-C. (stdout, stderr, exit code,
    seconds from the signal to its end)."""
    code = ("if True:\n        import signal\n"
            "        signal.signal(signal.SIGINT, signal.default_int_handler)\n" + body)
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline() == started + "\n"
        time.sleep(wait_s)
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=timeout_s)
        return out, err, p.returncode, time.monotonic() - sent
    finally:
        p.kill()


@pytest.fixture(scope="session")
def binary():
    path = os.environ.get("OVERTAKE_BINARY")
    if not path or not os.path.exists(path):
        pytest.skip("OVERTAKE_BINARY is not set to the overtake binary")
    return path


@pytest.fixture(scope="session")
def run_binary(binary, tmp_path_factory):
    """Runs the binary; returns (exit code, JSON report or None, stderr)."""

    def run(*args, cwd=None, env=None):
        out = tmp_path_factory.mktemp("run") / "report.json"
        full_env = dict(os.environ)
        full_env.update(env or {})
        p = subprocess.run([binary, *args, "--json", str(out), "--quiet"], cwd=cwd, env=full_env,
                           capture_output=True, text=True, timeout=600)
        report = json.loads(out.read_text()) if out.exists() and out.stat().st_size else None
        return p.returncode, report, p.stderr

    return run
