"""Session 47: every table of this folder's README (``python benchmarks/results/experiments/s47_coverage/tables.py``).

The mug diagnosis from the committed held-out records, the validation probe (step 1) and the held-out probe
(step 3). The simulated before/after tables compare committed records files (README: ``compare.py``).
"""

from __future__ import annotations

import glob
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parents[1]
sys.path.insert(0, str(HERE.parents[2]))


def views(path):
    return [json.loads(line) for line in open(path)] if path.exists() else []


def functional_azimuth_deg(record) -> float:
    """The object's functional direction (+y of O) against the direction to the camera, about z (0: facing it)."""
    return (record["placement"]["yaw_deg"] + 90 - record["camera"]["azimuth_deg"] + 180) % 360 - 180


def mug_diagnosis() -> None:
    """Why: single-view latent mugs of the committed held-out records (test + the four fresh seeds)."""
    from catgrasp_drake.benchmark.report import load_benchmark_records

    files = [RESULTS / "test_mug.jsonl"] + [Path(p) for p in sorted(glob.glob(str(RESULTS / "fresh_seed*.jsonl")))
                                            if "active" not in p]
    mugs = [r for f in files for r in load_benchmark_records(f) if r["method"] == "latent"
            and r["category"] == "mug" and r.get("view", "single") == "single"]
    near = [r for r in mugs if abs(r["yaw_error_deg"]) <= 5]
    far = [r for r in mugs if r["yaw_error_deg"] > 15 or r["yaw_error_deg"] < -45]
    profile = [r for r in mugs if 40 <= abs(functional_azimuth_deg(r)) <= 100 and abs(r["yaw_error_deg"]) > 45]
    print(f"Held-out single-view latent mugs: {len(mugs)} trials; yaw error within 5 deg: "
          f"{sum(r['functional'] for r in near)} of {len(near)} functional; beyond +15 or -45 deg: "
          f"{sum(r['functional'] for r in far)} of {len(far)}; handle 40-100 deg to the side of the view yet fitted "
          f"more than 45 deg off: {len(profile)} (" + ", ".join(f"{abs(r['yaw_error_deg']):.0f}" for r in profile)
          + " deg)\n")


def heldout_probe() -> None:
    """Step 3: the probe on the held-out drill views (``heldout_*.jsonl``)."""
    print("\n| held-out views | views | first-ranked turned round: before | after | changed |")
    print("|---|---:|---:|---:|---|")
    for path in sorted(HERE.glob("heldout_*.jsonl")):
        rows = views(path)
        turned = [sum(abs(r["hypotheses"][r[k]]["yaw_error_deg"]) > 45 for r in rows)
                  for k in ("first_today", "first_coverage")]
        changed = ", ".join(f"{r['instance']} {r['trial']} ({r['hypotheses'][r['first_today']]['yaw_error_deg']:.0f}"
                            f" -> {r['hypotheses'][r['first_coverage']]['yaw_error_deg']:.0f} deg)"
                            for r in rows if r["first_today"] != r["first_coverage"])
        print(f"| {path.stem[len('heldout_'):]} | {len(rows)} | {turned[0]} | {turned[1]} | {changed or '-'} |")


def main() -> int:
    mug_diagnosis()
    rows = views(HERE / "val_mug.jsonl") + views(HERE / "val_drill+spray_bottle.jsonl")
    print("| category | views | first-ranked within 15 deg: today | coverage | turned round (> 45 deg): today"
          " | coverage | first-ranked changed |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for cat in ("drill", "spray_bottle", "mug"):
        v = [r for r in rows if r["category"] == cat]
        if not v:
            continue

        def err(r, key):
            return abs(r["hypotheses"][r[key]]["yaw_error_deg"])

        counts = [sum(err(r, k) <= 15 for r in v) for k in ("first_today", "first_coverage")]
        turned = [sum(err(r, k) > 45 for r in v) for k in ("first_today", "first_coverage")]
        changed = [r for r in v if r["first_today"] != r["first_coverage"]]
        print(f"| {cat} | {len(v)} | {counts[0]} | {counts[1]} | {turned[0]} | {turned[1]} | {len(changed)} |")
    print("\nChanged views (instance placement: yaw error today -> coverage; uncovered at 8 mm today -> coverage):")
    for r in rows:
        if r["first_today"] != r["first_coverage"]:
            a, b = r["hypotheses"][r["first_today"]], r["hypotheses"][r["first_coverage"]]
            print(f"  {r['category']} {r['instance']} {r['trial']}: {a['yaw_error_deg']:.0f} ->"
                  f" {b['yaw_error_deg']:.0f} deg; {a['uncovered'][1]} -> {b['uncovered'][1]}")
    heldout_probe()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
