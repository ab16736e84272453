#!/usr/bin/env python3
"""Trains a lane-and-speed policy on overtake.VecEnv with PPO (ppo.py), then judges it on
held-out seeds against keeping the lane.

    python3 examples/learning/train.py --out build/learning            # the README's run
    python3 examples/learning/train.py --decisions 200000 --out /tmp/quick

Writes into --out: policy.json (after every update, so an interrupted run keeps what it
learned; examples/learning/planner.py drives with it), curve.csv (one row per update),
curve.svg (the learning curve) and heldout.json (the held-out scorecard of the trained
policy and of keeping the lane). Needs PyTorch (Debian: python3-torch) and the overtake
module (pip install --no-build-isolation ., or PYTHONPATH=build/release/python).
"""

import argparse
import csv
import dataclasses
import json
import pathlib
import sys

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

try:
    import overtake  # noqa: E402
    from planner import Greedy, load_policy  # noqa: E402
    import ppo  # noqa: E402
except KeyboardInterrupt:
    sys.exit(130)
except RuntimeError as e:  # Ctrl-C while PyTorch loads its library comes as this
    if "KeyboardInterrupt" in str(e):
        sys.exit(130)
    raise


def judge(choose, seed, runs, minutes, threads=0):
    """Drives `runs` episodes (seeds seed .. seed + runs - 1, the drives of `overtake drive
    --seed`) with choose(observations) -> actions; their miles, mean speed, incidents and
    collisions, from each episode's report."""
    env = overtake.VecEnv(runs, seed=seed, minutes=minutes, threads=threads, params=ppo.PARAMS)
    obs, _ = env.reset()
    reports = [None] * runs
    while any(r is None for r in reports):
        obs, _, _, _, info = env.step(choose(obs))
        for i in np.flatnonzero(info.get("_final_report", np.zeros(runs, bool))):
            if reports[i] is None:
                reports[i] = info["final_report"][i]
    miles = sum(r["distance_miles"] for r in reports)
    hours = sum(r["duration_s"] for r in reports) / 3600.0
    incidents = sum(sum(r["incident_counts"].values()) for r in reports)
    return {"runs": runs, "first_seed": seed, "minutes": minutes, "miles": round(miles, 3),
            "mean_speed_mph": round(miles / hours, 3),
            "incidents": incidents, "incidents_per_100mi": round(100.0 * incidents / miles, 3),
            "collisions": sum(r["collisions"]["total"] for r in reports),
            "at_fault": sum(r["collisions"]["at_fault"] for r in reports),
            "lane_changes": sum(r["lane_changes"] for r in reports)}


def sampled_chooser(policy, seed):
    """The policy as it was trained: each action drawn from the network's probabilities
    (numpy's generator seeded by `seed`, so the same every time)."""
    net = Greedy(policy)
    rng = np.random.default_rng(seed)

    def choose(obs):
        logits = net.logits(obs)
        p = np.exp(logits - logits.max(axis=1, keepdims=True))
        p /= p.sum(axis=1, keepdims=True)
        u = rng.random(len(obs))[:, None]
        picks = np.minimum((np.cumsum(p, axis=1) < u).sum(axis=1), p.shape[1] - 1)
        return net.meta[picks]

    return choose


def keep_lane(obs):
    return np.zeros(len(obs), dtype=np.int64)


