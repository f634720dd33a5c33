"""The committed drill model with its grasp knowledge raised by DZ metres, or its fingers spread by S rad.

    python benchmarks/results/experiments/s27_drill_raise/raise_model.py --dz 0.005 --out out/s27/drill_up5.npz
    python benchmarks/results/experiments/s27_drill_raise/raise_model.py --spread 0.15 --out out/s27/drill_spread.npz
    catgrasp benchmark --split stress --categories drill --methods latent --placements 1 \
        --model out/s27/drill_up5.npz --out benchmarks/results/experiments/s27_drill_raise/stress_up5.jsonl

Everything but the grasp positions is the committed model's: the regressor's intercept and every stored
training grasp (what the nearest-instance baseline reads) have the z of each control pose (pregrasp and grasp)
moved by ``--dz``, and ``--spread`` added to the finger spread (``svh_finger_spread``, rad) of both regressed
postures (preshape, closed); the rest and the shape space are untouched. Before warping, so on an instance
the shift is scaled and bent with the object like the rest of the grasp. No simulation.
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
from catgrasp_drake.grasping.descriptor import NUM_HAND_JOINTS, REGRESSED_POSTURES  # noqa: E402
from catgrasp_drake.robot.specs import SVH_ACTUATED_JOINTS  # noqa: E402


def raised(model: CategoryModel, dz: float, spread: float = 0.0) -> CategoryModel:
    """``model`` with the z (m, canonical frame) of every control pose in its descriptors moved by ``dz`` and
    ``spread`` (rad) added to the finger spread of every regressed posture."""
    offset = np.zeros(model.regressor.intercept.shape)
    K = len(model.template.poses)
    offset[[9 * k + 2 for k in range(K)]] = dz  # descriptor: (p, a, b) per pose, then the regressed postures
    j = SVH_ACTUATED_JOINTS.index("svh_finger_spread")
    offset[[9 * K + NUM_HAND_JOINTS * i + j for i in range(len(REGRESSED_POSTURES))]] = spread
    regressor = dataclasses.replace(model.regressor, intercept=model.regressor.intercept + offset)
    return dataclasses.replace(model, regressor=regressor, training_descriptors=model.training_descriptors + offset,
                               params=model.params | {"raised_m": float(dz)}
                               | ({"spread_added_rad": float(spread)} if spread else {}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=str(ROOT / "models" / "trained" / "drill.npz"))
    ap.add_argument("--dz", type=float, default=0.0, help="metres, canonical +z")
    ap.add_argument("--spread", type=float, default=0.0, help="rad added to svh_finger_spread")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    model = CategoryModel.load(args.model)
    out = raised(model, args.dz, args.spread)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    out.save(args.out)
    z0 = [model.canonical_motion(x).poses[-1][2, 3] for x in model.space.latent_train]
    z1 = [out.canonical_motion(x).poses[-1][2, 3] for x in model.space.latent_train]
    print(f"{args.out}: grasp z over the training shapes {1000 * np.mean(z0):.1f} -> {1000 * np.mean(z1):.1f} mm")


if __name__ == "__main__":
    main()
