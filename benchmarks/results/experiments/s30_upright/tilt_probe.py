"""Session 30 probe: how far the shape fit tilts each benchmark view, with a free rotation and upright (no simulation).

    python benchmarks/results/experiments/s30_upright/tilt_probe.py RECORDS.jsonl OUT.json [--methods latent]

Replays each single-view record's perception, estimate, prediction and plan twice: with the paper's free
similarity (``upright=False``) and with the rotation kept to a yaw about the table normal (``upright=True``, the
estimator's default since session 30). Writes per record and setting the estimate's tilt (deg between its z axis
and the world's), the executed candidate's functional point minus the TRUE region centre (mm, true object frame;
the trigger, or the mug's handle), the plan's status, the scale and the fit's energy.
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
    ap.add_argument("--methods", nargs="+", default=["latent"])
    ap.add_argument("--instances", nargs="*")
    args = ap.parse_args(argv)
    lines = Path(args.records).read_text().splitlines()[1:]
    records = [json.loads(line) for line in lines if line.strip()]
    records = [r for r in records if r["method"] in args.methods and r["view"] == "single"
               and (not args.instances or r["instance"] in args.instances)]
    rows = []
    for r in records:
        spec = spec_from_record(r, data_dir=ROOT / "out" / "benchmark" / "data")
        scenario, _, _ = trial_scenario(spec)
        model = _model(spec["_model"], spec["category"])
        X = scenario.X_WO()
        region = "handle" if r["category"] == "mug" else "trigger"
        centre = np.asarray(scenario.object.annotations()["regions"][region]["center"])
        row = {"instance": r["instance"], "trial": r["trial"], "method": r["method"], "functional": r["functional"],
               "reason": r["reason"]}
        for upright in (False, True):
            td = make_transfer_diagram(scenario, model, view=spec["view"], method=spec["method"], upright=upright)
            context = td.diagram.CreateDefaultContext()
            est_ctx = td.estimator.GetMyMutableContextFromRoot(context)
            estimate = td.estimator.estimate_now(est_ctx)
            td.estimator.set_estimate(est_ctx, estimate)
            plan = td.generator.GetOutputPort("plan").Eval(td.generator.GetMyContextFromRoot(context))
            candidates = td.regressor.GetOutputPort("grasp_candidates_W").Eval(
                td.regressor.GetMyContextFromRoot(context))
            k = plan.candidate if plan.candidate is not None and plan.candidate >= 0 else 0
            p_W = motion_functional_point(candidates[k].motion, model.grasp_anchor_H) + np.array(plan.object_shift)
            p_O = X[:3, :3].T @ (p_W - X[:3, 3])
            z_axis = np.asarray(estimate.X_WO)[:3, 2]
            row["up" if upright else "free"] = {
                "tilt": round(float(np.degrees(np.arccos(np.clip(z_axis[2], -1.0, 1.0)))), 1),
                "err_mm": [round(float(v), 1) for v in 1000 * (p_O - centre)], "plan": plan.status,
                "scale": round(float(estimate.scale), 3), "energy": round(float(estimate.energy), 1)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    Path(args.out).write_text(json.dumps(rows) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
