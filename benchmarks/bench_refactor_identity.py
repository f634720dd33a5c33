"""Behaviour fingerprint of a fixed set of grasp trials, to check a refactoring changes nothing.

    python benchmarks/bench_refactor_identity.py --out /tmp/identity_new.json [--reference /tmp/identity_ref.json]

Runs the hand-written grasp (``catgrasp_drake.station.handwritten``) on
drill_00..06, spray_bottle_00..06 and mug_00..05 through ``run_grasp_trial``
and three transfer-diagram runs (``make_transfer_diagram`` + ``run_transfer``
on drill_12, spray_bottle_16, mug_14 at ``random_placement(..., seed)``).
Per trial it records the plan (status, timeline, knot names and the sha256 of
every knot array: times, arm and hand positions, arm velocities) and the
outcome (``TrialResult.outcome()``, or the ``TransferResult`` without its
timings). Writes them as JSON to ``--out``; with ``--reference`` compares
entry by entry and exits 1 on any difference (listing the fields that differ).
``--only drill_00,...`` runs a subset (the comparison then covers those).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

HANDWRITTEN = ([f"drill_{i:02d}" for i in range(7)] + [f"spray_bottle_{i:02d}" for i in range(7)]
               + [f"mug_{i:02d}" for i in range(6)])
TRANSFERS = (("drill", "drill_12", 0), ("spray_bottle", "spray_bottle_16", 1), ("mug", "mug_14", 2))


def _sha(a) -> str:
    a = np.ascontiguousarray(np.asarray(a, dtype=float))
    return hashlib.sha256(str(a.shape).encode() + a.tobytes()).hexdigest()


def plan_record(plan) -> dict:
    """Everything deterministic about a ``GraspPlan`` (its solve time is not)."""
    return {"status": plan.status, "timeline": plan.timeline.as_dict(), "knot_names": list(plan.knot_names),
            "times": _sha(plan.times), "q_arm": _sha(plan.q_arm), "q_hand": _sha(plan.q_hand),
            "v_arm": None if plan.v_arm is None else _sha(plan.v_arm)}


def _category(instance: str) -> str:
    return instance.rsplit("_", 1)[0]


def handwritten_entry(instance: str) -> dict:
    from catgrasp_drake.station.handwritten import load_handwritten_motion
    from catgrasp_drake.station.scenario import load_scenario, with_instance
    from catgrasp_drake.trial import plan_for, run_grasp_trial, trial_diagram

    category = _category(instance)
    scenario = with_instance(load_scenario(f"{category}_default"), instance)
    motion = load_handwritten_motion(category, instance)
    plan = plan_for(trial_diagram(scenario), motion.in_world(scenario.X_WO()))
    result = run_grasp_trial(scenario, motion)
    return {"plan": plan_record(plan), "outcome": result.outcome()}


def transfer_entry(category: str, instance: str, seed: int) -> dict:
    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.demo import default_model_path
    from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
    from catgrasp_drake.transfer import make_transfer_diagram, run_transfer

    model = CategoryModel.load(default_model_path(category), category=category)
    scenario = random_placement(with_instance(load_scenario(f"{category}_default"), instance), seed)
    td = make_transfer_diagram(scenario, model)
    result, context = run_transfer(td, return_context=True)
    plan = td.generator.GetOutputPort("plan").Eval(td.generator.GetMyContextFromRoot(context))
    outcome = result.to_dict()
    outcome.pop("timings")
    return {"plan": plan_record(plan), "outcome": json.loads(json.dumps(outcome))}


def compare(new: dict, reference: dict) -> list[str]:
    """Human-readable differences (keys of ``new`` only)."""
    out = []
    for key, entry in new.items():
        ref = reference.get(key)
        if ref is None:
            out.append(f"{key}: not in the reference")
            continue
        for part in ("plan", "outcome"):
            for field in sorted(set(entry[part]) | set(ref[part])):
                if entry[part].get(field) != ref[part].get(field):
                    out.append(f"{key}: {part}.{field} differs: {entry[part].get(field)!r} vs "
                               f"{ref[part].get(field)!r}"[:300])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="JSON file to write")
    ap.add_argument("--reference", default=None, help="JSON file to compare against")
    ap.add_argument("--only", default=None, help="comma-separated trial keys (default: all)")
    args = ap.parse_args(argv)
    jobs = [(f"handwritten:{i}", handwritten_entry, (i,)) for i in HANDWRITTEN]
    jobs += [(f"transfer:{i}@seed{s}", transfer_entry, (c, i, s)) for c, i, s in TRANSFERS]
    if args.only:
        wanted = set(args.only.split(","))
        jobs = [j for j in jobs if j[0] in wanted or j[0].split(":", 1)[1].split("@")[0] in wanted]
    results = {}
    t_all = time.perf_counter()
    for key, fn, fargs in jobs:
        t0 = time.perf_counter()
        results[key] = json.loads(json.dumps(fn(*fargs)))
        o = results[key]["outcome"]
        print(f"{key:34s} plan {results[key]['plan']['status'][:40]:40s} grasp {o['grasp_success']!s:5s} "
              f"functional {o['functional_success']!s:5s} ({time.perf_counter() - t0:.1f} s)", flush=True)
    Path(args.out).write_text(json.dumps(results, indent=1, sort_keys=True))
    print(f"wrote {len(results)} trials to {args.out} in {time.perf_counter() - t_all:.0f} s")
    if args.reference is None:
        return 0
    diffs = compare(results, json.loads(Path(args.reference).read_text()))
    for d in diffs:
        print("DIFF", d)
    print(f"compared {len(results)} trials with {args.reference}: "
          + ("all identical" if not diffs else f"{len(diffs)} differences"))
    return 1 if diffs else 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
