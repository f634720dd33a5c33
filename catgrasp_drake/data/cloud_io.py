"""Point cloud files: ``.pcd`` and ``.ply`` (via open3d) and ``.npy``.

Clouds are returned as ``(N, 3)`` float64 arrays in metres.
"""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path

import numpy as np

from catgrasp_drake.core.fileio import atomic_write_bytes
from catgrasp_drake.core.validation import as_points
from catgrasp_drake.data.open3d_import import import_open3d
from catgrasp_drake.errors import InputError, ModelFileError, one_line

SUFFIXES = (".pcd", ".ply", ".npy")


def _suffix(path: Path) -> str:
    s = path.suffix.lower()
    if s not in SUFFIXES:
        raise InputError(f"{path}: unsupported point cloud format {s!r}; use one of {', '.join(SUFFIXES)}")
    return s


_HEADER_BYTES = 1 << 16
_PLY_SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2, "int16": 2, "uint16": 2,
              "int": 4, "uint": 4, "int32": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}


def _too_short(path: Path, n: int, need: int, have: int) -> ModelFileError:
    return ModelFileError(f"{path}: the header declares {n} points ({need} bytes of data) but the file holds "
                          f"{have}; the file is truncated or corrupt")


def _check_declared_size(path: Path, suffix: str) -> None:
    """Refuse a file whose header declares more points than the file can hold.

    A corrupt or hostile header (``POINTS 1000000000000``) otherwise makes the
    reader allocate terabytes, or (ASCII .pcd) pad a one-line file with 10^8
    zero points. Headers this check cannot parse are left to the reader.
    """
    size = path.stat().st_size
    if suffix == ".npy":
        with open(path, "rb") as f:
            try:
                version = np.lib.format.read_magic(f)
                if version == (1, 0):
                    shape, _, dtype = np.lib.format.read_array_header_1_0(f)
                elif version == (2, 0):
                    shape, _, dtype = np.lib.format.read_array_header_2_0(f)
                else:
                    return
            except Exception as e:  # ValueError, SyntaxError, tokenize errors...: a damaged header
                raise ModelFileError(f"{path}: unreadable .npy file ({one_line(e)})") from None
            if dtype.hasobject:
                raise ModelFileError(f"{path}: the .npy file holds Python objects (would need pickle); "
                                     "save a numeric (N, 3) array")
            n = int(np.prod(shape, dtype=np.float64)) if len(shape) else 1
            need, have = n * dtype.itemsize, size - f.tell()
            if need > have:
                raise _too_short(path, shape[0] if len(shape) else 1, need, have)
        return
    with open(path, "rb") as f:
        head = f.read(_HEADER_BYTES)
    if suffix == ".pcd":
        try:
            _check_pcd(path, head, size)
        except (ValueError, IndexError, KeyError):  # open3d reads garbage from a damaged header: refuse it
            raise ModelFileError(f"{path}: unreadable .pcd header (FIELDS/SIZE/POINTS/DATA); the file is corrupt "
                                 "or truncated") from None
    else:
        try:
            _check_ply(path, head, size)
        except (ValueError, IndexError, KeyError):
            raise ModelFileError(f"{path}: unreadable .ply header; the file is corrupt or truncated") from None


def _data_lines(path: Path, offset: int) -> int:
    """Non-empty lines after byte ``offset`` (an ASCII file's data records)."""
    with open(path, "rb") as f:
        f.seek(offset)
        data = f.read()
    return sum(1 for line in data.split(b"\n") if line.strip())


def _check_pcd(path: Path, head: bytes, size: int) -> None:
    fields, offset = {}, 0
    for line in head.split(b"\n"):
        offset += len(line) + 1
        words = line.decode("ascii").split()
        if not words or words[0].startswith("#"):
            continue
        fields[words[0].upper()] = words[1:]
        if words[0].upper() == "DATA":
            break
    else:
        raise ValueError("no DATA line")
    n = int(fields["POINTS"][0]) if "POINTS" in fields else int(fields["WIDTH"][0]) * int(fields["HEIGHT"][0])
    sizes = [int(v) for v in fields["SIZE"]]
    counts = [int(v) for v in fields.get("COUNT", ["1"] * len(sizes))]
    row = sum(a * b for a, b in zip(sizes, counts))
    have = size - offset
    kind = fields["DATA"][0].lower()
    if kind == "binary":
        if n * row > have:
            raise _too_short(path, n, n * row, have)
    elif kind == "ascii":
        lines = _data_lines(path, offset)
        if n > lines:
            raise ModelFileError(f"{path}: the header declares {n} points but the file has {lines} data lines; "
                                 "the file is truncated or corrupt")
    elif kind == "binary_compressed":
        raw = head[offset:offset + 8]
        if len(raw) < 8:
            raise _too_short(path, n, 8, have)
        compressed, uncompressed = (int.from_bytes(raw[i:i + 4], "little") for i in (0, 4))
        if uncompressed != n * row or compressed + 8 > have:
            raise ModelFileError(f"{path}: compressed .pcd data do not match the header ({n} points); the file is "
                                 "truncated or corrupt")


