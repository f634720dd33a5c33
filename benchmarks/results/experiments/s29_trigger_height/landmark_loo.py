"""Session 29 experiment (not landed): leave-one-instance-out single-view trigger error on the COMMITTED drills, shape
spaces from plain CPD registrations (kappa 0) or from CPD with the trigger box as soft landmarks (kappa > 0: the
canonical points inside its trigger box are pulled, with that weight per point in the M-step, to the same relative
place in the instance's trigger box). No simulation; bench_yaw_loo's harness (3 seeded placements, single view,
depth noise, the 8-start yaw search).

    git apply benchmarks/results/experiments/s29_trigger_height/landmarks.diff
    python benchmarks/results/experiments/s29_trigger_height/landmark_loo.py drill KAPPA
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import trial_placement  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.cpd import nonrigid_cpd  # noqa: E402
from catgrasp_drake.core.deformation import deform_points  # noqa: E402
from catgrasp_drake.core.shape_space import build_shape_space  # noqa: E402
from catgrasp_drake.data.dataset import instance_clouds, load_annotations  # noqa: E402
from catgrasp_drake.data.importer import canonical_annotations  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402

REGION = {"drill": "trigger", "spray_bottle": "trigger", "mug": "handle"}


def main(category: str, kappa: float, placements: int = 3, seed: int = 4242) -> None:
    region = REGION[category]
    model = CategoryModel.load(default_model_path(category), category=category)
    names = list(model.instances)
    can = names.index(model.canonical_instance)
    ann = {n: load_annotations(category, n)["regions"][region] for n in names}
    c_can = np.asarray(canonical_annotations(model)["regions"][region]["center"], float)
    clouds = instance_clouds(category, names, 0.01)
    beta, lam = model.space.beta, model.space.lam
    variance = float(model.params.get("variance", 0.95))
    Y = clouds[can]
    cc, hc = np.asarray(ann[names[can]]["center"]), np.asarray(ann[names[can]]["half_extents"])
    inside = np.flatnonzero(np.all(np.abs(Y - cc) <= hc, axis=1))
    print("canonical points in the region:", len(inside))
    W = {}
    for i, n in enumerate(names):
        if i == can:
            continue
        ci, hi = np.asarray(ann[n]["center"]), np.asarray(ann[n]["half_extents"])
        landmarks = (inside, ci + (Y[inside] - cc) * (hi / hc)) if kappa > 0 else None
        r = nonrigid_cpd(Y, clouds[i], beta=beta, lam=lam, landmarks=landmarks, landmark_weight=kappa)
        W[i] = r.W
        moved = deform_points(Y, r.W, beta, c_can[None])[0]
        print(f"{n} registration region-centre err {np.round(1000 * (moved - ci), 1)}")
    errs = []
    for h, name in enumerate(names):
        if h == can:
            continue
        members = [i for i in range(len(names)) if i != h]
        c = members.index(can)
        space = build_shape_space([clouds[i] for i in members], canonical_index=c, beta=beta, variance=variance,
                                  registrations={(c, k): W[i] for k, i in enumerate(members) if i != can})
        true_c = np.asarray(ann[name]["center"], float)
        base = with_instance(load_scenario(f"{category}_default"), name, category=category)
        for k in range(placements):
            scenario, _, _ = trial_placement(base, name, k, seed, noise=True)
            p_W, camera_W = observe(scenario)
            X_WO = scenario.X_WO()
            est = estimate_on_table(space, p_W, scenario.table.pose.matrix(), camera_W=camera_W, yaw_candidates=8,
                                    hypotheses=1)
            d = deform_points(space.canonical, space.decode(est.x), space.beta, c_can[None])[0]
            est_c = est.X_WO[:3, :3] @ (est.scale * d) + est.X_WO[:3, 3]
            e_O = X_WO[:3, :3].T @ (est_c - (X_WO[:3, :3] @ true_c + X_WO[:3, 3]))
            errs.append(e_O)
            print(f"{name} k{k} err_O {np.round(1000 * e_O, 1)} |e| {1000 * np.linalg.norm(e_O):.1f}", flush=True)
    E = 1000 * np.array(errs)
    n = np.linalg.norm(E, axis=1)
    print(f"kappa {kappa}: median |e| {np.median(n):.1f} mean {n.mean():.1f} <=5mm {(n <= 5).sum()}/{len(n)}  "
          f"rms xyz {np.sqrt((E ** 2).mean(0)).round(1)} |dz|>6: {(abs(E[:, 2]) > 6).sum()}")


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]))
