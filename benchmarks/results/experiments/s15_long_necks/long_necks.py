"""Would other deep necks let the spray-bottle space find the Windex bottle's trigger? (session 15, not landed)

    python benchmarks/results/experiments/s15_long_necks/long_necks.py [--ycb out/ycb]

The committed spray model's grasp lands 31.5 mm from the YCB Windex bottle's trigger (full view,
``bench_family_coverage.py``): its neck is 5 cm long, the deep generated bottles' 2.2-3.5 cm, and its head
is short and reaches far behind the neck. This scratch experiment changes only the deep training bottles
(:data:`VARIANTS`: necks 3.5-5.5 cm long, necks on the body's axis, Windex-like heads; each the same draw
mapped onto the new range, every other parameter and every flat bottle unchanged), rebuilds the shape space
of the 15 training bottles with the training's own settings, and measures where the transferred grasp's
functional point lands against the annotated trigger -- for the committed bottles and each variant, all
with the canonical grasp as the regressor's output (so only the shape space differs; the committed model's
learned mean is within 3 mm of it). Nothing here is committed data; the Windex bottle is measured, not
tuned on.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_family_coverage import CLOUD_VOXEL, fit, region_center, ycb_meshes  # noqa: E402

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.shape_space import build_shape_space  # noqa: E402
from catgrasp_drake.data import categories  # noqa: E402
from catgrasp_drake.data.dataset import instance_seed, load_annotations, load_mesh  # noqa: E402
from catgrasp_drake.data.pointclouds import full_cloud  # noqa: E402
from catgrasp_drake.training import TrainingConfig, canonical_regressor  # noqa: E402

LONG_NECK_M = (0.035, 0.055)
DEEP_NECK_M = (0.022, 0.035)  # the committed generator's deep-bottle neck range


def _mapped(value, old, new):
    """``value`` drawn uniformly in ``old`` mapped onto the range ``new`` (the same draw)."""
    return round(new[0] + (value - old[0]) / (old[1] - old[0]) * (new[1] - new[0]), 5)


def variant_bottle(seed, *, long_neck: bool, centred_neck: bool, windex_head: bool = False):
    """The committed generator's bottle of ``seed``; if deep, its neck redrawn 3.5-5.5 cm long (the same draw
    mapped onto the longer range) and/or set on the body's axis (the Windex bottle's neck is within 3 mm of it),
    and/or its head made like the Windex bottle's: 2.2-2.8 cm tall, reaching 3.5-4.5 cm behind the neck."""
    p = categories.spray_bottle_params(np.random.default_rng(seed))
    if p["deep"] and windex_head:
        p["head_height"] = _mapped(p["head_height"], (0.028, 0.045), (0.022, 0.028))
        p["head_back"] = _mapped(p["head_back"], (0.012, 0.025), (0.035, 0.045))
        p["head_length"] = _mapped(p["head_length"], (0.055, 0.085), (0.08, 0.095))
    if p["deep"] and long_neck:
        p["neck_height"] = _mapped(p["neck_height"], DEEP_NECK_M, LONG_NECK_M)
    if p["deep"] and centred_neck:
        p["neck_offset_y"] = 0.0
    return categories.build_spray_bottle(p)


VARIANTS = {  # label: (long_neck, centred_neck, windex_head)
    "long necks": (True, False, False),
    "centred necks": (False, True, False),
    "long, centred necks": (True, True, False),
    "Windex-like heads, centred necks": (False, True, True),
    "Windex-like heads, long centred necks": (True, True, True),
}


def canonical_model(model: CategoryModel, space) -> CategoryModel:
    """``model`` with ``space`` and the canonical grasp as every shape's prediction."""
    return replace(model, space=space, regressor=canonical_regressor(model.template, space.q),
                   training_latent=None, training_descriptors=None, training_groups=None, training_weights=None)


def offsets(model, objects):
    return np.array([fit(model, cloud, center)[3] for cloud, center in objects])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ycb", type=Path, default=ROOT / "out" / "ycb")
    args = ap.parse_args(argv)
    committed = CategoryModel.load(ROOT / "models" / "trained" / "spray_bottle.npz")
    names = list(committed.instances)
    shape_kwargs = TrainingConfig().shape_kwargs()
    voxel = TrainingConfig().cloud_voxel
    c_index = names.index(committed.canonical_instance)

    committed_objs = [(full_cloud(load_mesh("spray_bottle", n), voxel=CLOUD_VOXEL),
                       region_center(load_annotations("spray_bottle", n), "spray_bottle")) for n in names]
    runs = {"committed bottles": (build_shape_space(
        [full_cloud(load_mesh("spray_bottle", n), voxel=voxel) for n in names], canonical_index=c_index,
        **shape_kwargs), committed_objs)}
    for label, (long_neck, centred, head) in VARIANTS.items():
        bottles = [variant_bottle(instance_seed("spray_bottle", int(n.split("_")[-1])), long_neck=long_neck,
                                  centred_neck=centred, windex_head=head) for n in names]
        space = build_shape_space([full_cloud(b.mesh, voxel=voxel) for b in bottles], canonical_index=c_index,
                                  **shape_kwargs)
        runs[label] = (space, [(full_cloud(b.mesh, voxel=CLOUD_VOXEL), b.regions["trigger"]["center"])
                               for b in bottles])
    changed = [n for n in names if load_annotations("spray_bottle", n)["params"]["deep"]]
    real = [(name, full_cloud(m, voxel=CLOUD_VOXEL), region_center(a, "spray_bottle"))
            for name, m, a in ycb_meshes(args.ycb, "spray_bottle") if region_center(a, "spray_bottle") is not None]
    print(f"deep training bottles the variants change: {', '.join(changed)}; every space predicts the canonical grasp")
    print(f"{'training bottles':36s} {'q':>3s} {'own bottles (mm)':>22s}   real: grasp to trigger (mm, x / y / z)")
    for label, (space, own_objs) in runs.items():
        model = canonical_model(committed, space)
        own = np.linalg.norm(offsets(model, own_objs), axis=1)
        cells = []
        for name, cloud, center in real:
            conf, _, res, off = fit(model, cloud, center)
            cells.append(f"{name} {np.linalg.norm(off):.1f} ({off[0]:+.0f} / {off[1]:+.0f} / {off[2]:+.0f}), "
                         f"conf {conf:.2f}")
        print(f"{label:36s} {space.q:3d} {np.median(own):8.1f} [{own.min():.1f}-{own.max():.1f}]   "
              f"{'; '.join(cells) or '(no YCB scans)'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
