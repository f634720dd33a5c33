"""Mesh reading with clear errors."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import trimesh

from catgrasp_drake.core.validation import MAX_OBJECT_EXTENT_M
from catgrasp_drake.errors import InputError, ModelFileError, one_line


def read_mesh(path: str | os.PathLike, *, require_watertight: bool = False) -> trimesh.Trimesh:
    """Read a triangle mesh (.obj/.stl/.ply/...) in metres as one ``trimesh.Trimesh``.

    Raises ModelFileError if the file is missing, unreadable or has no
    triangles, and InputError if it is not watertight (when required) or looks
    like millimetres.
    """
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: expected a mesh file name, got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise ModelFileError(f"{path}: mesh file not found")
    try:
        mesh = trimesh.load(str(path), force="mesh", process=True)
    except Exception as e:  # trimesh raises many types for corrupt files
        raise ModelFileError(f"{path}: unreadable mesh ({one_line(e, limit=120)})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ModelFileError(f"{path}: the file holds no triangles")
    if not np.all(np.isfinite(mesh.vertices)):
        raise ModelFileError(f"{path}: mesh has NaN or inf vertices")
    extent = float(np.linalg.norm(mesh.extents))
    if extent > MAX_OBJECT_EXTENT_M:
        raise InputError(f"{path}: mesh spans {extent:.3g} units; expected metres. "
                         "Is it in millimetres? Scale by 0.001.")
    if require_watertight and not mesh.is_watertight:
        raise InputError(f"{path}: mesh is not watertight (has holes); repair it or use a closed mesh")
    return mesh
