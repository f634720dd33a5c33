"""Session 48 probe: does the mug shape space reach the handles of mugs it never saw? (tuning split, no simulation)

    python benchmarks/results/experiments/s48_mug_capacity/capacity.py [--extra 0 27] [--beta 0.1 0.05] \
        [--split-seed VAL] [--out FILE.json]

Shape spaces built as ``catgrasp train mug`` builds them (canonical mug_00, the committed model's CPD beta and
95 % variance) from the 13 committed mugs plus ``extra`` more draws of the committed data set's own seed (indices
13, 14, ...: training data the generator would have written with a larger INSTANCE_COUNTS, never a test, fresh or
validation seed). Each space fits the FULL cloud (ray-cast, 5 mm voxels) of every validation mug (a tuning set)
with the 8-start yaw search, as ``bench_family_coverage.py`` fits real objects, and reports per mug: the fit's yaw
error (deg), the mean distance of the cloud's points to the completed shape (mm), the same over the points of the
annotated handle region only (mm), and the share of handle points farther than 8 mm.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import VAL_SEED, ensure_test_split  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.inference import infer_latent_pose  # noqa: E402
from catgrasp_drake.core.shape_space import build_shape_space  # noqa: E402
from catgrasp_drake.data.categories import generate_instance  # noqa: E402
from catgrasp_drake.data.dataset import instance_clouds, instance_seed, read_annotations  # noqa: E402
from catgrasp_drake.data.meshes import read_mesh  # noqa: E402
from catgrasp_drake.data.pointclouds import full_cloud  # noqa: E402
from catgrasp_drake.station.judge import points_in_region  # noqa: E402

CLOUD_VOXEL = 0.005


def extra_clouds(n: int, voxel: float) -> list[np.ndarray]:
    """Full clouds of ``n`` more mugs of the committed data set's seed (indices 13, 14, ...)."""
    out = []
    for i in range(13, 13 + n):
        gen = generate_instance("mug", np.random.default_rng(instance_seed("mug", i)))
        out.append(full_cloud(gen.mesh, voxel=voxel))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--extra", type=int, nargs="+", default=[0, 27])
    ap.add_argument("--beta", type=float, nargs="+", default=None)
    ap.add_argument("--data", default="out/benchmark/data")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    model = CategoryModel.load("models/trained/mug.npz")
    kw = {"variance": model.params["variance"]}
    betas = args.beta or [model.params["beta"]]
    root = ensure_test_split(args.data, VAL_SEED) / "mug"
    val = sorted(p.name for p in root.iterdir() if p.is_dir())
    base = instance_clouds("mug", list(model.instances), model.params["cloud_voxel"])
    rows = []
    for beta in betas:
        for n in args.extra:
            clouds = base + extra_clouds(n, model.params["cloud_voxel"])
            space = build_shape_space(clouds, canonical_index=0, beta=beta, **kw)
            for name in val:
                mesh = read_mesh(root / name / f"{name}.obj")
                ann = read_annotations(root / name / "annotations.json")
                cloud = full_cloud(mesh, voxel=CLOUD_VOXEL)
                r = infer_latent_pose(space, cloud, yaw_candidates=8)
                d = cKDTree(r.completed).query(cloud)[0]
                handle = (points_in_region(cloud, np.eye(4), ann["regions"]["handle"], 0.0)
                          if "handle" in ann.get("regions", {}) else None)
                yaw = float(np.degrees(np.arctan2(r.R[1, 0], r.R[0, 0])))
                row = {"beta": beta, "extra": n, "q": space.q, "instance": name, "yaw_deg": round(yaw, 1),
                       "residual_mm": round(1e3 * d.mean(), 2), "scale": round(float(r.s), 3),
                       "confidence": round(float(r.confidence), 3)}
                if handle is not None and handle.any():
                    row["handle_residual_mm"] = round(1e3 * d[handle].mean(), 2)
                    row["handle_far_share"] = round(float((d[handle] > 0.008).mean()), 3)
                rows.append(row)
                print(json.dumps(row), flush=True)
    if args.out:
        Path(args.out).write_text("".join(json.dumps(r) + "\n" for r in rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
