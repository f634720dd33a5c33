"""Session 47: the probe's tables (``python benchmarks/results/experiments/s47_coverage/tables.py``)."""

from __future__ import annotations

import json
from pathlib import Path

HERE = Path(__file__).resolve().parent


def views(path):
    return [json.loads(line) for line in open(path)] if path.exists() else []


def main() -> int:
    rows = views(HERE / "val_mug.jsonl") + views(HERE / "val_drill+spray_bottle.jsonl")
    print("| category | views | first-ranked within 15 deg: today | coverage | turned round (> 45 deg): today"
          " | coverage | first-ranked changed |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for cat in ("drill", "spray_bottle", "mug"):
        v = [r for r in rows if r["category"] == cat]
        if not v:
            continue

        def err(r, key):
            return abs(r["hypotheses"][r[key]]["yaw_error_deg"])

        counts = [sum(err(r, k) <= 15 for r in v) for k in ("first_today", "first_coverage")]
        turned = [sum(err(r, k) > 45 for r in v) for k in ("first_today", "first_coverage")]
        changed = [r for r in v if r["first_today"] != r["first_coverage"]]
        print(f"| {cat} | {len(v)} | {counts[0]} | {counts[1]} | {turned[0]} | {turned[1]} | {len(changed)} |")
    print("\nChanged views (instance placement: yaw error today -> coverage; uncovered at 8 mm today -> coverage):")
    for r in rows:
        if r["first_today"] != r["first_coverage"]:
            a, b = r["hypotheses"][r["first_today"]], r["hypotheses"][r["first_coverage"]]
            print(f"  {r['category']} {r['instance']} {r['trial']}: {a['yaw_error_deg']:.0f} ->"
                  f" {b['yaw_error_deg']:.0f} deg; {a['uncovered'][1]} -> {b['uncovered'][1]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
