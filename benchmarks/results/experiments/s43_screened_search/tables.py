"""Session 43: the figures of this folder's README, from its committed records.

    python benchmarks/results/experiments/s43_screened_search/tables.py

- per search record (``search_first.json``, ``search_redraw.json``): the start and best robustness, each round's
  candidate scores, the screen's drawn/refused counts, and per search bottle the functional trials over all
  simulated candidates;
- the two grasps on the 17 shrouded bottles (``shroud_all_landed.json``, ``shroud_all_s17.json``): lifted,
  functional, failure reasons and functional per bottle.
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent


def search_summary(path: Path) -> None:
    d = json.loads(path.read_text())
    print(f"{path.name}: robustness {d['start_score']:.2f} -> {d['best_score']:.2f}, {d['trials']} trials, "
          f"{d['wall_s'] / 60:.0f} min; screened (drawn/refused) per round: "
          + (", ".join(f"{s['drawn']}/{s['infeasible']}" for s in d.get("screened", [])) or "-"))
    per_bottle = defaultdict(lambda: [0, 0])
    for k, candidates in enumerate(d["rounds"], 1):
        scores = sorted((c["score"] for c in candidates), reverse=True)
        refused = sum(bool(c.get("screen_refused")) for c in candidates)
        print(f"  round {k}: scores {', '.join(f'{s:.2f}' for s in scores)}; refused {refused}")
        for c in candidates:
            for t in c["trials"]:
                per_bottle[t["instance"]][0] += bool(t["functional"])
                per_bottle[t["instance"]][1] += 1
    print("  functional per search bottle, all candidates: "
          + ", ".join(f"{i.removeprefix('spray_bottle_')} {a}/{n}" for i, (a, n) in per_bottle.items()))


def sweep_summary(path: Path) -> None:
    records = json.loads(path.read_text())
    reasons = Counter(r["reason"] for r in records if not r["functional"])
    per_bottle = defaultdict(int)
    for r in records:
        per_bottle[r["instance"].removeprefix("spray_bottle_").removesuffix("_shroud")] += bool(r["functional"])
    print(f"{path.name}: lifted {sum(bool(r['grasp']) for r in records)}/{len(records)}, functional "
          f"{sum(bool(r['functional']) for r in records)}/{len(records)}; failures {dict(reasons)}")
    print("  functional per bottle: " + ", ".join(f"{b} {n}" for b, n in per_bottle.items()))


def main() -> None:
    for name in ("search_first.json", "search_redraw.json"):
        search_summary(HERE / name)
    for name in ("shroud_all_landed.json", "shroud_all_s17.json"):
        sweep_summary(HERE / name)


if __name__ == "__main__":
    main()
