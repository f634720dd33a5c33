"""Which latent -> grasp regressor predicts a held-out instance's grasp best: mean, nearest, ridge, kernel ridge.

    python benchmarks/bench_regression.py [--models models/trained/drill.npz ...]

For each trained category model, its stored training set (every training
instance's functional successes, mapped to the canonical frame, with the
instance's latent vector) is split leave-one-instance-out. The error of a
prediction is the mean distance (mm) between the grasp's functional point
(the trigger / handle centre carried in the hand frame) of the predicted
descriptor and of each of the held-out instance's own successes. Printed per
family (``core.regression.REGRESSOR_GRID``): the NESTED leave-one-instance-out
error -- each held-out instance predicted with the hyperparameters chosen by
leave-one-instance-out on the other instances, so no choice saw it -- and
the same for the automatic choice across all families (what a model file
would use). Also the regressor the model file itself holds. A model trained with the grasp
search (``catgrasp train --search``) is split on its instances' robustness-weighted mean grasps.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.regression import REGRESSOR_GRID, instance_means, nested_loo_error  # noqa: E402
from catgrasp_drake.grasping.descriptor import functional_point  # noqa: E402


def functional_point_error(model: CategoryModel):
    def centre(d):
        return functional_point(d, model.template, model.grasp_anchor_H)

    def error(pred, rows):
        c = centre(pred)
        return float(np.mean([np.linalg.norm(c - centre(d)) for d in rows]))

    return error


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", nargs="+",
                    default=[f"models/trained/{c}.npz" for c in ("drill", "spray_bottle", "mug")])
    args = ap.parse_args(argv)
    names = tuple(REGRESSOR_GRID)
    print("| model | instances | rows | " + " | ".join(names) + " | automatic choice (least error) | "
          "automatic choice (one-SE rule) | the model's regressor |")
    print("|---|---:|---:|" + "---:|" * (len(names) + 3))
    for path in args.models:
        model = CategoryModel.load(path)
        X, Y, g = model.training_latent, model.training_descriptors, np.asarray(model.training_groups)
        if model.training_weights is not None:  # searched grasps: each instance's robustness-weighted mean
            _, X, Y = instance_means(X, Y, g, model.training_weights)
            g = np.arange(len(X))
        error = functional_point_error(model)
        t0 = time.perf_counter()
        family = {n: nested_loo_error(X, Y, g, error, (n,)) for n in names}
        auto = nested_loo_error(X, Y, g, error, names)
        auto_1se = nested_loo_error(X, Y, g, error, names, rule="one_se")
        own = model.stats.get("regression", {"regressor": f"ridge (alpha {model.regressor.alpha:g})"})
        cells = " | ".join(f"{1000 * family[n]:.1f}" for n in names)
        print(f"| {path} | {len(np.unique(g))} | {len(model.training_groups)} | {cells} | {1000 * auto:.1f} | "
              f"{1000 * auto_1se:.1f} | {own['regressor']} {own.get('hyperparameters', '')} |", flush=True)
        print(f"  ({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
    print("\nErrors in mm at the grasp's functional point, nested leave-one-instance-out (module docstring).")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
