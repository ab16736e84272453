#!/usr/bin/env python3
"""Where the reference planner's time goes in faithful traffic: the share of the time in each
situation of the lanes around the ego, and its mean speed there.

    PYTHONPATH=build/release/python /usr/bin/python3 bench/where_time_goes.py \
        [--seeds 1-20] [--minutes 30] [--config FILE] [--map FILE]

A lane is *blocked* when a car slower than 47 mph is within 50 m ahead of the ego in it
(bumper to bumper), or beside the ego (centres less than a car length apart along the road).
Every world step after the first 30 s counts; the ego's lane is the one its centre is in. The
situations: its own lane open; its own blocked and a next lane open; its own and the next
blocked and the far lane open (from an outer lane); every lane blocked.

With --open-detail, the time with its own lane open is split further: changing lanes (the
ego's centre more than 0.5 m from its lane's centre); following (a car in its lane within 80 m
ahead, bumper to bumper, slower than the cruise speed); speeding up (faster than a step before
and more than 0.5 mph below cruise); the rest. The loss of each is its share of that time times
how far its mean speed is below cruise.

With --far-detail, the time with only the far lane open (the ego in an outer lane) is split by
what holds it in the middle lane: changing lanes; a car beside it there (centres less than a
car length and 1.5 m apart); the nearest car ahead there within 10 m, 10-20 m or farther
(bumper to bumper); a car behind there within 10 m.
"""
import argparse
import math

try:
    import overtake
except ImportError:
    raise SystemExit(f"{__file__}: no overtake module: build it (make build) and set "
                     "PYTHONPATH=build/release/python")

MPS_TO_MPH = 2.2369362920544
BLOCKING_MPH = 47.0
AHEAD_M = 50.0
CAR_LENGTH_M = 4.7
LANE_WIDTH_M = 4.0
LANES = 3
SKIP_S = 30.0
ROAD_LENGTH_M = 6945.554  # the loop's length in s, the built-in track's and the course map's
SITUATIONS = ("own lane open", "own lane blocked, the next lane open",
              "own lane and the next blocked, the far lane open", "every lane blocked")
CRUISE_MPH = 49.7
FOLLOW_M = 80.0
OPEN_DETAILS = ("changing lanes", "following a car slower than cruise", "speeding up",
                "the rest")
FAR_DETAILS = ("changing lanes", "a car beside in the middle lane",
               "a car ahead there within 10 m", "a car ahead there 10-20 m",
               "a car behind there within 10 m", "the nearest ahead there farther")


def seeds_of(text):
    first, _, last = text.partition("-")
    return range(int(first), int(last or first) + 1)


