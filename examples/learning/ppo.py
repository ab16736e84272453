"""Proximal policy optimisation (Schulman et al. 2017) on overtake.VecEnv's meta-actions.

The agent decides twice a simulated second (learn.json: a decision every 25 world steps)
among the meta-actions of Settings.actions (keep, left and right by default: the speed is left
at the limit, the reference planner's trajectory layer following the car ahead and carrying
out the lane changes it judges safe, dropping the others). The policy and the value function
are two small multilayer perceptrons (two tanh layers of `hidden`) over the environment's 31
observations. One update collects
`rollout` decisions from each of the `envs` worlds, computes generalised advantage estimates
(Schulman et al. 2016) and takes `epochs` passes of clipped-surrogate gradient steps over
shuffled minibatches.

Everything is drawn from generators seeded by `seed` (torch, on one thread, and the worlds'
own seeds), so the same seed trains the same weights, byte for byte.

The trained policy is saved as JSON (the layers' weights as lists), so that a planner can
drive with it without PyTorch (planner.py evaluates it with numpy).
"""

import dataclasses
import json
import math
import time

import numpy as np
import torch
from torch import nn

import pathlib

import overtake

# The environment's meta-actions by name; the agent chooses among Settings.actions of them.
META_ACTIONS = {"keep": 0, "left": 1, "right": 2, "faster": 3, "slower": 4}
# The environment's parameters for this example (a decision every 0.5 s); planner.py drives
# with the same.
PARAMS = pathlib.Path(__file__).resolve().parent / "learn.json"


@dataclasses.dataclass
class Settings:
    seed: int = 0
    actions: str = "keep,left,right"
    envs: int = 64
    decisions: int = 3_000_000
    rollout: int = 64
    minutes: float = 2.0
    threads: int = 0
    hidden: int = 64
    learning_rate: float = 3e-4
    gamma: float = 0.95
    gae_lambda: float = 0.9
    clip: float = 0.2
    epochs: int = 4
    minibatch: int = 1024
    entropy: float = 0.003
    value_coef: float = 0.5
    max_grad_norm: float = 0.5

    def meta_actions(self):
        return [META_ACTIONS[a] for a in self.actions.split(",")]

    def check(self):
        names = self.actions.split(",")
        unknown = [a for a in names if a not in META_ACTIONS]
        if unknown or len(set(names)) != len(names) or len(names) < 2:
            raise ValueError(f"actions: '{self.actions}' is not two or more distinct of "
                             f"{', '.join(META_ACTIONS)}")
        positive = ("envs", "decisions", "rollout", "hidden", "epochs", "minibatch")
        for name in positive:
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be at least 1 (got {getattr(self, name)})")
        if not 0 < self.minutes <= 60:
            raise ValueError(f"minutes must be in (0, 60] (got {self.minutes})")
        for name in ("gamma", "gae_lambda"):
            if not 0 <= getattr(self, name) <= 1:
                raise ValueError(f"{name} must be in [0, 1] (got {getattr(self, name)})")
        if not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be positive (got {self.learning_rate})")


def mlp(inputs, hidden, outputs, out_gain):
    layers = [nn.Linear(inputs, hidden), nn.Tanh(), nn.Linear(hidden, hidden), nn.Tanh(),
              nn.Linear(hidden, outputs)]
    for layer in layers:
        if isinstance(layer, nn.Linear):
            nn.init.orthogonal_(layer.weight, math.sqrt(2.0))
            nn.init.zeros_(layer.bias)
    nn.init.orthogonal_(layers[-1].weight, out_gain)
    return nn.Sequential(*layers)


class Agent(nn.Module):
    def __init__(self, observations, hidden, actions):
        super().__init__()
        self.policy = mlp(observations, hidden, actions, 0.01)
        self.value = mlp(observations, hidden, 1, 1.0)

    def act(self, obs, generator):
        logits = self.policy(obs)
        probs = torch.softmax(logits, dim=-1)
        action = torch.multinomial(probs, 1, generator=generator).squeeze(-1)
        logp = torch.log_softmax(logits, dim=-1).gather(-1, action[:, None]).squeeze(-1)
        return action, logp, self.value(obs).squeeze(-1)

    def evaluate(self, obs, action):
        logp_all = torch.log_softmax(self.policy(obs), dim=-1)
        logp = logp_all.gather(-1, action[:, None]).squeeze(-1)
        entropy = -(logp_all.exp() * logp_all).sum(-1)
        return logp, entropy, self.value(obs).squeeze(-1)

    def weights(self):
        """The policy network as JSON-ready lists: [[W, b], ...] per linear layer."""
        return [[layer.weight.detach().tolist(), layer.bias.detach().tolist()]
                for layer in self.policy if isinstance(layer, nn.Linear)]


def advantages(rewards, values, next_values, ends, terminals, valid, gamma, lam):
    """GAE over a rollout (time-major arrays). next_values[t] is V of the observation the step
    returned (the episode's last one where it ended); a terminal one is worth 0; no advantage
    flows across an episode's end; invalid steps (the environment's reset steps) get 0."""
    steps = rewards.shape[0]
    adv = torch.zeros_like(rewards)
    carry = torch.zeros_like(rewards[0])
    for t in reversed(range(steps)):
        bootstrap = next_values[t] * (1.0 - terminals[t])
        delta = rewards[t] + gamma * bootstrap - values[t]
        carry = delta + gamma * lam * (1.0 - ends[t]) * carry
        carry = carry * valid[t]
        adv[t] = carry
    return adv


