"""Session 36: on the fresh seeds, how a spray bottle's trigger gap goes with the latent method's missed triggers.

    python benchmarks/results/experiments/s36_third_seed/spray_gaps.py [--data out/benchmark/data]

Measurement only (no simulation, nothing chosen from it): reads the committed fresh-split records
(``benchmarks/results/fresh_seed*.jsonl``) and the generator parameters of the bottles they ran on (each seed's
instances generated again on demand, as the benchmark does), and counts, per trigger-gap band (the space
between trigger and neck, ``params.trigger_gap``), the trials and the ``trigger_missed`` ones of each method.
The index's distal capsule is 17.2 mm thick (session 26): a wider gap takes the fingertip.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.benchmark.report import load_benchmark_records  # noqa: E402
from catgrasp_drake.benchmark.runner import ensure_fresh_split  # noqa: E402

GAP_BANDS_MM = ((0, 14), (14, 17.2), (17.2, 99))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT / "out" / "benchmark" / "data"))
    args = ap.parse_args(argv)
    records = [r for r in load_benchmark_records(sorted((ROOT / "benchmarks" / "results").glob("fresh_seed*.jsonl")))
               if r["category"] == "spray_bottle" and r["view"] == "single" and r["physics"] == "default"]
    gaps = {}
    for seed in sorted({r["data_seed"] for r in records}):
        root = ensure_fresh_split(args.data, seed, "spray_bottle") / "spray_bottle"
        for d in sorted(p for p in root.iterdir() if p.is_dir()):
            gaps[(seed, d.name)] = 1000 * json.loads((d / "annotations.json").read_text())["params"]["trigger_gap"]
    cells = defaultdict(lambda: [0, 0, 0, set()])  # trials, functional, trigger missed, bottles
    for r in records:
        gap = gaps[(r["data_seed"], r["instance"])]
        band = next(b for b in GAP_BANDS_MM if b[0] <= gap < b[1])
        c = cells[(band, r["method"])]
        c[0] += 1
        c[1] += bool(r["functional"])
        c[2] += r["reason"] == "trigger_missed"
        c[3].add((r["data_seed"], r["instance"]))
    seeds = ", ".join(str(s) for s in sorted({r["data_seed"] for r in records}))
    print(f"fresh seeds {seeds}: spray bottles, single view\n")
    print("| trigger gap (mm) | method | bottles | trials | functional | trigger missed |")
    print("|---|---|---:|---:|---:|---:|")
    for band in GAP_BANDS_MM:
        for method in ("latent", "paper", "nearest", "rigid"):
            if (band, method) in cells:
                n, f, m, bottles = cells[(band, method)]
                print(f"| {band[0]:g}–{band[1]:g} | {method} | {len(bottles)} | {n} | {f} ({100 * f / n:.0f} %) | "
                      f"{m} ({100 * m / n:.0f} %) |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