def _check_ply(path: Path, head: bytes, size: int) -> None:
    if not head.startswith(b"ply"):
        return  # not a PLY file at all: the reader says it read no points
    end = head.find(b"end_header")
    if end < 0:
        raise ValueError("no end_header")
    offset = head.index(b"\n", end) + 1
    fmt, n, props, current = None, None, [], None
    for line in head[:end].decode("ascii").splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            current = words[1]
            if current == "vertex":
                n = int(words[2])
        elif words[0] == "property" and current == "vertex":
            props.append(words[1:])
    if n is None or fmt is None:
        raise ValueError("no vertex element or format")
    have = size - offset
    if fmt == "ascii":
        lines = _data_lines(path, offset)
        if n > lines:
            raise ModelFileError(f"{path}: the header declares {n} points but the file has {lines} data lines; "
                                 "the file is truncated or corrupt")
    elif all(p[0] != "list" for p in props):
        row = sum(_PLY_SIZES[p[0]] for p in props)
        if n * row > have:
            raise _too_short(path, n, n * row, have)


def read_point_cloud(path: str | os.PathLike, *, check_units: bool = True, with_normals: bool = False):
    """Read a cloud file into an ``(N, 3)`` float64 array (metres).

    ``with_normals``: return ``(points, normals)``, the normals (N, 3), unit length, as the file stores
    them (.pcd/.ply ``normal_x`` ... fields), or None when the file has none (or any is zero or NaN).
    Raises ModelFileError (missing/unreadable file) or InputError (empty cloud,
    NaN/inf, millimetre units) with a one-line message.
    """
    normals = None
    path = _as_path(path)
    suffix = _suffix(path)
    if not path.is_file():
        raise ModelFileError(f"{path}: point cloud file not found")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: the file is empty")
    _check_declared_size(path, suffix)
    if suffix == ".npy":
        try:
            points = np.load(path, allow_pickle=False)
        except Exception as e:  # ValueError, OSError, EOFError, MemoryError...: a damaged file
            raise ModelFileError(f"{path}: unreadable .npy file ({one_line(e)})") from None
    else:
        o3d = import_open3d()
        try:
            with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
                cloud = o3d.io.read_point_cloud(str(path), format=suffix[1:], print_progress=False)
        except (MemoryError, RuntimeError) as e:
            raise ModelFileError(f"{path}: unreadable {suffix} file ({type(e).__name__}: {str(e)[:80]})") from None
        points = np.asarray(cloud.points, dtype=np.float64)
        if points.size == 0:
            raise InputError(f"{path}: no points could be read (empty or corrupt {suffix} file)")
        if with_normals:
            normals = _usable_normals(np.asarray(cloud.normals, dtype=np.float64), len(points))
    points = as_points(points, str(path), check_units=check_units)
    return (points, normals) if with_normals else points


def _usable_normals(normals: np.ndarray, n: int) -> np.ndarray | None:
    """The file's normals, unit length, if every point has a finite, nonzero one; else None."""
    if normals.shape != (n, 3) or not np.all(np.isfinite(normals)):
        return None
    length = np.linalg.norm(normals, axis=1)
    if n == 0 or float(length.min()) < 1e-6:
        return None
    return normals / length[:, None]


def _as_path(path) -> Path:
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: expected a file name, got {type(path).__name__}")
    return Path(path)


def write_point_cloud(path: str | os.PathLike, points) -> None:
    """Write an ``(N, 3)`` cloud atomically as .pcd (binary), .ply (binary) or .npy."""
    path = _as_path(path)
    suffix = _suffix(path)
    points = as_points(points, "points")
    if suffix == ".npy":
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