def train(settings, log=print, checkpoint=None):
    """Trains an agent; returns (agent, curve): one row per update (decisions so far, seconds
    of training, the mean speed and incidents per 100 mi of the episodes that ended in it)."""
    settings.check()
    torch.manual_seed(settings.seed)
    torch.set_num_threads(1)
    generator = torch.Generator().manual_seed(settings.seed)
    env = overtake.VecEnv(settings.envs, seed=settings.seed, minutes=settings.minutes,
                          threads=settings.threads, params=PARAMS)
    agent = Agent(env.observation_size, settings.hidden, len(settings.meta_actions()))
    to_meta = np.asarray(settings.meta_actions(), dtype=np.int64)
    optimiser = torch.optim.Adam(agent.parameters(), lr=settings.learning_rate, eps=1e-5)
    obs_np, _ = env.reset()
    obs = torch.as_tensor(obs_np)
    n, steps = settings.envs, settings.rollout
    updates = max(1, settings.decisions // (n * steps))
    curve = []
    started = time.monotonic()
    for update in range(updates):
        frac = 1.0 - update / updates
        for group in optimiser.param_groups:
            group["lr"] = settings.learning_rate * frac
        buf = {k: torch.zeros(steps, n) for k in
               ("actions", "logp", "values", "rewards", "ends", "terminals", "valid",
                "next_values")}
        buf_obs = torch.zeros(steps, n, env.observation_size)
        miles, hours, incidents = 0.0, 0.0, 0
        for t in range(steps):
            with torch.no_grad():
                action, logp, value = agent.act(obs, generator)
            obs_np, reward, terminated, truncated, info = env.step(to_meta[action.numpy()])
            buf_obs[t] = obs
            buf["actions"][t] = action.float()
            buf["logp"][t] = logp
            buf["values"][t] = value
            buf["rewards"][t] = torch.as_tensor(reward)
            buf["terminals"][t] = torch.as_tensor(terminated, dtype=torch.float32)
            buf["ends"][t] = torch.as_tensor(terminated | truncated, dtype=torch.float32)
            buf["valid"][t] = torch.as_tensor(~info["was_reset"], dtype=torch.float32)
            obs = torch.as_tensor(obs_np)
            with torch.no_grad():
                buf["next_values"][t] = agent.value(obs).squeeze(-1)
            if "_final_report" in info:
                for i in np.flatnonzero(info["_final_report"]):
                    report = info["final_report"][i]
                    miles += report["distance_miles"]
                    hours += report["duration_s"] / 3600.0
                    incidents += sum(report["incident_counts"].values())
        adv = advantages(buf["rewards"], buf["values"], buf["next_values"], buf["ends"],
                         buf["terminals"], buf["valid"], settings.gamma, settings.gae_lambda)
        returns = adv + buf["values"]
        mask = buf["valid"].reshape(-1) > 0
        flat_obs = buf_obs.reshape(-1, env.observation_size)[mask]
        flat = {k: v.reshape(-1)[mask] for k, v in
                (("actions", buf["actions"]), ("logp", buf["logp"]), ("adv", adv),
                 ("returns", returns))}
        flat["adv"] = (flat["adv"] - flat["adv"].mean()) / (flat["adv"].std() + 1e-8)
        size = flat_obs.shape[0]
        for _ in range(settings.epochs):
            order = torch.randperm(size, generator=generator)
            for start in range(0, size, settings.minibatch):
                idx = order[start:start + settings.minibatch]
                logp, entropy, value = agent.evaluate(flat_obs[idx], flat["actions"][idx].long())
                ratio = (logp - flat["logp"][idx]).exp()
                a = flat["adv"][idx]
                surrogate = torch.min(ratio * a, ratio.clamp(1 - settings.clip,
                                                             1 + settings.clip) * a)
                loss = (-surrogate.mean() + settings.value_coef *
                        (value - flat["returns"][idx]).pow(2).mean() -
                        settings.entropy * entropy.mean())
                optimiser.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), settings.max_grad_norm)
                optimiser.step()
        decisions = (update + 1) * n * steps
        row = {"update": update + 1, "decisions": decisions,
               "seconds": round(time.monotonic() - started, 1),
               "episodes_mph": round(miles / hours, 3) if hours else None,
               "incidents_per_100mi": round(100.0 * incidents / miles, 3) if miles else None}
        curve.append(row)
        if row["episodes_mph"] is not None:
            log(f"update {update + 1}/{updates}: {decisions} decisions, {row['seconds']} s, "
                f"episodes {row['episodes_mph']:.2f} mph, "
                f"{row['incidents_per_100mi']:.2f} incidents per 100 mi")
        if checkpoint is not None:
            checkpoint(agent, curve)
    return agent, curve


def save_policy(agent, path, settings):
    path.write_text(json.dumps({"format": "overtake-mlp-policy/1", "activation": "tanh",
                                "meta_actions": settings.meta_actions(), "settings": dataclasses.asdict(settings),
                                "layers": agent.weights()}) + "\n")
