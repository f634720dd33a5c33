"""Speed levers with their fidelity guard: the same reference trials at the default and at faster settings.

    python benchmarks/bench_fidelity.py [--hint 0.010] [--workers 2] [--json out/fidelity.json]

The reference set (>= 60 trials, successes and failures, three categories):
the hand-written grasp on every committed instance (13 drills, 17 spray
bottles, 15 mugs) and the same grasp moved 1 cm forward on the first five of
each category (which fail more often). Every trial is run at the default
plant settings and at each lever (``--hint``: the hand's hydroelastic
resolution hint, m, replacing the model's 6 mm). Printed per setting: wall
time of the whole set on the workers, the median real-time rate of a trial
(simulated / wall seconds of one core), and the agreement with the default
(grasp and functional outcome both equal) -- issue 17's guard is >= 95 %.
Trials run as tasks of ``catgrasp_drake.runner.run_tasks`` (no cache: each
run measures).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "diagrams"))

CATEGORIES = ("drill", "spray_bottle", "mug")
SHIFTED_PER_CATEGORY = 5
SHIFT_O = (0.0, 0.01, 0.0)


def fidelity_task(spec: dict) -> dict:
    """One reference trial at one setting -> outcome and timing (module level: runs in workers)."""
    from handwritten_sweep import varied

    from catgrasp_drake.station.handwritten import load_handwritten_motion
    from catgrasp_drake.station.scenario import load_scenario, with_instance
    from catgrasp_drake.trial import run_grasp_trial

    category, instance = spec["category"], spec["instance"]
    base = with_instance(load_scenario(f"{category}_default"), instance)
    scenario = base.replace(plant=replace(base.plant, hand_resolution_hint=spec["hint"]))
    motion = load_handwritten_motion(category, instance)
    if spec["shifted"]:
        motion = varied(motion, category, instance, SHIFT_O, (0.0, 0.0, 0.0))
    t0 = time.perf_counter()
    r = run_grasp_trial(scenario, motion)
    return {"grasp": r.grasp_success, "functional": r.functional_success, "reason": r.failure_reason,
            "sim_s": r.sim_time_s, "wall_s": time.perf_counter() - t0}


def reference_set() -> list[dict]:
    from catgrasp_drake.data.dataset import list_instances

    out = []
    for category in CATEGORIES:
        names = list_instances(category)
        out += [{"category": category, "instance": n, "shifted": False} for n in names]
        out += [{"category": category, "instance": n, "shifted": True} for n in names[:SHIFTED_PER_CATEGORY]]
    return out


def main(argv=None) -> int:
    from catgrasp_drake.runner import run_tasks

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hint", type=float, nargs="+", default=[0.010], help="hand resolution hints to try (m)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default=None, help="also write every trial's outcome here")
    args = ap.parse_args(argv)

    trials = reference_set()
    settings = [None] + list(args.hint)
    results = {}
    for hint in settings:
        specs = [t | {"hint": hint} for t in trials]
        t0 = time.perf_counter()
        outcomes = run_tasks(fidelity_task, specs, cache_dir=None, code_version="fidelity", workers=args.workers)
        results[hint] = ([o.result for o in outcomes], time.perf_counter() - t0)
        print(f"setting hint={hint}: {len(specs)} trials in {results[hint][1]:.0f} s", file=sys.stderr, flush=True)

    base, _ = results[None]
    print(f"reference set: {len(trials)} trials (hand-written grasp on every committed instance, and moved "
          f"{SHIFT_O[1] * 100:.0f} cm on {SHIFTED_PER_CATEGORY} per category); {args.workers} workers")
    print("| setting | wall time of the set | median real-time rate | grasped | functional | agreement |")
    print("|---|---:|---:|---:|---:|---:|")
    for hint in settings:
        rs, wall = results[hint]
        ok = [r for r in rs if "grasp" in r]
        rates = [r["sim_s"] / r["wall_s"] for r in ok if r["sim_s"] > 0]
        agree = sum(1 for a, b in zip(base, rs) if "grasp" in a and "grasp" in b
                    and (a["grasp"], a["functional"]) == (b["grasp"], b["functional"]))
        name = "default (6 mm)" if hint is None else f"hand resolution hint {hint * 1000:.0f} mm"
        print(f"| {name} | {wall:.0f} s | {statistics.median(rates):.2f}x | {sum(r['grasp'] for r in ok)}/{len(rs)} "
              f"| {sum(r['functional'] for r in ok)}/{len(rs)} | {agree}/{len(rs)} ({100 * agree / len(rs):.0f} %) |")
    if args.json:
        from catgrasp_drake.core.fileio import atomic_write_text

        atomic_write_text(args.json, json.dumps({str(h): r for h, (r, _) in results.items()}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
