"""The committed drill model with another latent -> grasp regressor, fitted on its own stored training set.

    python benchmarks/results/experiments/s20_stress/regressor_variants.py --out out/s20/models
    catgrasp benchmark --split stress --categories drill --methods latent --placements 1 \
        --model out/s20/models/drill_ridge_1.npz --out out/s20/stress_ridge_1.jsonl

Writes one model file per variant (everything but the regressor is the committed model's): ``canonical`` (the
hand-written grasp, no learned knowledge), ``mean`` (the committed choice, refitted: identical), ``nearest``,
``ridge_<alpha>`` and ``kernel_ridge_<length scale>_<alpha>``, each fitted as training fits its regressors (on
the per-instance means of the kept grasps, ``core.regression.instance_means``). No simulation.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.regression import REGRESSOR_GRID, instance_means  # noqa: E402
from catgrasp_drake.training import canonical_regressor  # noqa: E402

VARIANTS = {"mean": ("mean", {}), "nearest": ("nearest", {}), "ridge_1": ("ridge", {"alpha": 1.0}),
            "ridge_0.1": ("ridge", {"alpha": 0.1}),
            "kernel_ridge_1_0.1": ("kernel_ridge", {"length_scale": 1.0, "alpha": 0.1}),
            "kernel_ridge_2_0.1": ("kernel_ridge", {"length_scale": 2.0, "alpha": 0.1})}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=str(ROOT / "models" / "trained" / "drill.npz"))
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    model = CategoryModel.load(args.model)
    _, x, y = instance_means(model.training_latent, model.training_descriptors, model.training_groups,
                             model.training_weights)
    args.out.mkdir(parents=True, exist_ok=True)
    variants = {"canonical": canonical_regressor(model.template, model.space.q)}
    for name, (family, hyper) in VARIANTS.items():
        variants[name] = REGRESSOR_GRID[family][0](x, y, np.arange(len(x)), **hyper)
    for name, regressor in variants.items():
        path = args.out / f"{model.category}_{name}.npz"
        dataclasses.replace(model, regressor=regressor).save(path)
        spread = np.ptp([regressor.predict(xi) for xi in model.space.latent_train], axis=0)
        print(f"{path}: predicted grasp position spread over the training shapes {1000 * spread[9:12].max():.1f} mm")


if __name__ == "__main__":
    main()
