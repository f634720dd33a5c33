"""How far the canonical trigger, warped by the CPD fields, lands from each training bottle's own (session 16).

    python benchmarks/results/experiments/s16_canonical_choice/canon_choice.py   (~1 min)

For several candidate canonical instances among the 15 spray training bottles, the shape space with the
training's settings, the candidate's annotated trigger centre warped onto every bottle (the candidate itself
counted, at 0 mm): mean / max over all, the deep and the flat bottles (mm). The figures quoted in
docs/training.md, session 16; ``catgrasp train --canonical region`` makes the choice (the candidate excluded).
"""
import numpy as np

from catgrasp_drake.core.deformation import deform_points
from catgrasp_drake.core.shape_space import build_shape_space
from catgrasp_drake.data.dataset import list_instances, load_annotations, load_mesh
from catgrasp_drake.data.pointclouds import full_cloud
from catgrasp_drake.training import TrainingConfig

cfg = TrainingConfig()
names = list_instances("spray_bottle")[:-2]
clouds = [full_cloud(load_mesh("spray_bottle", n), voxel=cfg.cloud_voxel) for n in names]
c = np.array([load_annotations("spray_bottle", n)["regions"]["trigger"]["center"] for n in names])
deep = np.array([bool(load_annotations("spray_bottle", n)["params"]["deep"]) for n in names])
for k in [0, 1, 3, 9, 10, 2, 4]:
    sp = build_shape_space(clouds, canonical_index=k, **cfg.shape_kwargs())
    e = 1000 * np.array([np.linalg.norm(deform_points(sp.canonical, sp.W_train[i], sp.beta, c[k:k + 1])[0] - c[i])
                         for i in range(len(names))])
    print(f"canonical {names[k]} ({'deep' if deep[k] else 'flat'}): mean {e.mean():.1f} max {e.max():.1f} | "
          f"deep mean {e[deep].mean():.1f} max {e[deep].max():.1f} | "
          f"flat mean {e[~deep].mean():.1f} max {e[~deep].max():.1f}", flush=True)
