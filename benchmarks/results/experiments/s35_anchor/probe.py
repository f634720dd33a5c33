"""Session 35 probe: where does each method's estimate put the grasp's functional point, against the true trigger?

    python benchmarks/results/experiments/s35_anchor/probe.py [--category drill] [--placements 3] [--seed 4242]
                                                              [--families committed thin deep small large]

TUNING SETS ONLY: the committed instances and the stress split's stretched copies. Each object is placed as the
benchmark places it (``--seed``, depth noise on), seen once by the station camera, fitted as ``latent`` (visibility,
3 hypotheses, the MAP taken) and as ``paper`` (no visibility model), and the method's predicted grasp motion's
functional point (``motion_functional_point``: the trigger centre the hand carries) is compared with the object's
annotated trigger centre at its true pose. Printed per family and method: mean and spread of the error in the
true object frame (x lateral, y forward, z up; mm) and the share of views more than 5 mm below the trigger.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import stretched_objects, trial_placement  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.data.dataset import INSTANCE_COUNTS, instance_name  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.grasping.descriptor import motion_functional_point  # noqa: E402
from catgrasp_drake.prediction import ESTIMATORS  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402

ROOT = Path(__file__).resolve().parents[4]


def objects(category, family, data):
    """``[(name, scenario)]`` of one family: the committed instances or their stretched copies."""
    names = [instance_name(category, i) for i in range(INSTANCE_COUNTS[category])]
    base = load_scenario(f"{category}_default")
    if family == "committed":
        return [(n, with_instance(base, n, category=category)) for n in names]
    out = []
    for name, directory in stretched_objects(Path(data) / "stress", category, names, [family]):
        out.append((name, with_instance(base, name, category=category, model_dir=directory)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", default="drill")
    ap.add_argument("--placements", type=int, default=3)
    ap.add_argument("--seed", type=int, default=4242)
    ap.add_argument("--families", nargs="+", default=["committed", "thin", "deep", "small", "large"])
    ap.add_argument("--data", default=str(ROOT / "out" / "benchmark" / "data"))
    args = ap.parse_args(argv)
    model = CategoryModel.load(default_model_path(args.category), category=args.category)
    region = "trigger" if args.category != "mug" else "handle"
    print("family | method | views | error x / y / z mean (mm) | z sd | |error| median | z < -5 mm")
    for family in args.families:
        errs = {"latent": [], "paper": []}
        for name, base in objects(args.category, family, args.data):
            c_O = np.asarray(base.object.annotations()["regions"][region]["center"], float)
            for k in range(args.placements):
                scenario, _, _ = trial_placement(base, name, k, args.seed, noise=True)
                X_WO = scenario.X_WO()
                p_W, camera_W = observe(scenario)
                X_WT = scenario.table.pose.matrix()
                for method in errs:
                    setup = ESTIMATORS[method]
                    est = estimate_on_table(model.space, p_W, X_WT, camera_W=camera_W if setup.visibility else None,
                                            yaw_candidates=8, **setup.inference_kwargs)
                    motion = model.transfer(est.x, est.X_WO[:3, :3], est.X_WO[:3, 3], est.scale)
                    f_W = motion_functional_point(motion, model.grasp_anchor_H)
                    true_W = X_WO[:3, :3] @ c_O + X_WO[:3, 3]
                    errs[method].append(1000 * X_WO[:3, :3].T @ (f_W - true_W))
        for method, e in errs.items():
            e = np.array(e)
            print(f"{family} | {method} | {len(e)} | {e[:, 0].mean():+.1f} / {e[:, 1].mean():+.1f} / "
                  f"{e[:, 2].mean():+.1f} | {e[:, 2].std():.1f} | {np.median(np.linalg.norm(e, axis=1)):.1f} | "
                  f"{int((e[:, 2] < -5).sum())}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
