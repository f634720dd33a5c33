"""Session 29 probe: where each method's planned functional point lands against the TRUE trigger (no simulation).

    python benchmarks/results/experiments/s29_trigger_height/offsets.py RECORDS.jsonl OUT.json \
        [--methods latent latent_map paper] [--view single] [--instances drill_02 ...]

Replays the perception, the estimate, the prediction and the plan of each drill record (the benchmark's own
spec, placement, camera and depth noise; ``benchmark.runner.spec_from_record``), and writes per record the
executed candidate's functional point (the model's grasp anchor at the ``grasp`` pose, plus the planner's
object-clearance shift) minus the true trigger centre, in the TRUE object's canonical frame (mm: x lateral,
y forward along the chuck, z up). Read-only on the split: nothing here is tuned.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))


def main(argv=None) -> int:
    from catgrasp_drake.benchmark.runner import _model, spec_from_record, trial_scenario
    from catgrasp_drake.grasping.descriptor import motion_functional_point
    from catgrasp_drake.transfer import make_transfer_diagram

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("records")
    ap.add_argument("out")
    ap.add_argument("--methods", nargs="+", default=["latent", "latent_map", "paper"])
    ap.add_argument("--view", default="single")
    ap.add_argument("--instances", nargs="*")
    args = ap.parse_args(argv)
    lines = Path(args.records).read_text().splitlines()[1:]
    records = [json.loads(line) for line in lines if line.strip()]
    records = [r for r in records if r["category"] == "drill" and r["method"] in args.methods
               and r["view"] == args.view and (not args.instances or r["instance"] in args.instances)]
    rows = []
    for r in records:
        spec = spec_from_record(r, data_dir=ROOT / "out" / "benchmark" / "data")
        scenario, _, _ = trial_scenario(spec)
        model = _model(spec["_model"], spec["category"])
        td = make_transfer_diagram(scenario, model, view=spec["view"], method=spec["method"])
        context = td.diagram.CreateDefaultContext()
        est_ctx = td.estimator.GetMyMutableContextFromRoot(context)
        estimate = td.estimator.estimate_now(est_ctx)
        td.estimator.set_estimate(est_ctx, estimate)
        plan = td.generator.GetOutputPort("plan").Eval(td.generator.GetMyContextFromRoot(context))
        candidates = td.regressor.GetOutputPort("grasp_candidates_W").Eval(td.regressor.GetMyContextFromRoot(context))
        p_W = motion_functional_point(candidates[plan.candidate].motion, model.grasp_anchor_H) + np.array(
            plan.object_shift)
        X = scenario.X_WO()
        p_O = X[:3, :3].T @ (p_W - X[:3, 3])
        trigger = scenario.object.annotations()["regions"]["trigger"]
        row = {"instance": r["instance"], "trial": r["trial"], "method": r["method"], "functional": r["functional"],
               "reason": r["reason"], "plan": plan.status, "scale": round(float(estimate.scale), 3),
               "d_mm": [round(float(v), 1) for v in 1000 * (p_O - np.asarray(trigger["center"]))],
               "half_extents_mm": [round(1000 * float(v), 1) for v in trigger["half_extents"]]}
        rows.append(row)
        print(json.dumps(row), flush=True)
    Path(args.out).write_text(json.dumps(rows, indent=0) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
