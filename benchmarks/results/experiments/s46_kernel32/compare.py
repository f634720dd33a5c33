"""Trial-by-trial agreement of two benchmark records files (same split, methods, placements).

    python compare.py BEFORE.jsonl AFTER.jsonl
"""

import sys

from catgrasp_drake.benchmark.report import load_benchmark_records
from catgrasp_drake.benchmark.runner import TRIAL_KEYS

MEASURED = ("scale", "pose_error_mm", "yaw_error_deg", "rise_m", "tilt_deg")


def load(path):
    """The file's records by their trial (``TRIAL_KEYS``: split, category, instance, trial, view, method, ...)."""
    return {tuple(r.get(k) for k in TRIAL_KEYS): r for r in load_benchmark_records(path)}


def main():
    a, b = load(sys.argv[1]), load(sys.argv[2])
    keys = sorted(set(a) & set(b))
    same = 0
    for k in keys:
        ra, rb = a[k], b[k]
        eq = all(ra[f] == rb[f] for f in ("grasp", "functional", "reason"))
        same += eq
        moved = {f: (ra[f], rb[f]) for f in MEASURED if ra.get(f) != rb.get(f)}
        print(ra["category"], ra["instance"], "same" if eq else "CHANGED", ra["functional"], rb["functional"],
              ra["reason"], rb["reason"], moved or "")
    print(f"{same}/{len(keys)} outcomes (grasp, functional, reason) agree; only in one file: {len(set(a) ^ set(b))}")
    for name, d in (("first", a), ("second", b)):
        print(name, "functional", sum(r["functional"] for r in d.values()), "of", len(d))


if __name__ == "__main__":
    main()
