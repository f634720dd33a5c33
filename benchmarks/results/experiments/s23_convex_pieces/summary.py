"""Summarise the convex-pieces probe: real-time rate and outcomes per collision mode, agreement with ``mesh``.

    python benchmarks/results/experiments/s23_convex_pieces/summary.py [results.jsonl]
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    path = Path(argv[0]) if argv else Path(__file__).with_name("results.jsonl")
    rows = defaultdict(list)
    for line in path.read_text().splitlines():
        r = json.loads(line)
        rows[r["mode"]].append(r)
    base = {(r["instance"], r["seed"], r["repeat"]): r for r in rows["mesh"]}
    print("| collision geometry | trials | median real-time rate | grasped | functional | same outcome as mesh |")
    print("|---|---:|---:|---:|---:|---:|")
    for mode in ("mesh", "rigid", "compliant"):
        rs = rows[mode]
        rate = np.median([r["sim_time_s"] / r["wall_time_s"] for r in rs])
        same = sum(1 for r in rs if (b := base[(r["instance"], r["seed"], r["repeat"])])["grasp"] == r["grasp"]
                   and b["functional"] == r["functional"])
        print(f"| {mode} | {len(rs)} | {rate:.2f}x | {sum(r['grasp'] for r in rs)} | "
              f"{sum(r['functional'] for r in rs)} | {same}/{len(rs)} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
