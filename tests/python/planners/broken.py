"""Planners that fail in the ways a run must survive."""
import math


def raises(telemetry):
    if telemetry["speed"] >= 0:
        raise ValueError("boom at s=%.0f" % telemetry["s"])
    return [], []


def nan(telemetry):
    return [telemetry["x"] + 1.0, math.nan], [telemetry["y"], telemetry["y"]]


def far(telemetry):
    """Finite, but 1e300 m away: no world can carry a car there."""
    return [telemetry["x"] + 1.0, 1e300], [telemetry["y"], telemetry["y"]]


def one_list(telemetry):
    return [telemetry["x"]]


def unequal(telemetry):
    return [telemetry["x"], telemetry["x"] + 0.4], [telemetry["y"]]


not_callable = 42
