"""Where a drill model's learned grasp sits against the hand-written template it was trained from.

    python benchmarks/results/experiments/s19_drill_handles/learned_grasp.py [--model models/trained/drill.npz]

Prints, in the model's canonical frame (mm; x lateral, y toward the chuck, z up), the learned grasp at the
latent origin (the regressor's prediction warped by W(0)) minus the model's template (the hand-written grasp
anchored on the canonical trigger), for the grasp and the pregrasp, and each motion's pregrasp-to-grasp
distance. It reads the model file only (no data set, no simulation); the experiment's retrained models are
made by the commands in this folder's README.
"""

from __future__ import annotations

import argparse

import numpy as np

from catgrasp_drake.category_model import CategoryModel


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="models/trained/drill.npz")
    a = ap.parse_args()
    model = CategoryModel.load(a.model, category="drill")
    template = model.template
    learned = model.transfer(np.zeros(model.space.latent_train.shape[1]), frame="object")
    print(f"model {a.model}, canonical {model.canonical_instance}")
    for name in ("grasp", "pregrasp"):
        d = 1000 * (learned.pose(name)[:3, 3] - template.pose(name)[:3, 3])
        print(f"  learned - template, {name:<8} x {d[0]:+6.1f}  y {d[1]:+6.1f}  z {d[2]:+6.1f} mm")
    for label, m in (("template", template), ("learned", learned)):
        gap = 1000 * np.linalg.norm(m.pose("pregrasp")[:3, 3] - m.pose("grasp")[:3, 3])
        print(f"  {label} pregrasp-to-grasp distance {gap:.0f} mm")


if __name__ == "__main__":
    main()