def svg_curve(curve, keep_mph):
    """The learning curve against decisions: the training episodes' mean speed (thin), the
    greedy policy's on the validation seeds (green, with its points), and keeping the lane's
    on the held-out seeds (dashed)."""
    points = [(r["decisions"], r["episodes_mph"]) for r in curve if r["episodes_mph"]]
    greedy = [(r["decisions"], r["greedy_mph"]) for r in curve if r.get("greedy_mph")]
    w, h, left, bottom = 640, 360, 60, 40
    xmax = max(p[0] for p in points) if points else 1
    ys = [p[1] for p in points] + [p[1] for p in greedy] + [keep_mph]
    ylo, yhi = np.floor(min(ys) - 1), np.ceil(max(ys) + 1)

    def at(x, y):
        return (left + (w - left - 20) * x / xmax,
                h - bottom - (h - bottom - 20) * (y - ylo) / (yhi - ylo))

    line = " ".join(f"{at(x, y)[0]:.1f},{at(x, y)[1]:.1f}" for x, y in points)
    gline = " ".join(f"{at(x, y)[0]:.1f},{at(x, y)[1]:.1f}" for x, y in greedy)
    dots = "".join(f'<circle cx="{at(x, y)[0]:.1f}" cy="{at(x, y)[1]:.1f}" r="2.5" fill="#2ca02c"/>'
                   for x, y in greedy)
    k0, k1 = at(0, keep_mph), at(xmax, keep_mph)
    ticks = []
    for y in np.arange(ylo, yhi + 0.01, 2.0):
        ty = at(0, y)[1]
        ticks.append(f'<text x="{left - 6}" y="{ty + 4:.1f}" text-anchor="end">{y:.0f}</text>')
    for x in np.linspace(0, xmax, 5):
        tx = at(x, ylo)[0]
        ticks.append(f'<text x="{tx:.1f}" y="{h - bottom + 16}" text-anchor="middle">'
                     f'{x / 1e6:.2f} M</text>')
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
            'font-family="sans-serif" font-size="11">\n'
            f'<rect width="{w}" height="{h}" fill="white"/>\n'
            f'<line x1="{left}" y1="{h - bottom}" x2="{w - 20}" y2="{h - bottom}" stroke="black"/>\n'
            f'<line x1="{left}" y1="20" x2="{left}" y2="{h - bottom}" stroke="black"/>\n'
            + "\n".join(ticks) + "\n" +
            f'<polyline points="{line}" fill="none" stroke="#9ecae1" stroke-width="1"/>\n'
            f'<polyline points="{gline}" fill="none" stroke="#2ca02c" stroke-width="2"/>{dots}\n'
            f'<text x="{left + 8}" y="34" fill="#6baed6">training episodes (actions drawn '
            'from the policy)</text>\n'
            f'<text x="{left + 8}" y="48" fill="#2ca02c">its most likely action, on validation '
            'seeds</text>\n'
            f'<line x1="{k0[0]:.1f}" y1="{k0[1]:.1f}" x2="{k1[0]:.1f}" y2="{k1[1]:.1f}" '
            'stroke="#d62728" stroke-dasharray="6,4"/>\n'
            f'<text x="{w - 24}" y="{k0[1] - 6:.1f}" text-anchor="end" fill="#d62728">'
            'keeping the lane (held out)</text>\n'
            f'<text x="{w / 2}" y="{h - 6}" text-anchor="middle">agent decisions</text>\n'
            f'<text x="14" y="{h / 2}" transform="rotate(-90 14 {h / 2})" '
            'text-anchor="middle">mean speed, mph</text>\n</svg>\n')


