"""Does a category's generated family cover real objects? Sizes and shape-space fits of real scans (issue 19).

    python benchmarks/bench_family_coverage.py [--categories drill spray_bottle mug] [--model-dir models/trained]
                                               [--ycb out/ycb] [--real ../shared/datasets/ais_drills]

For each category it prints

* the size range (bounding-box extents x / y / z, m, canonical frame) of the
  committed instances (where everything was tuned) and of the benchmark's
  test split (seed 7919, generated under ``out/benchmark/data`` if missing);
* for each real object -- the 11 real drill clouds of the paper's authors
  (``../shared/datasets/ais_drills``, drills only; skipped when absent) and
  the YCB scans prepared by ``python -m catgrasp_drake.data.ycb --out out/ycb``
  (skipped when absent) -- its extents, which of them fall outside the
  committed family's range, and the committed model's fit of its FULL cloud
  (ray-cast + 5 mm voxel grid for meshes; the cloud itself for the real
  drills) with the 8-start yaw search: the fit confidence (``core.inference``:
  ~1 for a shape the space reproduces) and the estimated scale (1 = the size
  of the canonical instance), and the fit's residual (mean distance from the
  object's points to the fitted shape, mm: independent of the cloud's density).
  For comparison the same fit of every committed and test-split instance is
  summarised (median and range).
* where the model's grasp lands: the distance (mm) from the functional point
  of the grasp the model transfers through that fit (R(x) warped by W(x) and
  placed by the fitted pose: where the hand carries the trigger or handle
  centre) to the centre of the object's annotated functional region, for
  every object with an annotation (not the AIS clouds); its components along
  x / y / z for the real objects.

Every real object is in its canonical frame already (the AIS clouds are; the
YCB scans by their stated transforms), so the fit starts from the true
orientation up to the yaw search, as in the benchmark. Nothing is trained or
tuned here: it measures how far real objects lie from the family the models
were trained on.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.benchmark.runner import ensure_test_split  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.inference import infer_latent_pose  # noqa: E402
from catgrasp_drake.data.categories import FUNCTIONAL_REGION  # noqa: E402
from catgrasp_drake.data.dataset import CATEGORIES, list_instances, load_annotations, load_mesh, read_annotations  # noqa: E402,E501
from catgrasp_drake.data.meshes import read_mesh  # noqa: E402
from catgrasp_drake.data.pointclouds import full_cloud  # noqa: E402
from catgrasp_drake.grasping.descriptor import motion_functional_point  # noqa: E402

AIS_DRILLS = ROOT.parent / "shared" / "datasets" / "ais_drills"
CLOUD_VOXEL = 0.005


def extents(points: np.ndarray) -> np.ndarray:
    """Bounding-box extents (x, y, z) of ``points`` (m)."""
    return points.max(axis=0) - points.min(axis=0)


def fit(model: CategoryModel, cloud: np.ndarray, region_center=None) -> tuple[float, float, float, np.ndarray]:
    """(confidence, scale, residual in mm, region offset in mm) of the model's fit to a full cloud, 8-start
    yaw search.

    The residual is the mean distance from the cloud's points to the fitted shape's nearest point: unlike
    the confidence it does not depend on how densely the cloud covers the object (the real drill clouds
    are ~500 sparse scan points, the others a 5 mm voxel grid). The region offset is the transferred
    grasp's functional point minus ``region_center`` (the annotated region's centre, m, object frame;
    NaN without one)."""
    r = infer_latent_pose(model.space, cloud, yaw_candidates=8)
    residual = cKDTree(r.completed).query(cloud)[0].mean()
    offset = np.full(3, np.nan)
    if region_center is not None:
        motion = model.transfer(r.x, r.R, r.t, r.s, frame="object")
        offset = 1e3 * (motion_functional_point(motion, model.grasp_anchor_H) - np.asarray(region_center, float))
    return float(r.confidence), float(r.s), 1e3 * float(residual), offset


def region_center(annotations: dict, category: str):
    """The centre of the object's annotated functional region (m), or None."""
    region = annotations.get("regions", {}).get(FUNCTIONAL_REGION[category])
    return None if region is None else region["center"]


def ais_drill_clouds(directory: Path) -> list[tuple[str, np.ndarray]]:
    paths = sorted(directory.glob("drill_*.pcd"), key=lambda p: int(p.stem.split("_")[1]))
    return [(f"ais {p.stem}", np.loadtxt(p, skiprows=11)[:, :3]) for p in paths]


