"""Session 42: the check's functional counts and failures per grasp and set, from check.sh's JSON records.

    python benchmarks/results/experiments/s42_shroud_search/check_table.py [DIR]   # default: this folder's check/
"""

from __future__ import annotations

import json
import sys
from collections import Counter
from pathlib import Path

SETS = ("plain_committed", "plain_val", "shroud")


def main(directory: str = str(Path(__file__).resolve().parent / "check")) -> None:
    d = Path(directory)
    labels = sorted({p.stem.split("_")[-1] for p in d.glob("*.json")})
    print(f"{'grasp':10s} " + " ".join(f"{s:>16s}" for s in SETS) + "   failures")
    for label in labels:
        cells, reasons = [], Counter()
        for s in SETS:
            records = json.loads((d / f"{s}_{label}.json").read_text())
            cells.append(f"{sum(r['functional'] for r in records)}/{len(records)}")
            reasons.update(f"{r['instance'].removeprefix('spray_bottle_')} {r['reason']}"
                           for r in records if not r["functional"])
        print(f"{label:10s} " + " ".join(f"{c:>16s}" for c in cells) + "   "
              + ", ".join(f"{k} x{n}" if n > 1 else k for k, n in sorted(reasons.items())))


if __name__ == "__main__":
    main(*sys.argv[1:2])
