"""Session 27: the hand-written drill grasp with its fingers spread or moved in z, on the tuning sets (records only).

    python benchmarks/results/experiments/s27_drill_raise/spread_table.py

Reads the ``diagrams/handwritten_sweep.py`` records in this folder (``spread_<S>_committed.json``: the 13
committed drills; ``spread_<S>_stress.json``: their 52 stretched copies, ``--split stress``;
``shift_<DZ>_stress.json``: the grasp moved DZ m up, ``--shift 0 0 DZ``; ``searched_<how>_*.json``: a grasp
file from ``catgrasp search-grasp``, probe 3 of ``plan.md``) and prints per variant the grasped
and functional counts, the failure reasons, and where each missed trigger was missed
(the judge's "outside its box by ... z -D mm", object frame).
"""

from __future__ import annotations

import json
import re
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
FAMILIES = ("small", "large", "thin", "deep")  # the stress split's stretches, 13 drills each
WHERE_Z = re.compile(r"z (-?[0-9.]+) mm")


def main() -> int:
    print("| record | trials | grasped | functional | functional small / large / thin / deep | trigger missed (z of "
          "the miss, mm) | not lifted | other failures |")
    print("|---|---:|---:|---:|---|---|---:|---|")
    for path in sorted([*HERE.glob("spread_*.json"), *HERE.glob("shift_*.json"), *HERE.glob("searched_*.json")]):
        rows = json.loads(path.read_text())
        reasons = Counter(r["reason"] for r in rows)
        missed = [WHERE_Z.search(r.get("detail") or "") for r in rows if r["reason"] == "trigger_missed"]
        zs = ", ".join(m.group(1) if m else "?" for m in missed) or "-"
        shown = (None, "trigger_missed", "not_lifted")
        other = ", ".join(f"{k} {v}" for k, v in sorted(reasons.items(), key=lambda kv: str(kv[0]))
                          if k not in shown) or "-"
        families = " / ".join(str(sum(r["functional"] for r in rows if r["instance"].endswith("_" + f)))
                              for f in FAMILIES) if "stress" in path.stem else "-"
        print(f"| {path.stem} | {len(rows)} | {sum(r['grasp'] for r in rows)} | {sum(r['functional'] for r in rows)} "
              f"| {families} | {reasons['trigger_missed']} ({zs}) | {reasons['not_lifted']} | {other} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
