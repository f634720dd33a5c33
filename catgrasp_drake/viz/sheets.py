"""Contact sheets of the embedded data set and of the aligned YCB objects (README pictures)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import trimesh

from catgrasp_drake.data.dataset import (
    CATEGORIES,
    CATEGORY_COLORS,
    instance_mesh_path,
    list_instances,
    load_annotations,
    obj_bytes,
    read_annotations,
)
from catgrasp_drake.data.ycb import ycb_annotations, ycb_instances, ycb_mesh_path, ycb_object
from catgrasp_drake.viz.render import contact_sheet, render_mesh

_COLORS = {"drill": (0.85, 0.45, 0.1, 1.0), "spray_bottle": (0.25, 0.5, 0.85, 1.0), "mug": (0.8, 0.8, 0.75, 1.0)}


def dataset_contact_sheet(path: str | os.PathLike, *, categories=None, tile: int = 200, columns: int = 9) -> None:
    """Render every instance of ``categories`` (default: all) into one PNG, one row block per category.

    Tiles of one category share a scale so relative sizes are visible.
    """
    images, labels = [], []
    for category in categories or CATEGORIES:
        names = list_instances(category)
        lo = np.min([load_annotations(category, n)["bbox_min"] for n in names], axis=0)
        hi = np.max([load_annotations(category, n)["bbox_max"] for n in names], axis=0)
        center = (lo + hi) / 2
        for name in names:
            bounds = (center - (hi - lo) / 2, center + (hi - lo) / 2)
            images.append(render_mesh(instance_mesh_path(category, name), color=_COLORS[category],
                                      size=(tile, tile), bounds=bounds))
            labels.append(name)
        while len(images) % columns:  # start each category on a new row
            images.append(np.full_like(images[-1], 255))
            labels.append("")
    contact_sheet(images, labels, path, columns=columns)


# ----------------------------------------------------------------------------- YCB alignment
REFERENCE_INSTANCE = {"drill": "drill_00", "spray_bottle": "spray_bottle_00", "mug": "mug_00"}
_SHEET_VIEWS = ((0.0, 10.0), (35.0, 20.0))  # (azimuth, elevation) in degrees; +y points right


def _overlay_regions(img: np.ndarray, regions: dict, bounds, view, size, tmp: Path) -> np.ndarray:
    """Blend each region box (rendered alone with the same camera) in semi-transparent red."""
    out = img.astype(float)
    for k, reg in enumerate(regions.values()):
        box = trimesh.creation.box(extents=2 * np.asarray(reg["half_extents"], float))
        box.apply_translation(np.asarray(reg["center"], float))
        path = tmp / f"region_{k}.obj"
        path.write_bytes(obj_bytes(box))
        mask = render_mesh(path, size=size, azimuth_deg=view[0], elevation_deg=view[1], bounds=bounds).min(axis=2) < 250
        out[mask] = 0.45 * out[mask] + 0.55 * np.array([230.0, 20.0, 20.0])
    return out.astype(np.uint8)


def ycb_contact_sheet(root: str | os.PathLike | None, path: str | os.PathLike, *,
                      size: tuple[int, int] = (240, 240)) -> None:
    """Contact sheet: each aligned YCB object next to its category's reference instance.

    Per row: the YCB object from the side (+x; +y points right) and from the
    default 3/4 view, then the embedded reference instance from the same two
    views, both at the same scale (one camera framing the union of their
    bounding boxes); functional regions blended in red.
    """
    images, labels = [], []
    with tempfile.TemporaryDirectory(prefix="catgrasp_ycb_sheet_") as tmp:
        tmp = Path(tmp)
        for category, name in ycb_instances():
            ann = ycb_annotations(name, root)
            ref = REFERENCE_INSTANCE[category]
            ref_ann = load_annotations(category, ref)
            rows = [(ycb_mesh_path(name, root), ann, f"{name} ({ycb_object(name).ycb_id[4:]})"),
                    (instance_mesh_path(category, ref), ref_ann, f"{ref} (embedded)")]
            lo = np.minimum(ann["bbox_min"], ref_ann["bbox_min"])
            hi = np.maximum(ann["bbox_max"], ref_ann["bbox_max"])
            for mesh_path, a, label in rows:
                color = tuple(c for c in CATEGORY_COLORS[category]) + (1.0,)
                for view in _SHEET_VIEWS:
                    img = render_mesh(mesh_path, color=color, size=size, azimuth_deg=view[0],
                                      elevation_deg=view[1], bounds=(lo, hi))
                    img = _overlay_regions(img, a.get("regions", {}), (lo, hi), view, size, tmp)
                    tag = "" if a.get("functional", True) else ", no trigger"
                    labels.append(f"{label}{tag}" if view == _SHEET_VIEWS[0] else f"az {view[0]:.0f} el {view[1]:.0f}")
                    images.append(img)
    contact_sheet(images, labels, path, columns=4,
                  title="YCB objects aligned to the canonical frames (left) vs embedded instance (right); "
                        "+y right; red: functional region")


# ----------------------------------------------------------------------------- an imported object
_IMPORT_VIEWS = ((0.0, 10.0), (35.0, 20.0), (0.0, 80.0))  # side (+y right), 3/4, from above


def import_sheet(directory: str | os.PathLike, path: str | os.PathLike | None = None, *,
                 size: tuple[int, int] = (240, 240), reference_dir: str | os.PathLike | None = None) -> Path:
    """The alignment of an imported object (``catgrasp import-object``) at a glance; returns the PNG's path.

    Top row: the object in its canonical frame from the side (+x; +y, the
    functional direction, points right), a 3/4 view and from above; bottom
    row: the category's reference instance from the same cameras at the same
    scale (``reference_dir``: an imported object's directory instead, e.g. a
    category folder's canonical instance). Functional regions blended in red.
    Written atomically to ``path`` (default ``<directory>/alignment.png``).
    """
    directory = Path(directory)
    ann = read_annotations(directory / "annotations.json")
    name, category = ann["instance"], ann["category"]
    if reference_dir is None:
        ref = REFERENCE_INSTANCE[category]
        ref_ann, ref_mesh, ref_label = load_annotations(category, ref), instance_mesh_path(category, ref), "embedded"
    else:
        ref_ann = read_annotations(Path(reference_dir) / "annotations.json")
        ref = ref_ann["instance"]
        ref_mesh, ref_label = Path(reference_dir) / f"{ref}.obj", "canonical"
    lo = np.minimum(ann["bbox_min"], ref_ann["bbox_min"])
    hi = np.maximum(ann["bbox_max"], ref_ann["bbox_max"])
    color = tuple(CATEGORY_COLORS[category]) + (1.0,)
    record = ann.get("import", {})
    tf, fit = record.get("transform", {}), record.get("fit") or {}
    how = (f"automatic: confidence {fit['confidence']:.2f}, scale {fit['scale']:.2f}" if tf.get("automatic")
           else "stated transform")
    rpy, xyz = tf.get("rpy_deg"), tf.get("xyz_m")
    extra = (("rpy " + " ".join(f"{v:.1f}" for v in rpy) + " deg") if rpy else "",
             ("xyz " + " ".join(f"{1000 * v:.1f}" for v in xyz) + " mm (canonical <- file)") if xyz else "")
    images, labels = [], []
    with tempfile.TemporaryDirectory(prefix="catgrasp_import_sheet_") as tmp:
        tmp = Path(tmp)
        for mesh_path, a, label in ((directory / f"{name}.obj", ann, f"{name} (imported)"),
                                    (ref_mesh, ref_ann, f"{ref} ({ref_label})")):
            for k, view in enumerate(_IMPORT_VIEWS):
                img = render_mesh(mesh_path, color=color, size=size, azimuth_deg=view[0], elevation_deg=view[1],
                                  bounds=(lo, hi))
                images.append(_overlay_regions(img, a.get("regions", {}), (lo, hi), view, size, tmp))
                labels.append(label if k == 0 else extra[k - 1] if a is ann else "")
    out = Path(path) if path is not None else directory / "alignment.png"
    regions = ", ".join(ann.get("regions", {})) or "no functional region"
    kind = ann["family"]["name"] if "family" in ann else category
    contact_sheet(images, labels, out, columns=len(_IMPORT_VIEWS),
                  title=f"{name} as a {kind} ({how}); +y right, z up; red: {regions}")
    return out
