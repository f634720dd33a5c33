"""Every table of the session-48 reseed probe, from its committed files.

    python benchmarks/results/experiments/s48_reseed/tables.py [FILE.jsonl ...]
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def summary(path: Path) -> None:
    rows = [json.loads(line) for line in path.open()]
    print(f"\n{path.name}")
    print("| category | views | within 15 deg: today | reseed | turned round (> 45 deg): today | reseed | changed |"
          " a right hypothesis exists: today | reseed | median core time (ms): today | reseed |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for cat in sorted({r["category"] for r in rows}):
        sel = [r for r in rows if r["category"] == cat]

        def err(fit):
            return abs(fit["hypotheses"][fit["first"]]["yaw_error_deg"])

        def n(pred, key):
            return sum(pred(r[key]) for r in sel)

        exists = {k: n(lambda f: any(abs(h["yaw_error_deg"]) <= 15 for h in f["hypotheses"]), k)
                  for k in ("today", "reseed")}
        within = {k: n(lambda f: err(f) <= 15, k) for k in ("today", "reseed")}
        turned = {k: n(lambda f: err(f) > 45, k) for k in ("today", "reseed")}
        changed = [r for r in sel if abs(err(r["today"]) - err(r["reseed"])) > 1e-9]
        t = {k: 1e3 * statistics.median(r[k]["time_s"] for r in sel) for k in ("today", "reseed")}
        print(f"| {cat} | {len(sel)} | {within['today']} | {within['reseed']} | {turned['today']} | "
              f"{turned['reseed']} | {len(changed)} | {exists['today']} | {exists['reseed']} | {t['today']:.0f} | "
              f"{t['reseed']:.0f} |")
    print("Views whose first-ranked yaw error changed (instance placement: today -> reseed, deg):")
    for r in rows:
        a = r["today"]["hypotheses"][r["today"]["first"]]["yaw_error_deg"]
        b = r["reseed"]["hypotheses"][r["reseed"]["first"]]["yaw_error_deg"]
        if abs(abs(a) - abs(b)) > 1e-9:
            print(f"  {r['category']} {r['instance']} {r['trial']}: {a:.0f} -> {b:.0f}")


def main(argv=None) -> int:
    files = [Path(p) for p in (argv or sys.argv[1:])] or sorted(HERE.glob("*.jsonl"))
    for path in files:
        summary(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
