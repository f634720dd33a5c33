"""Session 29 probe: how well non-rigid CPD from the drill canonical carries its trigger onto each COMMITTED drill's
own trigger, full clouds (the training's 1 cm voxel clouds), for several kernel widths beta and lambda. No simulation.

    python benchmarks/results/experiments/s29_trigger_height/beta_registration.py
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.cpd import nonrigid_cpd  # noqa: E402
from catgrasp_drake.core.deformation import deform_points  # noqa: E402
from catgrasp_drake.data.dataset import instance_clouds, load_annotations  # noqa: E402
from catgrasp_drake.data.importer import canonical_annotations  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402

model = CategoryModel.load(default_model_path("drill"), category="drill")
names = list(model.instances)
c_can = np.asarray(canonical_annotations(model)["regions"]["trigger"]["center"], float)
clouds = instance_clouds("drill", names, 0.01)
for beta, lam in [(0.1, 3.0), (0.05, 3.0), (0.03, 3.0), (0.02, 3.0), (0.03, 1.0)]:
    E = []
    for i, n in enumerate(names):
        if n == model.canonical_instance:
            continue
        t = np.asarray(load_annotations("drill", n)["regions"]["trigger"]["center"])
        r = nonrigid_cpd(model.space.canonical, clouds[i], beta=beta, lam=lam, w=0.0, max_iter=150, tol=1e-6)
        E.append(1000 * (deform_points(model.space.canonical, r.W, beta, c_can[None])[0] - t))
    E = np.array(E)
    print(f"beta {beta} lam {lam}: trigger error rms x/y/z {np.sqrt((E ** 2).mean(0)).round(1)} mm, "
          f"|dz| max {abs(E[:, 2]).max():.1f}, dz {E[:, 2].round(1)}")
