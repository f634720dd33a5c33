"""Session 44: the figures of this folder's README, from its committed records.

    python benchmarks/results/experiments/s44_s17_search/tables.py

- the search (``search.json``): start and best robustness, each round's scores, the screen's counts and the
  functional trials per search bottle (session 43's ``search_summary``), the best candidate's variation, then per
  candidate its functional trials on the 6 plain and the 6 shrouded search bottles and its shrouded failures;
- the check (``check/``), beside the landed grasp's (session 42's records): session 42's ``check_table.py``.
"""

from __future__ import annotations

import importlib.util
import json
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _sibling(folder: str, name: str):
    """Another experiment folder's script ``folder/name.py``, loaded as a module (the folders are not packages)."""
    spec = importlib.util.spec_from_file_location(f"{folder}_{name}", HERE.parent / folder / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def candidates_by_kind(path: Path) -> None:
    d = json.loads(path.read_text())
    print("per candidate: score; functional plain / shrouded (of 12 each); shrouded failures")
    for k, candidates in enumerate(d["rounds"], 1):
        for c in sorted(candidates, key=lambda c: -c["score"]):
            if not c["trials"]:
                print(f"  round {k}: {c['score']:.2f}; refused by the screen on {', '.join(c['screen_refused'])}")
                continue
            shroud = [t for t in c["trials"] if t["instance"].endswith("_shroud")]
            plain = [t for t in c["trials"] if not t["instance"].endswith("_shroud")]
            reasons = Counter(t["reason"] for t in shroud if not t["functional"])
            print(f"  round {k}: {c['score']:.2f}; {sum(t['functional'] for t in plain)} / "
                  f"{sum(t['functional'] for t in shroud)}; {dict(reasons)}")


def main() -> None:
    _sibling("s43_screened_search", "tables").search_summary(HERE / "search.json")
    print(f"best variation: {json.loads((HERE / 'search.json').read_text())['best']}")
    candidates_by_kind(HERE / "search.json")
    check_table = _sibling("s42_shroud_search", "check_table")
    print("check: this search's grasp ('searched'), then session 42's records (the landed grasp's)")
    for directory in (HERE / "check", HERE.parent / "s42_shroud_search" / "check"):
        check_table.main(str(directory))


if __name__ == "__main__":
    main()
