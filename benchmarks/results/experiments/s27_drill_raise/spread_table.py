"""Session 27: the drill grasp raised, spread or searched, on the tuning sets (records only; this folder's tables).

    python benchmarks/results/experiments/s27_drill_raise/spread_table.py

Reads the ``diagrams/handwritten_sweep.py`` records in this folder (``spread_<S>_committed.json``: the 13
committed drills; ``spread_<S>_stress.json``: their 52 stretched copies, ``--split stress``;
``shift_<DZ>_stress.json``: the grasp moved DZ m up, ``--shift 0 0 DZ``; ``searched_<how>_*.json``: a grasp
file from ``catgrasp search-grasp``, probe 3 of ``plan.md``) and prints per variant the grasped
and functional counts, the failure reasons, where each missed trigger was missed (the judge's "outside its box
by ... z -D mm", object frame) and the functional count on the 44 stretched drills probe 3's searches
(``search_height.json``) did not run on. Then section 1's table: the committed drill model against the raised one
(``stress_up5.jsonl``) through the transfer diagram, latent functional and fitted scale per stress family.
"""

from __future__ import annotations

import json
import re
import sys
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.benchmark.report import load_benchmark_records  # noqa: E402
from catgrasp_drake.data.stretch import STRESS_FAMILIES  # noqa: E402

WHERE_Z = re.compile(r"z (-?[0-9.]+) mm")


def family(instance: str) -> str:
    """The stress family of a stretched copy's name (``drill_03_large`` -> ``large``)."""
    return instance.rsplit("_", 1)[-1]


def not_searched(path: Path, rows) -> str:
    """Functional count on the stretched drills probe 3's searches (``search_height.json``; the control searched
    the same ones) did not run on."""
    if "stress" not in path.stem:
        return "-"
    skip = set(json.loads((HERE / "search_height.json").read_text())["instances"])
    rest = [r for r in rows if r["instance"] not in skip]
    return f"{sum(r['functional'] for r in rest)} of {len(rest)}"


def latent_by_family() -> None:
    print("| model (`--split stress`, latent, single view) | functional, " + " / ".join(STRESS_FAMILIES)
          + " | fitted scale, min-max per family |")
    print("|---|---|---|")
    for name, path in (("committed", ROOT / "benchmarks" / "results" / "stress_drill.jsonl"),
                       ("raised 5 mm", HERE / "stress_up5.jsonl")):
        rows = [r for r in load_benchmark_records(path) if r["method"] == "latent" and r["category"] == "drill"]
        by = {f: [r for r in rows if family(r["instance"]) == f] for f in STRESS_FAMILIES}
        print(f"| {name} | " + " / ".join(str(sum(r["functional"] for r in by[f])) for f in STRESS_FAMILIES)
              + " | " + ", ".join(f"{f} {min(r['scale'] for r in by[f]):.2f}-{max(r['scale'] for r in by[f]):.2f}"
                                  for f in STRESS_FAMILIES) + " |")


def main() -> int:
    print("| record | trials | grasped | functional | functional " + " / ".join(STRESS_FAMILIES) + " | trigger missed "
          "(z of the miss, mm) | not lifted | other failures | functional where probe 3 did not search |")
    print("|---|---:|---:|---:|---|---|---:|---|---|")
    for path in sorted([*HERE.glob("spread_*.json"), *HERE.glob("shift_*.json"), *HERE.glob("searched_*.json")]):
        rows = json.loads(path.read_text())
        reasons = Counter(r["reason"] for r in rows)
        missed = [WHERE_Z.search(r.get("detail") or "") for r in rows if r["reason"] == "trigger_missed"]
        zs = ", ".join(m.group(1) if m else "?" for m in missed) or "-"
        shown = (None, "trigger_missed", "not_lifted")
        other = ", ".join(f"{k} {v}" for k, v in sorted(reasons.items(), key=lambda kv: str(kv[0]))
                          if k not in shown) or "-"
        families = " / ".join(str(sum(r["functional"] for r in rows if family(r["instance"]) == f))
                              for f in STRESS_FAMILIES) if "stress" in path.stem else "-"
        print(f"| {path.stem} | {len(rows)} | {sum(r['grasp'] for r in rows)} | {sum(r['functional'] for r in rows)} "
              f"| {families} | {reasons['trigger_missed']} ({zs}) | {reasons['not_lifted']} | {other} "
              f"| {not_searched(path, rows)} |")
    print()
    latent_by_family()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
