"""Copies of four committed objects with three collision geometries, for issue 17's convex-pieces lever.

    pip install coacd            # not a project dependency: this probe only
    python benchmarks/results/experiments/s23_convex_pieces/make_pieces.py --out OUT_DIR

Writes OUT_DIR/{mesh,rigid,compliant}/<category>/<instance>/ (the imported-object layout that
``diagrams/handwritten_sweep.py --objects`` reads) for drill_00, drill_03, spray_bottle_00 and mug_00:

* ``mesh``: the committed SDF unchanged (the object's rigid-hydroelastic mesh, today's default);
* ``rigid``: the collision mesh replaced by CoACD's convex decomposition (threshold 0.05, at most 16
  pieces, seed 0), each piece a rigid-hydroelastic ``<drake:declare_convex/>`` mesh;
* ``compliant``: the same pieces compliant-hydroelastic (modulus 5e7 Pa, resolution hint 1 cm).

The visual mesh, mass, inertia and annotations are the committed object's in every mode.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

import trimesh

REPO = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(REPO))

from catgrasp_drake.core.fileio import atomic_write_text  # noqa: E402

OBJECTS = [("drill", "drill_00"), ("drill", "drill_03"), ("spray_bottle", "spray_bottle_00"), ("mug", "mug_00")]
MODES = ("mesh", "rigid", "compliant")
PROPERTIES = {
    "rigid": "<drake:rigid_hydroelastic/>",
    "compliant": ("<drake:compliant_hydroelastic/><drake:hydroelastic_modulus>5e7</drake:hydroelastic_modulus>"
                  "<drake:mesh_resolution_hint>0.01</drake:mesh_resolution_hint>"),
}


def make(out: Path, category: str, instance: str, mode: str) -> int:
    """Write one object in one mode; returns its number of convex pieces (0: the mesh itself)."""
    import coacd

    src = REPO / "models" / "objects" / category / instance
    dst = out / mode / category / instance
    dst.mkdir(parents=True, exist_ok=True)
    shutil.copy(src / f"{instance}.obj", dst / f"{instance}.obj")
    annotations = json.loads((src / "annotations.json").read_text())
    annotations.setdefault("category", category)
    atomic_write_text(dst / "annotations.json", json.dumps(annotations))
    sdf = (src / f"{instance}.sdf").read_text()
    if mode == "mesh":
        atomic_write_text(dst / f"{instance}.sdf", sdf)
        return 0
    mesh = trimesh.load(src / f"{instance}.obj", force="mesh")
    pieces = coacd.run_coacd(coacd.Mesh(mesh.vertices, mesh.faces), threshold=0.05, max_convex_hull=16, seed=0)
    collisions = []
    for k, (vertices, faces) in enumerate(pieces):
        piece = trimesh.Trimesh(vertices, faces)
        piece.fix_normals()
        atomic_write_text(dst / f"piece_{k}.obj", trimesh.exchange.obj.export_obj(piece))
        collisions.append(
            f'<collision name="piece_{k}"><geometry><mesh><uri>piece_{k}.obj</uri><drake:declare_convex/></mesh>'
            f"</geometry><drake:proximity_properties>{PROPERTIES[mode]}<drake:mu_static>0.9</drake:mu_static>"
            f"<drake:mu_dynamic>0.8</drake:mu_dynamic></drake:proximity_properties></collision>")
    start = sdf.index("<collision")
    end = sdf.index("</collision>") + len("</collision>")
    atomic_write_text(dst / f"{instance}.sdf", sdf[:start] + "\n".join(collisions) + sdf[end:])
    return len(pieces)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    for category, instance in OBJECTS:
        for mode in MODES:
            print(category, instance, mode, "pieces:", make(args.out, category, instance, mode), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
