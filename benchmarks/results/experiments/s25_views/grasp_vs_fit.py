"""Session 25 probe: where the learned grasp lands on the true trigger, from one view and from three (no simulation).

    python benchmarks/results/experiments/s25_views/grasp_vs_fit.py [--category spray_bottle] [--placements 3]

COMMITTED instances only (the tuning set; seed 4242 placements as the benchmark draws them, depth noise on).
For each placement the ``latent`` method's estimate (8 yaw starts, 3 hypotheses) from the station camera
alone and from it and the cameras turned +90 / -90 deg, and the regressed grasp R(x) warped by W(x) and
placed by the fit (``prediction.predict_motion``); also the grasp under perfect perception (the instance's
training latent, its true pose, scale 1) for the model's training instances. Printed per instance and in
medians: the fit's position error (mm) and scale, and the grasp's functional point (``grasp_anchor_H``)
minus the instance's true trigger centre, in the TRUE object frame (mm: x lateral, y forward, z up).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from probe import committed_views, merged_fit  # noqa: E402  (this folder's probe.py)

from catgrasp_drake.benchmark.runner import yaw_error_deg  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.data.dataset import load_annotations  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.grasping.descriptor import motion_functional_point  # noqa: E402
from catgrasp_drake.prediction import predict_motion  # noqa: E402
from catgrasp_drake.transfer import EXTRA_VIEW_AZIMUTHS_DEG  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", default="spray_bottle")
    ap.add_argument("--placements", type=int, default=3)
    ap.add_argument("--seed", type=int, default=4242)
    args = ap.parse_args(argv)
    c = args.category
    region = {"drill": "trigger", "spray_bottle": "trigger", "mug": "handle"}[c]
    model = CategoryModel.load(default_model_path(c), category=c)
    rows = []
    for name, k, scenario, views in committed_views(c, args.placements, args.seed, (0.0,) + EXTRA_VIEW_AZIMUTHS_DEG):
        p_O = np.asarray(load_annotations(c, name)["regions"][region]["center"], float)
        X_WT, X_WO = scenario.table.pose.matrix(), scenario.X_WO()

        def offset_mm(motion):  # the grasp's functional point minus the true region centre, TRUE frame O (mm)
            f_W = motion_functional_point(motion, model.grasp_anchor_H)
            return [round(1000 * float(v), 1) for v in X_WO[:3, :3].T @ (f_W - (X_WO[:3, :3] @ p_O + X_WO[:3, 3]))]

        row = {"instance": name, "placement": k}
        for label, n in (("one", 1), ("three", 3)):
            e = merged_fit(model.space, views, n, X_WT)
            motion, _ = predict_motion("latent", model, e.x, e.X_WO, e.scale)
            row[label] = {"pos_mm": round(1000 * float(np.linalg.norm(e.X_WO[:3, 3] - X_WO[:3, 3])), 1),
                          "yaw": round(yaw_error_deg(e.X_WO, X_WO), 1), "scale": round(e.scale, 3),
                          "off_mm": offset_mm(motion)}
        if name in model.instances and k == 0:
            j = model.instances.index(name)
            row["perfect"] = {"off_mm": offset_mm(predict_motion("latent", model, model.space.latent_train[j], X_WO,
                                                                 1.0)[0])}
        rows.append(row)
        print(json.dumps(row), flush=True)
    for label in ("one", "three", "perfect"):
        off = np.array([r[label]["off_mm"] for r in rows if label in r])
        extra = ""
        if label != "perfect":
            extra = (f", position error {np.median([r[label]['pos_mm'] for r in rows]):.1f} mm, scale "
                     f"{np.median([r[label]['scale'] for r in rows]):.3f}")
        print(f"{label}: {len(off)} grasps; functional point - true {region} (mm, median x / y / z): "
              f"{' / '.join(f'{v:+.1f}' for v in np.median(off, axis=0))}, median distance "
              f"{np.median(np.linalg.norm(off, axis=1)):.1f}{extra}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
