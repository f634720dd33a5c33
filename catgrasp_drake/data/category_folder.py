"""A new category from a folder of meshes and one hand-written grasp (docs/import.md, "A new category").

A category folder holds the meshes of a family of objects, one of them the
canonical instance, a hand-written grasp on it, and ``category.yaml``::

    name: tankard                  # the category's name (file-safe)
    like: mug                      # the built-in category whose functional type it shares: its judge
                                   # (handle: hand on the handle, upright; trigger: the index presses it),
                                   # grasp constraint, hand postures and station scenario
    canonical: tankard_a.obj       # the canonical instance, one of the folder's meshes
    region:                        # its functional region (the like-category's: handle or trigger), an
      center: [0.0, 0.07, 0.05]    # axis-aligned box in the canonical mesh's file frame (m); half_extents
      half_extents: [0.01, 0.016, 0.03]   # optional (default: the importer's for that region)
    grasp: grasp.yaml              # the hand-written grasp on the canonical instance (the format of
                                   # models/grasps/<category>_handwritten.yaml, anchored on the region)
    density_kg_m3: 1900            # optional: mass = density x volume (default: the like-category's)
    transforms:                    # optional, per mesh: canonical <- file, "rx ry rz x y z" (deg, m)
      tankard_c.stl: "0 0 90 0 0 0"

A new category has no shape space to align its meshes to yet, so they come in
its canonical frame (docs/design.md section 3: z up, base on z = 0, the
functional part on +y) or with a stated transform; each is levelled onto its
nearest resting pose as the importer does. :func:`import_category` imports
every mesh with :func:`catgrasp_drake.data.importer.import_mesh` (watertight
solid, flat base, mass, SDF) as an object of the like-category and gives
every instance but the canonical its functional region by non-rigid CPD from
the canonical shape (the kernel width of training, 0.10 m): the region box's
corners deformed by the fitted field. ``catgrasp train --objects FOLDER``
then trains on these objects alone, with the folder's canonical instance and
grasp (``catgrasp_drake.training.train_category_folder``).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from catgrasp_drake.core.cpd import nonrigid_cpd
from catgrasp_drake.core.deformation import deform_points
from catgrasp_drake.core.fileio import atomic_write_text
from catgrasp_drake.data.categories import DENSITY_KG_M3, FUNCTIONAL_REGION, REGION_MARGIN_M
from catgrasp_drake.data.dataset import CATEGORIES, read_annotations
from catgrasp_drake.data.importer import (
    DEFAULT_HALF_EXTENTS_M,
    MESH_SUFFIXES,
    ImportedObject,
    box_around,
    box_points,
    default_name,
    import_mesh,
    parse_transform,
    read_object_file,
)
from catgrasp_drake.data.pointclouds import full_cloud
from catgrasp_drake.errors import InputError

CATEGORY_FILE = "category.yaml"
#: Kernel width (m) of the CPD that carries the canonical region onto the other instances: training's
#: (``training.TrainingConfig.beta``), whose warped handles and triggers land 3.8-4.3 mm from the annotated ones.
REGION_CPD_BETA_M = 0.10
#: Voxel (m) of the clouds registered for the region transfer (training's cloud voxel).
REGION_CPD_VOXEL_M = 0.01
_FIELDS = {"name", "like", "canonical", "region", "grasp", "density_kg_m3", "transforms", "description"}
_NAME = re.compile(r"^[a-z][a-z0-9_]{0,31}$")


@dataclass(frozen=True)
class CategoryFolder:
    """A parsed, checked category folder (module docstring). Paths are absolute."""

    folder: Path
    name: str
    like: str
    canonical: Path
    meshes: tuple[Path, ...]  # the canonical first
    region: dict  # {"center", "half_extents"} in the canonical mesh's file frame (m)
    grasp: Path
    density_kg_m3: float
    transforms: dict = field(default_factory=dict)  # mesh path -> "rx ry rz x y z"
    description: str = ""

    @property
    def region_name(self) -> str:
        return FUNCTIONAL_REGION[self.like]

    def instance_name(self, mesh: Path) -> str:
        return default_name(mesh)


def _vector(value, what: str, where: str) -> list[float]:
    try:
        v = [float(x) for x in value]
    except (TypeError, ValueError):
        v = []
    if len(v) != 3 or not all(np.isfinite(v)):
        raise InputError(f"{where}: {what}: expected three numbers (m), got {value!r}")
    if max(abs(x) for x in v) > 2.0:
        raise InputError(f"{where}: {what}: {max(abs(x) for x in v):g} m from the origin; expected metres")
    return v


def read_category_folder(folder) -> CategoryFolder:
    """Parse and check ``folder``/category.yaml and the meshes it names; InputError (one line) naming the problem."""
    folder = Path(folder).resolve()
    where = f"{folder}/{CATEGORY_FILE}"
    if not folder.is_dir():
        raise InputError(f"{folder}: no such category folder")
    try:
        spec = yaml.safe_load((folder / CATEGORY_FILE).read_text())
    except FileNotFoundError:
        raise InputError(f"{folder}: no {CATEGORY_FILE} (a category folder names its canonical mesh, functional "
                         "region and grasp there; docs/import.md)") from None
    except (OSError, yaml.YAMLError) as e:
        raise InputError(f"{where}: unreadable ({' '.join(str(e).split())})") from None
    if not isinstance(spec, dict):
        raise InputError(f"{where}: expected a mapping of {sorted(_FIELDS)}")
    unknown = sorted(set(spec) - _FIELDS)
    if unknown:
        raise InputError(f"{where}: unknown field(s) {unknown}; known: {sorted(_FIELDS)}")
    missing = [k for k in ("name", "like", "canonical", "region", "grasp") if k not in spec]
    if missing:
        raise InputError(f"{where}: missing field(s) {missing}")
    name, like = spec["name"], spec["like"]
    if not isinstance(name, str) or not _NAME.match(name):
        raise InputError(f"{where}: name {name!r}: expected lower-case letters, digits and _ (<= 32)")
    if like not in CATEGORIES:
        raise InputError(f"{where}: like {like!r}: unknown category; known: {', '.join(CATEGORIES)}")
    meshes = sorted(p for p in folder.iterdir() if p.suffix.lower() in MESH_SUFFIXES and p.is_file())
    canonical = folder / str(spec["canonical"])
    if canonical not in meshes:
        raise InputError(f"{where}: canonical {spec['canonical']!r} is not one of the folder's meshes "
                         f"({', '.join(p.name for p in meshes) or 'none'})")
    if len(meshes) < 2:
        raise InputError(f"{folder}: a category needs at least 2 meshes ({', '.join(MESH_SUFFIXES)}), found "
                         f"{len(meshes)}")
    names = [default_name(p) for p in meshes]
    if len(set(names)) != len(names):
        raise InputError(f"{folder}: two meshes give the same instance name ({', '.join(names)})")
    region = spec["region"]
    if not isinstance(region, dict) or "center" not in region:
        raise InputError(f"{where}: region: expected {{center: [x, y, z], half_extents: [hx, hy, hz]}}")
    region_name = FUNCTIONAL_REGION[like]
    half = region.get("half_extents", DEFAULT_HALF_EXTENTS_M[region_name])
    region = {"center": _vector(region["center"], "region.center", where),
              "half_extents": _vector(half, "region.half_extents", where)}
    if min(region["half_extents"]) <= 0:
        raise InputError(f"{where}: region.half_extents must be positive, got {region['half_extents']}")
    grasp = folder / str(spec["grasp"])
    if not grasp.is_file():
        raise InputError(f"{where}: grasp {spec['grasp']!r}: no such file in the folder")
    density = spec.get("density_kg_m3", DENSITY_KG_M3[like])
    if not isinstance(density, (int, float)) or not 10.0 <= float(density) <= 25000.0:
        raise InputError(f"{where}: density_kg_m3 {density!r}: expected 10..25000 kg/m^3")
    transforms = spec.get("transforms") or {}
    if not isinstance(transforms, dict):
        raise InputError(f"{where}: transforms: expected a mapping mesh -> 'rx ry rz x y z'")
    stated = {}
    for mesh_name, text in transforms.items():
        path = folder / str(mesh_name)
        if path not in meshes:
            raise InputError(f"{where}: transforms: {mesh_name!r} is not one of the folder's meshes")
        parse_transform(text)  # InputError naming a malformed transform
        stated[path] = text
    ordered = (canonical, *[p for p in meshes if p != canonical])
    return CategoryFolder(folder, name, like, canonical, ordered, region, grasp, float(density), stated,
                          str(spec.get("description", "")))


def _stated(cat: CategoryFolder, mesh: Path) -> str:
    return cat.transforms.get(mesh, "0 0 0 0 0 0")


def transfer_region_by_cpd(canonical_points, region: dict, instance_points, *, beta: float = REGION_CPD_BETA_M
                           ) -> dict:
    """``region`` (a box on the canonical shape) carried onto an instance: non-rigid CPD from
    ``canonical_points`` (M, 3) to ``instance_points`` (N, 3), both in the category's canonical frame (m),
    the box's corners and centre deformed by the fitted field; the deformed corners' axis-aligned box."""
    r = nonrigid_cpd(canonical_points, instance_points, beta=beta)
    return box_around(deform_points(canonical_points, r.W, beta, box_points(region)))


def import_category(folder, out=None) -> list[ImportedObject]:
    """Import every mesh of a category folder (module docstring) into ``out`` (default
    ``out/categories/<name>``), one object directory per mesh, the canonical first; returns them with their
    regions. The objects are of the like-category; their annotations name the new category (``family``)."""
    cat = read_category_folder(folder)
    out = Path(out) if out is not None else Path("out") / "categories" / cat.name
    region_name = cat.region_name
    grown = REGION_MARGIN_M.get(region_name, 0.0)
    family = {"family": {"name": cat.name, "like": cat.like, "folder": str(cat.folder),
                         "canonical": cat.instance_name(cat.canonical), "grasp": str(cat.grasp)}}
    imported = []
    for mesh_path in cat.meshes:
        f = read_object_file(mesh_path)
        if f.kind != "mesh":
            raise InputError(f"{mesh_path}: a category folder holds meshes; this file has no faces")
        name = cat.instance_name(mesh_path)
        is_canonical = mesh_path == cat.canonical
        regions = {region_name: dict(cat.region) | {"grown_by": grown}} if is_canonical else None
        obj = import_mesh(f.mesh, cat.like, name, transform=_stated(cat, mesh_path), regions=regions,
                          out=out / name, source={"file": str(mesh_path), "sha256": f.sha256, "kind": f.kind,
                                                  "faces": int(len(f.mesh.faces))},
                          extra=family, what=str(mesh_path), density_kg_m3=cat.density_kg_m3)
        imported.append(obj)
    canonical = imported[0]
    source = full_cloud(canonical.mesh, voxel=REGION_CPD_VOXEL_M)
    box = canonical.regions[region_name]
    done = [canonical]
    for obj in imported[1:]:
        region = transfer_region_by_cpd(source, box, full_cloud(obj.mesh, voxel=REGION_CPD_VOXEL_M))
        region |= {"grown_by": grown, "transferred_from": canonical.name}
        done.append(_with_region(obj, region_name, region))
    return done


def _with_region(obj: ImportedObject, region_name: str, region: dict) -> ImportedObject:
    """``obj`` with its functional region written into its annotations.json (atomically)."""
    path = obj.directory / "annotations.json"
    ann = read_annotations(path)
    regions = {region_name: region}
    ann["regions"] = regions
    ann["functional"] = True
    ann["import"]["region_source"] = f"transferred from {region['transferred_from']} by non-rigid CPD " \
                                     f"(beta {REGION_CPD_BETA_M} m)"
    atomic_write_text(path, json.dumps(ann, indent=2, sort_keys=True) + "\n")
    return ImportedObject(obj.name, obj.category, obj.directory, obj.mesh, obj.mass_kg, regions, obj.alignment,
                          ann["import"])
