#!/usr/bin/env python3
"""Turn a decoded Klipper run (decode_steps.py's PREFIX_1ms.csv and PREFIX_summary.json)
into the fixture format of tests/fixtures/klipper-ref: every STEP_MS from Klipper's first
carriage step for SECONDS, each carriage's change of step count since the row before, and a
JSON with the spacing, the step, the homed height and Klipper's end time.

    make_fixture.py PREFIX OUT_STEM [--step-ms 2] [--seconds 40] [--commit SHA]
"""
import argparse
import csv
import json


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("prefix")
    ap.add_argument("out_stem")
    ap.add_argument("--step-ms", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=40.0)
    ap.add_argument("--commit", default="")
    a = ap.parse_args()
    summary = json.load(open(a.prefix + "_summary.json"))
    step_mm = summary["step_dist_mm"]["stepper_a"]
    home_mm = summary["homed_height_mm"]["stepper_a"]
    rows = list(csv.reader(open(a.prefix + "_1ms.csv")))[1:]
    kept = [r for r in rows if float(r[0]) <= a.seconds and round(float(r[0]) * 1000) % a.step_ms == 0]
    prev = [0, 0, 0]
    with open(a.out_stem + ".steps.csv", "w") as f:
        f.write("d1,d2,d3\n")
        for r in kept:
            n = [round((float(q) - home_mm) / step_mm) for q in r[1:]]
            f.write("%d,%d,%d\n" % tuple(x - y for x, y in zip(n, prev)))
            prev = n
    meta = {"step_ms": a.step_ms, "step_mm": step_mm, "home_mm": home_mm, "rows": len(kept),
            "end_s": summary["end_time_s"], "klipper_commit": a.commit}
    json.dump(meta, open(a.out_stem + ".json", "w"), indent=1)


if __name__ == "__main__":
    main()
