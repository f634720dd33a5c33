"""Point cloud files: ``.pcd`` and ``.ply`` (via open3d) and ``.npy``.

Clouds are returned as ``(N, 3)`` float64 arrays in metres.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from catgrasp_drake.core.fileio import atomic_write_bytes
from catgrasp_drake.core.validation import as_points
from catgrasp_drake.data.open3d_import import import_open3d
from catgrasp_drake.errors import InputError, ModelFileError

SUFFIXES = (".pcd", ".ply", ".npy")


def _suffix(path: Path) -> str:
    s = path.suffix.lower()
    if s not in SUFFIXES:
        raise InputError(f"{path}: unsupported point cloud format {s!r}; use one of {', '.join(SUFFIXES)}")
    return s


def read_point_cloud(path: str | os.PathLike, *, check_units: bool = True) -> np.ndarray:
    """Read a cloud file into an ``(N, 3)`` float64 array (metres).

    Raises ModelFileError (missing/unreadable file) or InputError (empty cloud,
    NaN/inf, millimetre units) with a one-line message.
    """
    path = Path(path)
    suffix = _suffix(path)
    if not path.is_file():
        raise ModelFileError(f"{path}: point cloud file not found")
    if suffix == ".npy":
        try:
            points = np.load(path, allow_pickle=False)
        except (ValueError, OSError, EOFError) as e:
            raise ModelFileError(f"{path}: unreadable .npy file ({e})") from None
    else:
        o3d = import_open3d()
        with open(path, "rb") as f:
            head = f.read(64)
        if not head:
            raise InputError(f"{path}: the file is empty")
        cloud = o3d.io.read_point_cloud(str(path), format=suffix[1:], print_progress=False)
        points = np.asarray(cloud.points, dtype=np.float64)
        if points.size == 0:
            raise InputError(f"{path}: no points could be read (empty or corrupt {suffix} file)")
    return as_points(points, str(path), check_units=check_units)


def write_point_cloud(path: str | os.PathLike, points) -> None:
    """Write an ``(N, 3)`` cloud atomically as .pcd (binary), .ply (binary) or .npy."""
    path = Path(path)
    suffix = _suffix(path)
    points = as_points(points, "points")
    if suffix == ".npy":
        import io

        buf = io.BytesIO()
        np.save(buf, points, allow_pickle=False)
        atomic_write_bytes(path, buf.getvalue())
        return
    o3d = import_open3d()
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    with tempfile.TemporaryDirectory() as tmp:
        tmp_file = Path(tmp) / f"cloud{suffix}"
        if not o3d.io.write_point_cloud(str(tmp_file), cloud, write_ascii=False, print_progress=False):
            raise ModelFileError(f"{path}: open3d could not write the cloud")
        atomic_write_bytes(path, tmp_file.read_bytes())
