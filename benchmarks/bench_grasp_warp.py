"""How well the shape space carries a grasp onto the training instances: the figures behind the training choices.

    python benchmarks/bench_grasp_warp.py [--betas 0.02 0.10] [--model models/trained/drill.npz]

1. CPD kernel width: for each category and beta, the canonical instance's
   functional region centre (trigger / handle) warped by each training
   instance's CPD field vs that instance's annotated centre (mm), and the
   registration's symmetric Chamfer distance (mm). Instances: all but the
   last two (the demo's held-out ones), canonical = the first.
2. Hand orientation (drill, beta 0.10): the canonical grasp warped at its
   functional point, its rotation from the field's Jacobian at that point vs
   averaged over 5 cm (``local_rotations``), compared with the hand-written
   grasp's orientation, which is the same on every instance (deg).
3. Ridge alpha of a trained model: leave-one-instance-out error of the
   predicted grasp's functional point against the held-out instance's
   stored successes (mm).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.deformation import deform_points, warp_poses  # noqa: E402
from catgrasp_drake.core.regression import fit_ridge  # noqa: E402
from catgrasp_drake.core.rotations import rotation_angle  # noqa: E402
from catgrasp_drake.core.shape_space import build_shape_space  # noqa: E402
from catgrasp_drake.data.dataset import instance_clouds, list_instances, load_annotations  # noqa: E402
from catgrasp_drake.grasping.constraints import load_constraint  # noqa: E402
from catgrasp_drake.grasping.descriptor import motion_from_descriptor  # noqa: E402
from catgrasp_drake.station.handwritten import load_handwritten_motion  # noqa: E402
from catgrasp_drake.training import functional_point_in_hand  # noqa: E402


def kernel_table(betas) -> dict:
    spaces = {}
    print("| category | beta (m) | region warp error mean / max (mm) | registration Chamfer (mm) |")
    print("|---|---|---|---|")
    for category in ("drill", "spray_bottle", "mug"):
        names = list_instances(category)[:-2]
        clouds = instance_clouds(category, names, 0.01)
        region = load_constraint(category).region
        centres = np.array([load_annotations(category, n)["regions"][region]["center"] for n in names])
        for beta in betas:
            sp = build_shape_space(clouds, canonical_index=0, beta=beta)
            err = [np.linalg.norm(deform_points(sp.canonical, sp.W_train[i], beta, centres[:1])[0] - centres[i])
                   for i in range(len(names))]
            cham = []
            for i, cloud in enumerate(clouds):
                moved = deform_points(sp.canonical, sp.W_train[i], beta, sp.canonical)
                cham.append(0.5 * (cKDTree(cloud).query(moved)[0].mean() + cKDTree(moved).query(cloud)[0].mean()))
            print(f"| {category} | {beta:.2f} | {1000 * np.mean(err):.1f} / {1000 * np.max(err):.1f} | "
                  f"{1000 * np.mean(cham):.1f} |", flush=True)
            spaces[(category, beta)] = (sp, names)
    return spaces


def rotation_table(space, names) -> None:
    template = load_handwritten_motion("drill", names[0])
    anchor = functional_point_in_hand(template, load_annotations("drill", names[0]), "trigger")
    R0 = template.pose("grasp")[:3, :3]
    print("\n| drill, hand rotation from | error vs the hand-written orientation, mean / max (deg) |")
    print("|---|---|")
    for label, radius in (("Jacobian at the functional point", None), ("field averaged over 5 cm", 0.05)):
        errs = [np.degrees(rotation_angle(warp_poses(space.canonical, space.W_train[i], space.beta, template.poses,
                                                     anchor=anchor, rotation_radius=radius)[1][:3, :3].T @ R0))
                for i in range(len(names))]
        print(f"| {label} | {np.mean(errs):.1f} / {np.max(errs):.1f} |")


def alpha_table(model: CategoryModel) -> None:
    X, Y, g = model.training_latent, model.training_descriptors, model.training_groups
    a = np.asarray(model.grasp_anchor_H)

    def centre(d):
        P = motion_from_descriptor(d, model.template).pose("grasp")
        return P[:3, :3] @ a + P[:3, 3]

    print(f"\n| {model.category} ridge alpha | leave-one-instance-out functional-point error (mm) |")
    print("|---|---|")
    for alpha in (0.01, 0.1, 1.0, 10.0, 100.0, 1e9):  # 1e9: the plain mean of the training grasps
        errs = []
        for i in np.unique(g):
            keep = g != i
            reg = fit_ridge(X[keep], Y[keep], alpha=alpha, groups=g[keep])
            p = centre(reg.predict(X[g == i][0]))
            errs += [np.linalg.norm(p - centre(d)) for d in Y[g == i]]
        label = "mean (alpha -> inf)" if alpha >= 1e9 else f"{alpha:g}"
        print(f"| {label} | {1000 * np.mean(errs):.1f} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--betas", nargs="+", type=float, default=[0.02, 0.10])
    ap.add_argument("--model", default="models/trained/drill.npz")
    ap.add_argument("--alpha-only", action="store_true", help="only the ridge-alpha table (no CPD runs)")
    args = ap.parse_args(argv)
    if args.alpha_only:
        alpha_table(CategoryModel.load(args.model))
        return 0
    spaces = kernel_table(args.betas)
    if ("drill", 0.10) in spaces:
        rotation_table(*spaces[("drill", 0.10)])
    alpha_table(CategoryModel.load(args.model))
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
