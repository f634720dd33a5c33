"""Contact sheet of an evaluation's failed grasps: where the predicted hand went, seen by the camera.

    python diagrams/failure_sheet.py drill [--method latent] [--out docs/failures_drill.png]

For every trial of ``out/eval/<category>/records.jsonl`` with the method that
was not a functional success, the same observation and prediction are made
again (same fold model, placement and view), the arm is planned, and the
station is posed kinematically at the plan's grasp knot (hand in its
preshape, just before closing) -- no simulation -- and rendered from the
scenario's camera. Plans that failed show the start configuration. Each tile
is labelled with the instance, view and failure reason.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main(argv=None) -> int:
    from catgrasp_drake.baselines import predict_grasp
    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.evaluation import load_records
    from catgrasp_drake.robot.models import ARM_JOINTS, hand_joint_angles
    from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
    from catgrasp_drake.transfer import observe
    from catgrasp_drake.trial import plan_for, trial_diagram
    from catgrasp_drake.viz.render import contact_sheet, rgb_array

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("category")
    ap.add_argument("--method", default="latent")
    ap.add_argument("--eval-dir", default="out/eval")
    ap.add_argument("--out", default=None, help="PNG (default: docs/failures_<category>.png)")
    args = ap.parse_args(argv)
    folder = Path(args.eval_dir) / args.category
    failed = [r for r in load_records(folder / "records.jsonl") if r["method"] == args.method and not r["functional"]]
    images, labels = [], []
    for r in failed:
        model = CategoryModel.load(folder / f"fold{r['fold']}.npz", category=args.category)
        scenario = random_placement(with_instance(load_scenario(f"{args.category}_default"), r["instance"]),
                                    r["seed"])
        observed, camera_W = observe(scenario, r["view"])
        pred = predict_grasp(args.method, model, observed, scenario.table.pose.matrix(), camera_W=camera_W)
        td = trial_diagram(scenario)
        h = td.station
        context = td.diagram.CreateDefaultContext()
        plant_ctx = h.plant.GetMyMutableContextFromRoot(context)
        if pred.ok:
            plan = plan_for(td, pred.motion_W)
            if plan.ok:
                k = plan.knot_names.index("grasp")
                for name, q in zip(ARM_JOINTS, plan.q_arm[k]):
                    h.plant.GetJointByName(name, h.arm).set_angle(plant_ctx, float(q))
                for name, q in hand_joint_angles(plan.q_hand[k]).items():
                    h.plant.GetJointByName(name, h.hand).set_angle(plant_ctx, float(q))
        sensor = h.cameras[scenario.cameras[0].name]
        image = sensor.color_image_output_port().Eval(sensor.GetMyContextFromRoot(context))
        images.append(np.ascontiguousarray(rgb_array(image)[::2, ::2]))
        labels.append(f"{r['instance']} {r['view']}: {r['reason']}")
        print(f"  {labels[-1]}", flush=True)
    if not images:
        print("no failures")
        return 0
    out = args.out or f"docs/failures_{args.category}.png"
    contact_sheet(images, labels, out, columns=5,
                  title=f"{args.category}, {args.method}: failed trials at the grasp knot (before closing)")
    print(f"wrote {out} ({len(images)} tiles)")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
