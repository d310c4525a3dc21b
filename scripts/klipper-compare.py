#!/usr/bin/env python3
"""Compare delta-gcode's commanded carriage heights with real Klipper's steps.

    scripts/klipper-compare.py OURS.csv KLIPPER.csv [--step-mm 0.0125] [--json]

OURS.csv is `delta-gcode trace` output (columns t_s, q1_cmd_mm, q2_cmd_mm, q3_cmd_mm).
KLIPPER.csv holds Klipper's carriage heights as step functions: columns t_s, q1_mm, q2_mm,
q3_mm, one row per step event (or per grid instant), the time of Klipper's first carriage
step being 0 (scripts/klipper-reference.sh makes it from a Klipper batch run).

The two time lines are aligned on the first step: ours is the first instant a commanded
carriage leaves its start height by half a step. Then, at each of our grid samples, the
difference between our commanded height and the step position Klipper had reached then;
and the end times (Klipper's last step, our last instant more than half a step from the
final heights). Standard library only.
"""
import argparse
import bisect
import csv
import json
import sys


def read_ours(path):
    t, q = [], []
    with open(path, newline="") as f:
        r = csv.DictReader(f)
        for row in r:
            t.append(float(row["t_s"]))
            q.append((float(row["q1_cmd_mm"]), float(row["q2_cmd_mm"]), float(row["q3_cmd_mm"])))
    return t, q


def read_klipper(path):
    t, q = [], []
    opener = open
    if path.endswith(".gz"):
        import gzip

        opener = gzip.open
    with opener(path, "rt", newline="") as f:
        r = csv.DictReader(f)
        for row in r:
            t.append(float(row["t_s"]))
            q.append((float(row["q1_mm"]), float(row["q2_mm"]), float(row["q3_mm"])))
    return t, q


def first_departure(t, q, half):
    """The instant a carriage first leaves its start height by half a step (Klipper's first
    step), interpolated linearly between the two samples around it."""
    q0 = q[0]
    dist = lambda qi: max(abs(a - b) for a, b in zip(qi, q0))
    for k in range(1, len(t)):
        d1 = dist(q[k])
        if d1 >= half:
            d0 = dist(q[k - 1])
            if d1 == d0:
                return t[k]
            return t[k - 1] + (t[k] - t[k - 1]) * (half - d0) / (d1 - d0)
    return None


def last_departure(t, q, half):
    qn = q[-1]
    last = t[0]
    for ti, qi in zip(t, q):
        if any(abs(a - b) > half for a, b in zip(qi, qn)):
            last = ti
    return last


def percentile(sorted_values, p):
    if not sorted_values:
        return float("nan")
    k = min(len(sorted_values) - 1, int(round(p / 100.0 * (len(sorted_values) - 1))))
    return sorted_values[k]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("ours")
    ap.add_argument("klipper")
    ap.add_argument("--step-mm", type=float, default=0.0125, help="carriage step distance, mm")
    ap.add_argument("--json", action="store_true", help="print the figures as JSON")
    a = ap.parse_args()
    half = a.step_mm / 2
    ot, oq = read_ours(a.ours)
    kt, kq = read_klipper(a.klipper)
    # Klipper's time line starts at its first step: rows before it (homing) are dropped.
    k0 = bisect.bisect_left(kt, 0.0)
    kt, kq = kt[max(k0 - 1, 0):], kq[max(k0 - 1, 0):]
    start = first_departure(ot, oq, half)
    if start is None:
        sys.exit("our trace never moves a carriage")
    diffs = []
    for ti, qi in zip(ot, oq):
        tk = ti - start
        if tk < kt[0] or tk > kt[-1]:
            continue
        i = bisect.bisect_right(kt, tk) - 1
        diffs.extend(abs(a_ - b_) for a_, b_ in zip(qi, kq[i]))
    diffs.sort()
    ours_end = last_departure(ot, oq, half) - start
    klipper_end = kt[-1]
    out = {
        "samples": len(diffs) // 3,
        "p50_mm": percentile(diffs, 50),
        "p99_mm": percentile(diffs, 99),
        "max_mm": diffs[-1] if diffs else float("nan"),
        "end_ours_s": ours_end,
        "end_klipper_s": klipper_end,
        "end_diff_pct": 100.0 * (ours_end - klipper_end) / klipper_end,
    }
    if a.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k:14} {v}")


if __name__ == "__main__":
    main()