def ycb_meshes(root: Path, category: str) -> list[tuple[str, object, dict]]:
    out = []
    for d in sorted((root / category).glob("ycb_*")):
        mesh_path = d / f"{d.name}.obj"
        if mesh_path.is_file():
            out.append((d.name, read_mesh(mesh_path), read_annotations(d / "annotations.json")))
    return out


def fmt(e: np.ndarray) -> str:
    return " / ".join(f"{v:.3f}" for v in e)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--categories", nargs="+", default=list(CATEGORIES), choices=CATEGORIES)
    ap.add_argument("--model-dir", type=Path, default=ROOT / "models" / "trained")
    ap.add_argument("--ycb", type=Path, default=ROOT / "out" / "ycb")
    ap.add_argument("--real", type=Path, default=AIS_DRILLS, help="the AIS real drill clouds (drills only)")
    ap.add_argument("--data", type=Path, default=ROOT / "out" / "benchmark" / "data", help="test split location")
    args = ap.parse_args(argv)

    test_root = ensure_test_split(args.data)
    for category in args.categories:
        t0 = time.perf_counter()
        model = CategoryModel.load(args.model_dir / f"{category}.npz", category=category)
        committed = [(n, load_mesh(category, n), load_annotations(category, n)) for n in list_instances(category)]
        test = [(p.name, read_mesh(p / f"{p.name}.obj"), read_annotations(p / "annotations.json"))
                for p in sorted((test_root / category).glob(f"{category}_*"))]
        print(f"\n{category} (model {args.model_dir / f'{category}.npz'}, canonical {model.canonical_instance})")
        print(f"{'objects':28s} {'extents x / y / z (m), min .. max':45s} {'confidence':>16s} {'scale':>16s} "
              f"{'residual (mm)':>18s} {'grasp to region (mm)':>22s}")
        family_lo = family_hi = None
        for label, objs in (("committed instances", committed), ("test split (seed 7919)", test)):
            E = np.array([extents(np.asarray(m.vertices)) for _, m, _ in objs])
            fits = [fit(model, full_cloud(m, voxel=CLOUD_VOXEL), region_center(a, category)) for _, m, a in objs]
            if family_lo is None:
                family_lo, family_hi = E.min(axis=0), E.max(axis=0)
            conf, scale, res = (np.array([f[k] for f in fits]) for k in range(3))
            off = np.linalg.norm([f[3] for f in fits], axis=1)
            print(f"{label + f' ({len(objs)})':28s} {fmt(E.min(axis=0)) + ' .. ' + fmt(E.max(axis=0)):45s} "
                  f"{np.median(conf):5.2f} [{conf.min():.2f}-{conf.max():.2f}] "
                  f"{np.median(scale):5.2f} [{scale.min():.2f}-{scale.max():.2f}] "
                  f"{np.median(res):5.1f} [{res.min():.1f}-{res.max():.1f}] "
                  f"{np.median(off):7.1f} [{off.min():.1f}-{off.max():.1f}]")
        real = []
        if category == "drill" and args.real.is_dir():
            real += [(name, cloud, None) for name, cloud in ais_drill_clouds(args.real)]
        elif category == "drill":
            print(f"(no real drill clouds at {args.real}: skipped)")
        if args.ycb.is_dir():
            real += [(name, full_cloud(m, voxel=CLOUD_VOXEL), region_center(a, category))
                     for name, m, a in ycb_meshes(args.ycb, category)]
        else:
            print(f"(no prepared YCB scans at {args.ycb}: python -m catgrasp_drake.data.ycb --out {args.ycb})")
        outside_count, confs, residuals = 0, [], []
        for name, cloud, center in real:
            e = extents(cloud)
            outside = [f"{ax} {'<' if v < lo else '>'}" for ax, v, lo, hi in zip("xyz", e, family_lo, family_hi)
                       if not lo <= v <= hi]
            outside_count += bool(outside)
            conf, scale, res, off = fit(model, cloud, center)
            confs.append(conf)
            residuals.append(res)
            where = "—" if center is None else (
                f"{np.linalg.norm(off):.1f} ({off[0]:+.0f} / {off[1]:+.0f} / {off[2]:+.0f})")
            print(f"{name:28s} {fmt(e):45s} {conf:16.2f} {scale:16.3f} {res:18.1f} {where:>22s}   "
                  f"{'outside the committed family: ' + ', '.join(outside) if outside else 'inside'}")
        if real:
            print(f"{outside_count} of {len(real)} real objects lie outside the committed family's size range "
                  f"in at least one extent; real objects: confidence median {np.median(confs):.2f}, residual "
                  f"median {np.median(residuals):.1f} mm ({time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
