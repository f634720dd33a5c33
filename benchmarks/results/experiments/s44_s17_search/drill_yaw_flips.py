"""Session 44 observation: drills the fit turns round (yaw error > 45 deg), per method and committed record file.

    python benchmarks/results/experiments/s44_s17_search/drill_yaw_flips.py

Reads the committed benchmark records only (no simulation). Per file with drill trials of ``paper`` and
``latent``: trials, turned round, functional among those; then the paired trials (same instance and placement)
that only one of the two makes functional.
"""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(REPO))

from catgrasp_drake.benchmark.report import load_benchmark_records  # noqa: E402

FLIP_DEG = 45.0
METHODS = ("latent", "paper")


def main() -> None:
    totals = {m: [0, 0] for m in METHODS}
    for path in sorted((REPO / "benchmarks" / "results").glob("*.jsonl")):
        drills = [r for r in load_benchmark_records(path) if r["category"] == "drill" and r["method"] in METHODS]
        if {r["method"] for r in drills} != set(METHODS):
            continue
        by = {(r["instance"], r["trial"], r["method"]): r for r in drills}
        cells = []
        for m in METHODS:
            rs = [r for r in drills if r["method"] == m]
            flips = [r for r in rs if r.get("yaw_error_deg") is not None and abs(r["yaw_error_deg"]) > FLIP_DEG]
            totals[m][0] += len(flips)
            totals[m][1] += len(rs)
            cells.append(f"{m} {len(flips)}/{len(rs)} turned round ({sum(r['functional'] for r in flips)} functional)")
        pairs = [k[:2] for k in by if k[2] == "paper" and k[:2] + ("latent",) in by]
        only = {m: sum(by[p + (m,)]["functional"] and not by[p + (o,)]["functional"] for p in pairs)
                for m, o in (("latent", "paper"), ("paper", "latent"))}
        print(f"{path.name}: " + "; ".join(cells)
              + f"; paired {len(pairs)}: functional only with latent {only['latent']}, only with paper {only['paper']}")
    print("all: " + "; ".join(f"{m} {f}/{n} turned round" for m, (f, n) in totals.items()))


if __name__ == "__main__":
    main()
