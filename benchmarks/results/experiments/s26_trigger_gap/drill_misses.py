"""Session 26 probe: where a drill's missed trigger is missed -- below it, on short triggers (no simulation).

    python benchmarks/results/experiments/s26_trigger_gap/drill_misses.py [--data out/benchmark/data]

Reads the committed benchmark records of the test split's drills (every method and view whose judge
reports where the index ended: "outside its box by ... z -D mm", object frame) and each drill's generator
parameters (the test split is generated again from its seed where absent; only read). Prints, per drill,
its trigger's height, its handle's tilt, the trials, the missed triggers and where the index ended.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

RECORDS = ("test_active+three.jsonl", "test_active_baselines.jsonl", "test_latent_fast.jsonl")
WHERE = re.compile(r"outside its box by ([^m]*) mm")


def main(argv=None) -> int:
    from catgrasp_drake.benchmark.runner import ensure_test_split

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT / "out" / "benchmark" / "data"))
    args = ap.parse_args(argv)
    root = ensure_test_split(args.data) / "drill"
    trials, misses = defaultdict(int), defaultdict(list)
    for name in RECORDS:
        lines = (ROOT / "benchmarks" / "results" / name).read_text().splitlines()[1:]
        for r in (json.loads(line) for line in lines if line.strip()):
            if r.get("category") != "drill":
                continue
            trials[r["instance"]] += 1
            if r["reason"] == "trigger_missed":
                m = WHERE.search(r["detail"] or "")
                misses[r["instance"]].append(m.group(1) if m else "?")
    print(f"records: {', '.join(RECORDS)}\n")
    print("| drill | trigger height (mm) | handle tilt (deg) | trials | trigger missed | where the index ended (mm) |")
    print("|---|---:|---:|---:|---:|---|")
    for instance in sorted(trials, key=lambda i: json.loads((root / i / "annotations.json").read_text())
                           ["params"]["trigger_height"]):
        p = json.loads((root / instance / "annotations.json").read_text())["params"]
        where = ", ".join(misses[instance]) or "-"
        print(f"| {instance} | {1000 * p['trigger_height']:.1f} | {p['handle_tilt_deg']:.1f} | {trials[instance]} | "
              f"{len(misses[instance])} | {where} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
