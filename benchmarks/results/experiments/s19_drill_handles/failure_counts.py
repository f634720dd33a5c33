"""Why trials were not grasped, counted from benchmark records.

    python benchmarks/results/experiments/s19_drill_handles/failure_counts.py FILE [FILE ...]
        [--methods latent latent_map paper nearest]

Per records file, over the given methods' trials: how many were not grasped, by reason, with plans refused
before closing split into pregrasp collisions and hands in the table, and not-lifted trials that ended
tilted more than 60 deg.
"""

from __future__ import annotations

import argparse
import collections

from catgrasp_drake.benchmark.report import load_benchmark_records


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--methods", nargs="+", default=["latent", "latent_map", "paper", "nearest"])
    a = ap.parse_args()
    for path in a.files:
        trials = [r for r in load_benchmark_records(path) if r["method"] in a.methods]
        missed = [r for r in trials if not r["grasp"]]
        reasons = collections.Counter(r["reason"] for r in missed)
        refused = [r["detail"] for r in missed if r["reason"] == "collision_before_closing"]
        tilted = sum(r["reason"] == "not_lifted" and r["tilt_deg"] > 60 for r in missed)
        print(f"{path}: {len(missed)} of {len(trials)} not grasped; {dict(reasons)}")
        print(f"  refused before closing: {sum('pregrasp' in d for d in refused)} at the pregrasp, "
              f"{sum('table' in d for d in refused)} in the table; not lifted and tilted > 60 deg: {tilted}")


if __name__ == "__main__":
    main()
