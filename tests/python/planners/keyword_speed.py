"""The example planner (examples/python/planner.py) with its target speed as a keyword
argument: a class, so that each run gets a copy of the example's module (its state) of its
own. For the tests of `overtake tune` on a Python planner's keyword."""
import importlib.util
import os

# From the file itself, not a link to it (the docs tests link it in as a reader's planner.py).
_EXAMPLE = os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", "..",
                        "examples", "python", "planner.py")


class Planner:
    def __init__(self, speed_mps=15.0):
        spec = importlib.util.spec_from_file_location("keyword_speed_example", _EXAMPLE)
        self.example = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(self.example)
        self.example.LIMIT = speed_mps

    def __call__(self, telemetry):
        return self.example.plan(telemetry)
