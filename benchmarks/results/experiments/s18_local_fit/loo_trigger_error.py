"""Session 18 experiment (not landed): the fitted trigger centre's error, and after a translation-only local fit
(ICP) of the completed shape near it to the observed points. Leave-one-instance-out shape spaces on the
COMMITTED instances (bench_yaw_loo's harness: 3 seeded placements, single view, depth noise; no simulation).

    python benchmarks/results/experiments/s18_local_fit/loo_trigger_error.py drill [RADIUS CUTOFF CAP]
    python benchmarks/results/experiments/s18_local_fit/loo_trigger_error.py spray_bottle 0.03 0.015 0.015
"""

import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.benchmark.runner import trial_placement  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.deformation import deform_points  # noqa: E402
from catgrasp_drake.core.shape_space import build_shape_space  # noqa: E402
from catgrasp_drake.data.dataset import instance_clouds, load_annotations  # noqa: E402
from catgrasp_drake.data.importer import canonical_annotations  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402

CLOUD_VOXEL_M = 0.01  # the training's voxel size for instance clouds (m), as bench_yaw_loo


def local_shift(model_W, obs_W, centre, radius=0.04, cutoff=0.015, iters=10):
    """Translation moving the model's surface near ``centre`` onto the observed points within ``radius``."""
    obs = obs_W[np.linalg.norm(obs_W - centre, axis=1) < radius]
    if len(obs) < 20:
        return np.zeros(3), len(obs)
    t = np.zeros(3)
    near = model_W[np.linalg.norm(model_W - centre, axis=1) < radius + 0.02]
    tree = cKDTree(near)
    for _ in range(iters):
        d, j = tree.query(obs - t)
        ok = d < cutoff
        if ok.sum() < 10:
            break
        t = np.mean(obs[ok] - near[j[ok]], axis=0)
    return t, len(obs)


def main(category="drill", radius=0.04, cutoff=0.015, cap=1.0, placements=3, seed=4242, region="trigger"):
    model = CategoryModel.load(default_model_path(category), category=category)
    names = list(model.instances)
    canonical = names.index(model.canonical_instance)
    c_can = np.asarray(canonical_annotations(model)["regions"][region]["center"], float)
    clouds = instance_clouds(category, names, CLOUD_VOXEL_M)
    variance = float(model.params.get("variance", 0.95))
    W = build_shape_space(clouds, canonical_index=canonical, beta=model.space.beta, variance=variance).W_train
    errs = []
    for h, name in enumerate(names):
        if h == canonical:
            continue
        members = [i for i in range(len(names)) if i != h]
        c = members.index(canonical)
        space = build_shape_space([clouds[i] for i in members], canonical_index=c, beta=model.space.beta,
                                  variance=variance,
                                  registrations={(c, k): W[i] for k, i in enumerate(members) if i != canonical})
        true_c = np.asarray(load_annotations(category, name)["regions"][region]["center"], float)
        base = with_instance(load_scenario(f"{category}_default"), name, category=category)
        for k in range(placements):
            scenario, _, _ = trial_placement(base, name, k, seed, noise=True)
            p_W, camera_W = observe(scenario)
            X_WT, X_WO = scenario.table.pose.matrix(), scenario.X_WO()
            est = estimate_on_table(space, p_W, X_WT, camera_W=camera_W, yaw_candidates=8, hypotheses=1)
            d = deform_points(space.canonical, space.decode(est.x), space.beta, c_can[None])[0]
            est_c = est.X_WO[:3, :3] @ (est.scale * d) + est.X_WO[:3, 3]
            tru_c = X_WO[:3, :3] @ true_c + X_WO[:3, 3]
            t, n = local_shift(est.completed_W, p_W, est_c, radius=radius, cutoff=cutoff)
            if np.linalg.norm(t) > cap:
                t = t * cap / np.linalg.norm(t)
            e0, e1 = np.linalg.norm(est_c - tru_c), np.linalg.norm(est_c + t - tru_c)
            errs.append((e0, e1, n))
            print(f"{name} k{k} trigger err {1000 * e0:5.1f} -> {1000 * e1:5.1f} mm  shift {np.round(1000 * t, 1)} "
                  f"obs {n}", flush=True)
    e = np.array(errs)
    print(f"{category}: median {1000 * np.median(e[:, 0]):.1f} -> {1000 * np.median(e[:, 1]):.1f} mm; "
          f"mean {1000 * e[:, 0].mean():.1f} -> {1000 * e[:, 1].mean():.1f}; <=5 mm {(e[:, 0] <= 0.005).sum()} -> "
          f"{(e[:, 1] <= 0.005).sum()} of {len(e)}; worse by >2 mm {(e[:, 1] > e[:, 0] + 0.002).sum()}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "drill", *map(float, sys.argv[2:5]))
