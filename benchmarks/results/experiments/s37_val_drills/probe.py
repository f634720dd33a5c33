"""Session 37 probe: how each fit sizes and places a drill it never trained on (validation split, no simulation).

    python benchmarks/results/experiments/s37_val_drills/probe.py [--placements 6] [--methods latent paper]

TUNING SET: the validation split (``catgrasp benchmark --split val``, novel generator draws of the fixed
validation seed). Each drill is placed and seen exactly as the benchmark's trials (benchmark seed 0, depth
noise on), fitted as each method's estimator does (``prediction.ESTIMATORS``; the MAP fit), and compared with
the true object at its true pose, in the TRUE object frame O (x lateral, y forward, z up; mm):
the completed shape's height and length against the true mesh's (ratio), the mean distance from the true
surface to the completed shape (``truth->fit``, its unseen side included), and the predicted grasp's
functional point (``motion_functional_point``) minus the annotated trigger centre. One JSON line per view and
method goes to ``--out`` (default: probe.jsonl beside this file), so the figures can be set against the
benchmark's outcomes of the same trials (``val_drill.jsonl``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import BenchmarkConfig, split_objects, trial_placement  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.grasping.descriptor import motion_functional_point  # noqa: E402
from catgrasp_drake.prediction import ESTIMATORS  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402

HERE = Path(__file__).resolve().parent


def view_figures(model, est, X_WO, surface_O, c_O):
    """The figures of one fit (module docstring) against the true object: points sampled on its surface
    ``surface_O`` (V, 3) and its trigger centre ``c_O``, both in O (m)."""
    R, t = X_WO[:3, :3], X_WO[:3, 3]
    fit_O = (est.completed_W - t) @ R
    ext_true = surface_O.max(0) - surface_O.min(0)
    ext_fit = fit_O.max(0) - fit_O.min(0)
    d, _ = cKDTree(fit_O).query(surface_O)
    motion = model.transfer(est.x, est.X_WO[:3, :3], est.X_WO[:3, 3], est.scale)
    f_O = R.T @ (motion_functional_point(motion, model.grasp_anchor_H) - t)
    return {"scale": round(est.scale, 4), "height_ratio": round(float(ext_fit[2] / ext_true[2]), 4),
            "length_ratio": round(float(ext_fit[1] / ext_true[1]), 4),
            "width_ratio": round(float(ext_fit[0] / ext_true[0]), 4),
            "truth_to_fit_mm": round(1000 * float(d.mean()), 2),
            "trigger_error_mm": [round(1000 * float(v), 1) for v in f_O - c_O]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--placements", type=int, default=6)
    ap.add_argument("--methods", nargs="+", default=["latent", "paper"])
    ap.add_argument("--data", default="out/benchmark/data")
    ap.add_argument("--out", default=str(HERE / "probe.jsonl"))
    args = ap.parse_args(argv)
    model = CategoryModel.load(default_model_path("drill"), category="drill")
    base = load_scenario("drill_default")
    rows = []
    for obj in split_objects(BenchmarkConfig(split="val", categories=("drill",), data_dir=args.data)):
        scenario0 = with_instance(base, obj.instance, category="drill", model_dir=obj.model_dir)
        mesh = trimesh.load(Path(obj.model_dir) / f"{obj.instance}.obj", force="mesh")
        surface_O = np.asarray(mesh.sample(4000, seed=0))
        c_O = np.asarray(scenario0.object.annotations()["regions"]["trigger"]["center"], float)
        for k in range(args.placements):
            scenario, _, _ = trial_placement(scenario0, obj.instance, k, 0, noise=True)
            p_W, camera_W = observe(scenario)
            for method in args.methods:
                setup = ESTIMATORS[method]
                est = estimate_on_table(model.space, p_W, scenario.table.pose.matrix(),
                                        camera_W=camera_W if setup.visibility else None, yaw_candidates=8,
                                        **setup.inference_kwargs)
                rows.append({"instance": obj.instance, "trial": k, "method": method}
                            | view_figures(model, est, scenario.X_WO(), surface_O, c_O))
                print(json.dumps(rows[-1]), flush=True)
    Path(args.out).write_text("".join(json.dumps(r) + "\n" for r in rows))
    for method in args.methods:
        m = [r for r in rows if r["method"] == method]
        e = np.array([r["trigger_error_mm"] for r in m])
        print(f"{method}: {len(m)} views; height ratio {np.median([r['height_ratio'] for r in m]):.3f}, length "
              f"{np.median([r['length_ratio'] for r in m]):.3f}, width {np.median([r['width_ratio'] for r in m]):.3f}"
              f" (medians); truth->fit {np.mean([r['truth_to_fit_mm'] for r in m]):.2f} mm; trigger error x/y/z "
              f"{e[:, 0].mean():+.1f} / {e[:, 1].mean():+.1f} / {e[:, 2].mean():+.1f} mm (means)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
