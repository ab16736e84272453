"""Planners for the interruption tests (tests/python/interrupt_test.cpp)."""
import time


def spin(telemetry):
    while True:
        pass


def straight(telemetry):
    return [1.0, 2.0, 3.0], [0.0, 0.0, 0.0]


def for_a_second(telemetry):
    """Runs Python for a second of wall time, then answers."""
    end = time.monotonic() + 1.0
    n = 0
    while time.monotonic() < end:
        n += 1
    return [1.0, 2.0, 3.0], [0.0, 0.0, 0.0]


def counts(telemetry):
    """Runs a few thousand bytecodes before it answers."""
    n = 0
    for i in range(20000):
        n += i
    return [1.0, 2.0, 3.0], [0.0, 0.0, float(n % 2)]
