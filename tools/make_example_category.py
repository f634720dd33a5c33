"""Write the example category folder ``models/examples/tankards`` (docs/import.md, "A new category").

Tankards: octagonal mugs with a heavy D-shaped handle, a shape the mug
generator never makes (its cups are round). Three meshes, the third stored
turned by 90 deg about z so that the folder shows a stated transform, a
hand-written grasp on the canonical one (the mug grasp's pose about the
handle), and ``category.yaml``::

    python tools/make_example_category.py [--out models/examples/tankards]

The meshes are a pure function of the parameters below (rewritten byte for byte).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import trimesh
from manifold3d import Manifold

from catgrasp_drake.core.fileio import atomic_write_bytes, atomic_write_text
from catgrasp_drake.data import shapes
from catgrasp_drake.data.dataset import obj_bytes

#: name -> (radius to the octagon's corners, height, wall, handle ring radius, handle tube, handle height
#: as a fraction of the height), metres.
TANKARDS = {
    "tankard_a": (0.048, 0.110, 0.006, 0.028, 0.008, 0.50),
    "tankard_b": (0.042, 0.095, 0.005, 0.024, 0.007, 0.52),
    "tankard_c": (0.054, 0.125, 0.007, 0.031, 0.009, 0.48),
}
TURNED = {"tankard_c": 90.0}  # stored turned about z by this (deg): category.yaml states the way back


def tankard(radius: float, height: float, wall: float, ring: float, tube: float, at: float):
    """``(mesh, handle box (centre, half extents))`` of a tankard in the canonical frame (handle on +y)."""
    turn = 22.5  # a flat face of the octagon toward +y
    outer = Manifold.cylinder(height, radius, radius, 8).rotate((0.0, 0.0, turn))
    cavity = Manifold.cylinder(height, radius - wall, radius - wall, 8).rotate((0.0, 0.0, turn)) \
        .translate((0.0, 0.0, 1.5 * wall))
    apothem = radius * np.cos(np.radians(22.5))
    zc = at * height
    handle = shapes.partial_torus_yz((0.0, 0.0, 0.0), ring, tube, tube, 200.0, -10.0, segments=32)
    handle = handle.translate((0.0, apothem - 0.2 * ring, zc))
    handle = handle - Manifold.cylinder(height, radius - 0.5 * wall, radius - 0.5 * wall, 8).rotate((0.0, 0.0, turn))
    solid = outer - cavity + handle
    xmin, ymin, zmin, xmax, ymax, zmax = handle.bounding_box()
    lo, hi = np.array([xmin, max(ymin, apothem), zmin]), np.array([xmax, ymax, zmax])
    return shapes.to_trimesh(solid), ((lo + hi) / 2, (hi - lo) / 2)


CATEGORY_YAML = """\
# An example category folder (docs/import.md, "A new category"): tankards, octagonal mugs with a heavy
# D-shaped handle. Written by tools/make_example_category.py. Train on it with
#   catgrasp train --objects models/examples/tankards
name: tankard
like: mug                  # a handle category: the mug's judge, constraint, hand postures and scenario
description: octagonal mugs with a heavy D-shaped handle
canonical: tankard_a.obj
region:                    # the handle of tankard_a, in its file frame (m)
  center: {center}
  half_extents: {half}
grasp: grasp.yaml
density_kg_m3: 1900        # stoneware, as the mugs
transforms:
  tankard_c.obj: "0 0 -90 0 0 0"   # stored turned 90 deg about z: canonical <- file
"""

GRASP_YAML = """\
# The hand-written grasp of the example tankards, on tankard_a: the project's mug grasp
# (models/grasps/mug_handwritten.yaml, session 12) about the handle's centre, unchanged.
category: mug
description: power grasp around the handle, tankard upright
anchor: {region: handle}
grasp:
  position: [0.12132, 0.05246, 0.0266]
  fingers: [-0.99349, -0.11387, 0.00351]
  palm: [0.09359, -0.83339, -0.54471]
pregrasp_distance: 0.08
postures: mug
posture_overrides:
  closed: {svh_thumb_flexion: 0.97, svh_index_proximal: 0.6809, svh_index_distal: 1.0075,
           svh_middle_proximal: 0.7985, svh_middle_distal: 1.334, svh_ring: 0.856, svh_pinky: 0.65,
           svh_finger_spread: 0.0822}
lift_height: 0.12
hold_time: 2.0
"""


def write_example(out: Path) -> dict:
    """Write the folder; returns each tankard's true handle box (canonical frame) for checking the import."""
    out.mkdir(parents=True, exist_ok=True)
    truth = {}
    for name, p in TANKARDS.items():
        mesh, (c, h) = tankard(*p)
        truth[name] = {"center": c, "half_extents": h}
        if name in TURNED:
            mesh = mesh.copy()
            mesh.apply_transform(trimesh.transformations.rotation_matrix(np.radians(TURNED[name]), (0, 0, 1)))
        atomic_write_bytes(out / f"{name}.obj", obj_bytes(mesh))
    c, h = truth["tankard_a"]["center"], truth["tankard_a"]["half_extents"]
    fmt = lambda v: "[" + ", ".join(f"{x:.4f}" for x in v) + "]"  # noqa: E731
    atomic_write_text(out / "category.yaml", CATEGORY_YAML.format(center=fmt(c), half=fmt(h)))
    atomic_write_text(out / "grasp.yaml", GRASP_YAML)
    return truth


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "models" / "examples"
                    / "tankards")
    args = ap.parse_args()
    write_example(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
