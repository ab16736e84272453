#!/usr/bin/env python3
"""Bench rows for the evaluation's calibration (tests/eval/stats_calibration_test.cpp).

Reads the runs.jsonl of one or more benches and writes, per run, the figures the intervals
and verdicts are computed from (one CSV line): the set it belongs to, policy, traffic, seed,
miles, hours, the rubric's incidents, collisions (contacts), at-fault collisions and near
misses. How tests/data/calibration/bench_rows.csv was made: docs/evaluation.md, "Calibration".

    scripts/calibration-rows.py SET=FOLDER [SET=FOLDER ...] > bench_rows.csv
"""
import json
import sys


def main(argv):
    if len(argv) < 2 or any("=" not in a for a in argv[1:]):
        sys.stderr.write(__doc__)
        return 2
    print("set,policy,traffic,seed,miles,hours,incidents,collisions,at_fault,near_misses")
    for arg in argv[1:]:
        label, folder = arg.split("=", 1)
        rows = []
        with open(folder + "/runs.jsonl", encoding="utf-8") as f:
            for line in f:
                if not line.strip():
                    continue
                r = json.loads(line)
                c = r["config"]
                coll = r["collisions"]
                if "contacts" not in coll:
                    sys.exit(f"{folder}: a row without collisions.contacts (an older build)")
                rows.append((c["policy"], c["traffic"], c["seed"], r["distance_miles"],
                             r["duration_s"] / 3600.0, sum(r["incident_counts"].values()),
                             coll["total"], coll["at_fault"],
                             r["safety"]["near_miss_episodes"]))
        rows.sort(key=lambda x: (x[0], x[1], x[2]))
        for p, t, seed, miles, hours, inc, col, atf, near in rows:
            print(f"{label},{p},{t},{seed},{miles:.6f},{hours:.6f},{inc},{col},{atf},{near}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