def blocked_lanes(t, road_length_m):
    blocked = [False] * LANES
    for _, _, _, vx, vy, s, d in t["sensor_fusion"]:
        lane = int(d // LANE_WIDTH_M)
        if not 0 <= lane < LANES:
            continue
        gap = (s - t["s"]) % road_length_m
        if gap > road_length_m / 2:
            gap -= road_length_m
        beside = abs(gap) < CAR_LENGTH_M
        slow_ahead = (0 <= gap - CAR_LENGTH_M <= AHEAD_M and
                      math.hypot(vx, vy) * MPS_TO_MPH < BLOCKING_MPH)
        blocked[lane] = blocked[lane] or beside or slow_ahead
    return blocked


def situation(own, blocked):
    if not blocked[own]:
        return 0
    near = [lane for lane in (own - 1, own + 1) if 0 <= lane < LANES]
    if any(not blocked[lane] for lane in near):
        return 1
    if any(not blocked[lane] for lane in range(LANES) if abs(lane - own) == 2):
        return 2
    return 3


def open_detail(t, own, previous_mph):
    """Which part of the time with its own lane open this step is (an index of OPEN_DETAILS)."""
    if abs(t["d"] - (own + 0.5) * LANE_WIDTH_M) > 0.5:
        return 0
    for _, _, _, vx, vy, s, d in t["sensor_fusion"]:
        if int(d // LANE_WIDTH_M) != own:
            continue
        gap = (s - t["s"]) % ROAD_LENGTH_M - CAR_LENGTH_M
        if 0 <= gap < FOLLOW_M and math.hypot(vx, vy) * MPS_TO_MPH < CRUISE_MPH - 0.3:
            return 1
    if previous_mph < t["speed"] < CRUISE_MPH - 0.5:
        return 2
    return 3


def far_detail(t, own):
    """What holds the ego in the middle lane this step (an index of FAR_DETAILS)."""
    if abs(t["d"] - (own + 0.5) * LANE_WIDTH_M) > 0.5:
        return 0
    ahead = behind = math.inf
    for _, _, _, _, _, s, d in t["sensor_fusion"]:
        if int(d // LANE_WIDTH_M) != 1:
            continue
        gap = (s - t["s"]) % ROAD_LENGTH_M
        if gap > ROAD_LENGTH_M / 2:
            gap -= ROAD_LENGTH_M
        if abs(gap) < CAR_LENGTH_M + 1.5:
            return 1
        if gap > 0:
            ahead = min(ahead, gap - CAR_LENGTH_M)
        else:
            behind = min(behind, -gap - CAR_LENGTH_M)
    if ahead < 10.0:
        return 2
    if ahead < 20.0:
        return 3
    return 4 if behind < 10.0 else 5


def print_table(header, names, time_s, miles, loss):
    total = sum(time_s)
    print(header)
    print("|---|---:|---:|" + ("---:|" if loss else ""))
    for k, name in enumerate(names):
        speed = miles[k] / time_s[k] * 3600.0 if time_s[k] > 0 else float("nan")
        row = f"| {name} | {100 * time_s[k] / total:.1f}% | {speed:.1f} mph |"
        if loss:
            row += f" {time_s[k] / total * (CRUISE_MPH - speed):.2f} mph |"
        print(row)
    print(f"| all | | {sum(miles) / total * 3600.0:.2f} mph |" + (" |" if loss else ""))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="1-20", help="a seed or a range, e.g. 1-20")
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--config", help="a config file, as for overtake --config")
    ap.add_argument("--map", help="a map file (default: the built-in track)")
    ap.add_argument("--open-detail", action="store_true",
                    help="split the time with the own lane open further")
    ap.add_argument("--far-detail", action="store_true",
                    help="split the time with only the far lane open by what holds the ego")
    a = ap.parse_args()
    time_s = [0.0] * len(SITUATIONS)
    miles = [0.0] * len(SITUATIONS)
    open_time_s = [0.0] * len(OPEN_DETAILS)
    open_miles = [0.0] * len(OPEN_DETAILS)
    far_time_s = [0.0] * len(FAR_DETAILS)
    far_miles = [0.0] * len(FAR_DETAILS)
    for seed in seeds_of(a.seeds):
        world = overtake.World(map=a.map, seed=seed, traffic="faithful", config=a.config,
                               minutes=a.minutes)
        policy = overtake.builtin_policy("reference", map=a.map, config=a.config)
        t = world.reset()
        last_s = 0.0
        previous_mph = 0.0
        while True:
            t, info = world.step(*policy(t))
            if info["done"]:
                break
            dt = info["time_s"] - last_s
            last_s = info["time_s"]
            step_previous_mph, previous_mph = previous_mph, t["speed"]
            if info["time_s"] <= SKIP_S:
                continue
            own = min(LANES - 1, max(0, int(t["d"] // LANE_WIDTH_M)))
            k = situation(own, blocked_lanes(t, ROAD_LENGTH_M))
            time_s[k] += dt
            miles[k] += t["speed"] * dt / 3600.0
            if k == 0 and a.open_detail:
                j = open_detail(t, own, step_previous_mph)
                open_time_s[j] += dt
                open_miles[j] += t["speed"] * dt / 3600.0
            if k == 2 and a.far_detail:
                j = far_detail(t, own)
                far_time_s[j] += dt
                far_miles[j] += t["speed"] * dt / 3600.0
    print_table("| situation | share of the time | the ego's mean speed |", SITUATIONS, time_s,
                miles, False)
    if a.open_detail:
        print()
        print_table("| own lane open | share of that time | the ego's mean speed | loss |",
                    OPEN_DETAILS, open_time_s, open_miles, True)
    if a.far_detail:
        print()
        print_table("| only the far lane open | share of that time | the ego's mean speed |",
                    FAR_DETAILS, far_time_s, far_miles, False)


if __name__ == "__main__":
    main()