def main(argv=None):
    defaults = ppo.Settings()
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--out", type=pathlib.Path, required=True, help="folder for the results")
    for field in dataclasses.fields(ppo.Settings):
        p.add_argument("--" + field.name.replace("_", "-"), type=type(getattr(defaults, field.name)),
                       default=getattr(defaults, field.name),
                       help=f"PPO setting {field.name}")
    p.add_argument("--heldout-seed", type=int, default=1_000_001,
                   help="first seed of the held-out episodes (training uses seed .. seed + envs)")
    p.add_argument("--validate-seed", type=int, default=2_000_001,
                   help="first seed of the validation episodes the greedy policy is driven on "
                        "during training, for the learning curve")
    p.add_argument("--validate-runs", type=int, default=16, help="validation episodes")
    p.add_argument("--validate-minutes", type=float, default=2.0, help="validation episode length")
    p.add_argument("--validate-every", type=int, default=25,
                   help="updates between two validations (0: none)")
    p.add_argument("--heldout-runs", type=int, default=64, help="held-out episodes")
    p.add_argument("--heldout-minutes", type=float, default=10.0, help="held-out episode length")
    args = p.parse_args(argv)
    settings = ppo.Settings(**{f.name: getattr(args, f.name) for f in dataclasses.fields(ppo.Settings)})
    try:
        settings.check()
    except ValueError as e:
        p.error(str(e))
    if args.heldout_runs < 1 or not 0 < args.heldout_minutes <= 60:
        p.error("--heldout-runs must be at least 1 and --heldout-minutes in (0, 60]")
    if args.validate_runs < 1 or not 0 < args.validate_minutes <= 60 or args.validate_every < 0:
        p.error("--validate-runs must be at least 1, --validate-minutes in (0, 60] and "
                "--validate-every at least 0")
    for name, first, count in (("--heldout-seed", args.heldout_seed, args.heldout_runs),
                               ("--validate-seed", args.validate_seed, args.validate_runs)):
        if first < args.seed + args.envs and args.seed < first + count:
            p.error(f"{name}'s episodes fall among the training seeds")
    if (args.validate_seed < args.heldout_seed + args.heldout_runs and
            args.heldout_seed < args.validate_seed + args.validate_runs):
        p.error("the validation and held-out seeds overlap")
    args.out.mkdir(parents=True, exist_ok=True)

    def checkpoint(agent, curve):
        ppo.save_policy(agent, args.out / "policy.json", settings)
        row = curve[-1]
        row["greedy_mph"] = None
        if args.validate_every and (row["update"] % args.validate_every == 0 or
                                    row["update"] == 1):
            # The greedy policy so far on validation seeds of their own (neither the training's
            # nor the held-out ones): the curve's second line. Training draws nothing here.
            judged = judge(Greedy(load_policy(args.out / "policy.json")),
                           args.validate_seed, args.validate_runs, args.validate_minutes,
                           settings.threads)
            row["greedy_mph"] = judged["mean_speed_mph"]
            print(f"update {row['update']}: greedy on the validation seeds "
                  f"{judged['mean_speed_mph']:.2f} mph, {judged['incidents']} incidents")
        with open(args.out / "curve.csv", "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(curve[0]))
            writer.writeheader()
            writer.writerows(curve)

    try:
        agent, curve = ppo.train(settings, checkpoint=checkpoint)
    except KeyboardInterrupt:
        print(f"interrupted: {args.out / 'policy.json'} holds the last finished update",
              file=sys.stderr)
        return 130
    policy = load_policy(args.out / "policy.json")
    heldout = {"learned": judge(Greedy(policy), args.heldout_seed, args.heldout_runs,
                                args.heldout_minutes, settings.threads),
               "sampled": judge(sampled_chooser(policy, args.heldout_seed), args.heldout_seed,
                                args.heldout_runs, args.heldout_minutes, settings.threads),
               "keep_lane": judge(keep_lane, args.heldout_seed, args.heldout_runs,
                                  args.heldout_minutes, settings.threads)}
    heldout["gain_mph"] = round(heldout["learned"]["mean_speed_mph"] -
                                heldout["keep_lane"]["mean_speed_mph"], 3)
    (args.out / "heldout.json").write_text(json.dumps(heldout, indent=2) + "\n")
    (args.out / "curve.svg").write_text(svg_curve(curve, heldout["keep_lane"]["mean_speed_mph"]))
    for name in ("learned", "sampled", "keep_lane"):
        r = heldout[name]
        print(f"held out, {name}: {r['mean_speed_mph']:.2f} mph, "
              f"{r['incidents_per_100mi']:.2f} incidents per 100 mi ({r['miles']:.0f} mi, "
              f"{r['lane_changes']} lane changes)")
    print(f"gain over keeping the lane: {heldout['gain_mph']:+.2f} mph")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
