"""The policy train.py learned, as a planner: `overtake drive --policy-py
examples/learning/planner.py:Learned` (and bench, compare, risk), with numpy only.

Learned reads the policy from $OVERTAKE_LEARNED_POLICY, or policy.json beside this file (the
one the README's figures are of). It takes the most likely meta-action for each observation.
KeepLane is the baseline it is judged against: it never changes lane and keeps the speed
target at the limit, the reference's trajectory layer following the car ahead.
"""

import json
import os
import pathlib

import numpy as np

import overtake

HERE = pathlib.Path(__file__).resolve().parent


def load_policy(path):
    """The JSON train.py writes: linear layers with tanh between them, logits out."""
    path = pathlib.Path(path)
    try:
        policy = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise ValueError(f"{path}: not a policy file train.py wrote ({e})") from None
    if not isinstance(policy, dict) or policy.get("format") != "overtake-mlp-policy/1":
        raise ValueError(f"{path}: not a policy file train.py wrote (no format "
                         "'overtake-mlp-policy/1')")
    meta = np.asarray(policy.get("meta_actions", []), dtype=np.int64)
    layers = [(np.asarray(w, dtype=np.float64), np.asarray(b, dtype=np.float64))
              for w, b in policy["layers"]]
    for (w, b), nxt in zip(layers, layers[1:] + [None]):
        if w.ndim != 2 or b.shape != (w.shape[0],) or (nxt and nxt[0].shape[1] != w.shape[0]):
            raise ValueError(f"{path}: the layers' shapes do not chain")
    if meta.shape != (layers[-1][0].shape[0],) or np.any((meta < 0) | (meta > 4)):
        raise ValueError(f"{path}: meta_actions does not name one meta-action per output")
    return layers, meta


class Greedy:
    """observation -> the meta-action of the largest of the network's logits."""

    def __init__(self, policy):
        self.layers, self.meta = policy

    def logits(self, observation):
        x = np.asarray(observation, dtype=np.float64)
        for i, (w, b) in enumerate(self.layers):
            x = x @ w.T + b
            if i + 1 < len(self.layers):
                x = np.tanh(x)
        return x

    def __call__(self, observation):
        return self.meta[np.argmax(self.logits(observation), axis=-1)]


class Learned(overtake.Driver):
    def __init__(self):
        path = os.environ.get("OVERTAKE_LEARNED_POLICY") or HERE / "policy.json"
        greedy = Greedy(load_policy(path))
        super().__init__(lambda observation: int(greedy(observation)), params=HERE / "learn.json")


def keep(observation):
    return 0


class KeepLane(overtake.Driver):
    def __init__(self):
        super().__init__(keep, params=HERE / "learn.json")
