"""Session 18: the figures of docs/import.md on the real AIS drill clouds (scratch checks, committed to reproduce them).

    python benchmarks/results/experiments/s18_ais_imports/normals_and_bases.py [--ycb out/ycb]

Per AIS drill (``../shared/datasets/ais_drills``): on how many points the estimated normal orientation (12
neighbours, tangent-plane propagation, turned outward) agrees with the file's own normals; whether the
Poisson surface is closed with the file's normals and with estimated ones; the normals the importer keeps;
and the support margin of the imported drill (the split ``ais``'s import into a temporary folder). Then the
support margins of the YCB drill (when prepared) and of the committed drills.
"""

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import trimesh

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.benchmark.runner import ais_drills_dir  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.data.dataset import load_annotations, load_mesh, read_annotations  # noqa: E402
from catgrasp_drake.data.importer import _poisson_surface, import_object, read_object_file  # noqa: E402
from catgrasp_drake.data.meshes import support_margin  # noqa: E402
from catgrasp_drake.data.open3d_import import import_open3d  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402


def estimated_agreement(points, normals) -> float:
    o3d = import_open3d()
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    cloud.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(12))
    cloud.orient_normals_consistent_tangent_plane(12)
    n = np.asarray(cloud.normals)
    if float(np.mean(np.einsum("ij,ij->i", n, points - points.mean(axis=0)))) < 0:
        n = -n
    return float(np.mean(np.einsum("ij,ij->i", n, normals) > 0))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ycb", default="out/ycb")
    args = ap.parse_args(argv)
    model = CategoryModel.load(default_model_path("drill"), category="drill")
    clouds = sorted(ais_drills_dir().glob("drill_*.pcd"), key=lambda f: (len(f.stem), f.stem))
    print("| AIS drill | estimated orientation agrees | closed: own normals / estimated | kept | support margin (mm) |")
    print("|---|---:|---|---|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for path in clouds:
            f = read_object_file(path)
            usable = f.normals is not None  # a file normal that is zero or NaN: none of them is used
            agree = f"{100 * estimated_agreement(f.points, f.normals):.0f} %" if usable else "(no usable normals)"
            own = _poisson_surface(f.points, f.normals).is_watertight if usable else "-"
            est = _poisson_surface(f.points, None).is_watertight
            imported = import_object(path, "drill", model=model, transform="0 0 0 0 0 0",
                                     out=Path(tmp) / path.stem, name=path.stem)
            rec = imported.record
            print(f"| {path.stem} | {agree} | {own} / {est} | {rec['source']['reconstruction']['normals']} "
                  f"| {1000 * rec['support_margin_m']:.1f} |", flush=True)
    ycb = Path(args.ycb) / "drill" / "ycb_035"
    if (ycb / "ycb_035.obj").is_file():
        m = support_margin(trimesh.load(ycb / "ycb_035.obj", force="mesh"),
                           read_annotations(ycb / "annotations.json")["center_of_mass"])
        print(f"YCB 035 drill: support margin {1000 * m:.1f} mm")
    margins = [support_margin(load_mesh("drill", f"drill_{i:02d}"), load_annotations("drill", f"drill_{i:02d}")
                              ["center_of_mass"]) for i in range(13)]
    print(f"committed drills: support margin {1000 * min(margins):.1f}-{1000 * max(margins):.1f} mm")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
