"""Every table of the session-48 handle-support probe, from its committed files.

    python benchmarks/results/experiments/s48_handle_support/tables.py [FILE.jsonl ...]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def summary(path: Path) -> None:
    rows = [json.loads(line) for line in path.open()]

    def err(r, key):
        return abs(r["hypotheses"][r[key]]["yaw_error_deg"])

    within = {k: sum(err(r, k) <= 15 for r in rows) for k in ("first_today", "first_support")}
    turned = {k: sum(err(r, k) > 45 for r in rows) for k in ("first_today", "first_support")}
    oracle = sum(any(abs(h["yaw_error_deg"]) <= 15 for h in r["hypotheses"]) for r in rows)
    changed = [r for r in rows if r["first_today"] != r["first_support"]]
    print(f"\n{path.name}: {len(rows)} views; a hypothesis within 15 deg exists in {oracle}")
    print("| first-ranked within 15 deg: today | E - 5 S8 | turned round (> 45 deg): today | E - 5 S8 | changed |")
    print("|---:|---:|---:|---:|---:|")
    print(f"| {within['first_today']} | {within['first_support']} | {turned['first_today']} | "
          f"{turned['first_support']} | {len(changed)} |")
    print("Changed views (instance placement: yaw error today -> E - 5 S8; support at 8 mm today -> E - 5 S8;"
          " handle azimuth):")
    for r in changed:
        a, b = r["hypotheses"][r["first_today"]], r["hypotheses"][r["first_support"]]
        print(f"  {r['instance']} {r['trial']}: {a['yaw_error_deg']:.0f} -> {b['yaw_error_deg']:.0f} deg; "
              f"{a['support'][1]} -> {b['support'][1]}; {r['functional_azimuth_deg']:.0f} deg")


def main(argv=None) -> int:
    files = [Path(p) for p in (argv or sys.argv[1:])] or sorted(HERE.glob("*.jsonl"))
    for path in files:
        summary(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
