"""Session 26 probe: is a spray bottle's missed trigger the index finger on the neck, across the trigger gap?

    python benchmarks/results/experiments/s26_trigger_gap/gap_vs_miss.py [--data out/benchmark/data]

Reads committed benchmark records only (no simulation) and the objects they ran on: the generated test split
(made again from its seed where absent, as the benchmark does), the committed instances and the stress split's
stretched copies. For every spray-bottle trial the judge failed as ``trigger_missed`` with the index's nearest
contact straight behind the trigger box (its detail "outside its box by y -D mm", object frame), it compares D
with the bottle's trigger gap (``params.trigger_gap``: the space between the trigger and the neck, mm; a
stretched copy's is its source's times the stretch in y). Prints, per record file and method, how many
trials missed that way and how many of them ended within 1.5 mm of the gap: the fingertip on the neck, where the
trigger gap ends; then, per bottle, the gap and the misses.
"""

from __future__ import annotations

import argparse
import functools
import json
import re
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

RECORDS = ("test_spray_bottle.jsonl", "test_true_object.jsonl", "test_active+three.jsonl",
           "stress_spray_bottle+mug.jsonl", "ycb.jsonl")
BEHIND = re.compile(r"outside its box by (?:x [-+][\d.]+ )?y -([\d.]+)")
GAP_BINS = ((0, 13), (13, 16), (16, 18), (18, 99))
ON_NECK_MM = 1.5  # |miss - gap| within this: the fingertip ended on the neck behind the gap


def records(name):
    lines = (ROOT / "benchmarks" / "results" / name).read_text().splitlines()
    return [json.loads(line) for line in lines[1:] if line.strip()]


@functools.lru_cache(maxsize=None)  # (one bottle's files read once, not once per trial)
def trigger_gap_mm(split, instance, data):
    """The bottle's trigger gap (mm) from its generator parameters, or None (a scan: no parameters)."""
    from catgrasp_drake.benchmark.runner import ensure_test_split

    if split == "test":
        path = ensure_test_split(data) / "spray_bottle" / instance / "annotations.json"
    elif split == "stress":
        stretched = json.loads((Path(data) / "stress" / "spray_bottle" / instance / "annotations.json").read_text())
        source = ROOT / "models" / "objects" / "spray_bottle" / stretched["stretched_from"] / "annotations.json"
        return 1000 * json.loads(source.read_text())["params"]["trigger_gap"] * stretched["stretch"][1]
    else:
        return None
    return 1000 * json.loads(path.read_text())["params"]["trigger_gap"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT / "out" / "benchmark" / "data"))
    args = ap.parse_args(argv)
    from catgrasp_drake.benchmark.runner import stretched_objects
    from catgrasp_drake.data.dataset import list_instances
    from catgrasp_drake.data.stretch import STRESS_FAMILIES

    stretched_objects(Path(args.data) / "stress", "spray_bottle", list_instances("spray_bottle"),
                      list(STRESS_FAMILIES))  # made once, as the benchmark does
    per_bottle = defaultdict(lambda: {"trials": 0, "misses": []})
    print("| records | method | view | trials | trigger missed | of them straight behind the box | "
          f"of those, on the neck (miss within {ON_NECK_MM} mm of the gap) |")
    print("|---|---|---|---:|---:|---:|---:|")
    for name in RECORDS:
        groups = defaultdict(lambda: [0, 0, 0, 0])
        for r in records(name):
            if r.get("category") != "spray_bottle":
                continue
            g = groups[(r["method"], r.get("view", "single"))]
            g[0] += 1
            gap = trigger_gap_mm(r["split"], r["instance"], args.data)
            key = (r["split"], r["instance"], round(gap, 1) if gap is not None else None)
            per_bottle[key]["trials"] += 1
            if r["reason"] != "trigger_missed":
                continue
            g[1] += 1
            m = BEHIND.search(r["detail"] or "")
            if m is None:
                per_bottle[key]["misses"].append("elsewhere")
                continue
            miss = float(m.group(1))
            g[2] += 1
            per_bottle[key]["misses"].append(miss)
            if gap is not None and abs(miss - gap) <= ON_NECK_MM:
                g[3] += 1
        for (method, view), (n, missed, behind, neck) in sorted(groups.items()):
            print(f"| {name} | {method} | {view} | {n} | {missed} | {behind} | {neck} |")
    print("\n| split | trigger gap (mm) | bottles | trials | trigger missed | on the neck (within 1.5 mm of the gap) |")
    print("|---|---|---:|---:|---:|---:|")
    for split in ("test", "stress"):
        for lo, hi in GAP_BINS:
            sel = [(k, v) for k, v in per_bottle.items() if k[0] == split and k[2] is not None and lo <= k[2] < hi]
            if not sel:
                continue
            misses = [m for _, v in sel for m in v["misses"]]
            neck = sum(isinstance(m, float) and abs(m - k[2]) <= ON_NECK_MM for k, v in sel for m in v["misses"])
            print(f"| {split} | {lo:g}-{hi:g} | {len(sel)} | {sum(v['trials'] for _, v in sel)} | {len(misses)} | "
                  f"{neck} |")
    print("\n| split | bottle | trigger gap (mm) | trials | misses: D (mm) behind the box |")
    print("|---|---|---:|---:|---|")
    for (split, instance, gap), v in sorted(per_bottle.items(), key=lambda kv: (kv[0][0], -(kv[0][2] or 0))):
        if split == "stress" and not v["misses"]:
            continue
        misses = sorted(v["misses"], key=str)
        shown = ", ".join(f"{m:.1f}" if isinstance(m, float) else m for m in misses) or "-"
        print(f"| {split} | {instance} | {gap if gap is not None else '-'} | {v['trials']} | {shown} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
