"""A Python planner that hands each telemetry to the built-in walkthrough policy (through the
overtake module): its drive must report what `--policy walkthrough` reports."""
import overtake

_policy = None


def plan(telemetry):
    global _policy
    if _policy is None:
        _policy = overtake.builtin_policy("walkthrough")
    return _policy(telemetry)


class Walkthrough:
    """The same as a class: one instance (one policy state) per run."""

    def __init__(self):
        self.policy = overtake.builtin_policy("walkthrough")

    def __call__(self, telemetry):
        return self.policy(telemetry)
