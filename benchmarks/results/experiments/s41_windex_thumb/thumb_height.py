"""Where the thumb first meets each spray bottle, against where the index does: a hand_fit --closing JSON, tabled.

    python diagrams/hand_fit.py --categories spray_bottle --objects out/ycb/spray_bottle/ycb_022 \
        out/benchmark/data/val_seed902870906/spray_bottle/*/ out/benchmark/data/stress/spray_bottle/*/ \
        --closing --json FILE
    python benchmarks/results/experiments/s41_windex_thumb/thumb_height.py FILE

Kinematic only (the preshaped hand stepped to closed against the true mesh, no simulation). Per object: the
height of the thumb's first contact minus the index's (mm, the object's canonical z), and how far into the
closing the thumb arrives. Prints the objects whose thumb arrives within 15 mm of the index's height, and
per set (committed, YCB, val, stress) how many objects the thumb meets at all.
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict


def set_of(row: dict, index: int, committed: int) -> str:
    if "ycb" in row["object"]:
        return "ycb"
    if index < committed:
        return "committed"
    return "stress" if row["object"].count("_") > 2 else "val"


def main(path: str) -> None:
    rows = json.load(open(path))
    committed = next(i for i, r in enumerate(rows) if "ycb" in r["object"] or r["object"].count("_") > 2
                     or (i > 0 and r["object"] == rows[0]["object"]))
    counts = defaultdict(lambda: [0, 0, 0])  # objects, thumb meets it, thumb within 15 mm of the index
    print(f"{'set':10s} {'object':26s} {'thumb z - index z (mm)':>24s} {'thumb arrives at':>18s}")
    for i, row in enumerate(rows):
        first = {c["finger"]: c for c in row["closing"]}
        thumb, index = first["thumb"], first["index"]
        name = set_of(row, i, committed)
        counts[name][0] += 1
        if thumb["point_mm"] is None or index["point_mm"] is None:
            continue
        counts[name][1] += 1
        dz = thumb["point_mm"][2] - index["point_mm"][2]
        if dz > -15:
            counts[name][2] += 1
            print(f"{name:10s} {row['object']:26s} {dz:24.0f} {100 * thumb['fraction']:17.0f}%")
    print()
    print(f"{'set':10s} {'objects':>8s} {'thumb meets it':>15s} {'thumb within 15 mm of the index height':>40s}")
    for name, (n, met, high) in counts.items():
        print(f"{name:10s} {n:8d} {met:15d} {high:40d}")


if __name__ == "__main__":
    main(sys.argv[1])
