"""Session 37: the validation drills' benchmark outcomes beside the probe's geometry of the same trials.

    python benchmarks/results/experiments/s37_val_drills/outcomes.py [RECORDS] [PROBE]

RECORDS: ``benchmarks/results/val_drill.jsonl`` (``catgrasp benchmark --split val --categories drill``);
PROBE: this folder's ``probe.jsonl`` (``probe.py``). Printed: per method, the failure reasons, and the outcome by
the predicted functional point's height above the true trigger centre (dz, mm) and by the fit's height ratio.
Validation split: a TUNING set.
"""

from __future__ import annotations

import collections
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]

DZ_BINS_MM = (-99.0, -4.0, -2.0, 0.0, 2.0, 4.0, 6.0, 99.0)


def read_jsonl(path):
    rows = [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]
    return [r for r in rows if "method" in r]  # a records file's first line is its header


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    records = read_jsonl(argv[0] if argv else ROOT / "benchmarks/results/val_drill.jsonl")
    probe = {(r["instance"], r["trial"], r["method"]): r
             for r in read_jsonl(argv[1] if len(argv) > 1 else HERE / "probe.jsonl")}
    for method in sorted({r["method"] for r in records}):
        mine = [r for r in records if r["method"] == method]
        print(f"{method}: functional {sum(r['functional'] for r in mine)}/{len(mine)}, grasped "
              f"{sum(r['grasp'] for r in mine)}; reasons {dict(collections.Counter(r['reason'] for r in mine))}")
        bins = collections.defaultdict(lambda: [0, 0])
        for r in mine:
            g = probe.get((r["instance"], r["trial"], method))
            if g is None:
                continue
            dz = g["trigger_error_mm"][2]
            lo = max(b for b in DZ_BINS_MM if b <= dz)
            bins[lo][0] += r["functional"]
            bins[lo][1] += 1
        print("   dz from (mm): " + ", ".join(f"{lo:+.0f}: {k}/{n}" for lo, (k, n) in sorted(bins.items())))
        per = collections.defaultdict(list)
        for r in mine:
            per[r["instance"]].append("F" if r["functional"] else (r["reason"] or "?")[:6])
        print("   " + "; ".join(f"{i} {' '.join(v)}" for i, v in sorted(per.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
