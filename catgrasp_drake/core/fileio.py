"""Atomic, versioned, pickle-free array files (numpy + json only).

A file is a ``.npz`` archive whose arrays are stored under their own names
plus one array ``__header__`` holding a UTF-8 JSON document with at least
``{"format": <kind>, "format_version": <int>, "sha256": <hex>}``. The checksum
covers every array's name, dtype, shape and bytes, so a corrupt or edited file
is detected on load. Writes go to a temporary file in the same directory,
are fsync'ed and then renamed over the target: a reader never sees half a file.
The archive holds no wall-clock time (numpy writes every member with the zip
epoch as its date), so the same arrays and header always give the same bytes.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import tempfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from catgrasp_drake.errors import ModelFileError, one_line

_HEADER_KEY = "__header__"


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temporary file + fsync + rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; a written file gets the usual permissions
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


def _arrays_checksum(arrays: Mapping[str, np.ndarray]) -> str:
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(name.encode())
        h.update(str(a.dtype.str).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def save_arrays(
    path: str | os.PathLike,
    arrays: Mapping[str, np.ndarray],
    *,
    kind: str,
    version: int,
    meta: Mapping[str, Any] | None = None,
) -> None:
    """Save named arrays plus a JSON header atomically to ``path`` (.npz).

    ``meta`` must be JSON-serialisable; object arrays are refused (no pickle).
    """
    arrays = {k: np.asarray(v) for k, v in arrays.items()}
    for name, a in arrays.items():
        if name == _HEADER_KEY:
            raise ValueError(f"array name {_HEADER_KEY!r} is reserved")
        if a.dtype == object:
            raise ValueError(f"array {name!r} has dtype object; only numeric arrays can be saved")
    header = {
        "format": kind,
        "format_version": int(version),
        "sha256": _arrays_checksum(arrays),
        "meta": dict(meta or {}),
    }
    buf = io.BytesIO()
    header_array = np.frombuffer(json.dumps(header, sort_keys=True).encode("utf-8"), dtype=np.uint8)
    np.savez_compressed(buf, **{_HEADER_KEY: header_array}, **arrays)  # object arrays refused above: no pickle
    atomic_write_bytes(path, buf.getvalue())


def load_arrays(
    path: str | os.PathLike, *, kind: str, version: int
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Load a file written by :func:`save_arrays`; return ``(arrays, meta)``.

    Raises :class:`ModelFileError` with a one-line message if the file is
    missing, not an archive, of another kind or version, or fails its checksum.
    """
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise ModelFileError(f"expected a model file name, got {type(path).__name__}")
    path = Path(os.fsdecode(path))
    if not path.is_file():
        raise ModelFileError(f"{path}: file not found")
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except Exception as e:  # zipfile, zlib, numpy header errors: all mean "corrupt"
        raise ModelFileError(f"{path}: not a readable {kind} file ({one_line(e)})") from None
    if _HEADER_KEY not in arrays:
        raise ModelFileError(f"{path}: no header; not a {kind} file")
    try:
        header = json.loads(arrays.pop(_HEADER_KEY).tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise ModelFileError(f"{path}: corrupt header") from None
    if not isinstance(header, dict):
        raise ModelFileError(f"{path}: corrupt header (not a JSON object); not a {kind} file")
    if header.get("format") != kind:
        raise ModelFileError(f"{path}: is a {header.get('format')!r} file, expected {kind!r}")
    if header.get("format_version") != version:
        raise ModelFileError(
            f"{path}: format version {header.get('format_version')} but this catgrasp_drake reads "
            f"version {version}; rebuild the file with this version"
        )
    if header.get("sha256") != _arrays_checksum(arrays):
        raise ModelFileError(f"{path}: checksum mismatch; the file is corrupt or was edited")
    return arrays, header.get("meta", {})


# ----------------------------------------------------------------------------- checksummed JSON lines
def file_sha256(path: str | os.PathLike) -> str:
    """sha256 (hex) of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def text_sha256(text: str) -> str:
    """sha256 (hex) of ``text`` encoded as UTF-8."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def write_json_lines(path: str | os.PathLike, records, fmt: str, version: int) -> None:
    """Write ``records`` (JSON-able dicts) as JSON lines (keys sorted), atomically, after a header line
    ``{"format", "format_version", "records": count, "sha256": of the record lines}``."""
    body = "".join(json.dumps(r, sort_keys=True) + "\n" for r in records)
    header = {"format": fmt, "format_version": version, "records": body.count("\n"), "sha256": text_sha256(body)}
    atomic_write_text(path, json.dumps(header, sort_keys=True) + "\n" + body)


def read_json_lines(path: str | os.PathLike, fmt: str, version: int, *, what: str, rerun: str,
                    headerless_ok: bool = False, check=None) -> list[dict]:
    """Read a :func:`write_json_lines` file back: one dict per record line.

    ModelFileError (one line naming the file) when it is unreadable, has no
    header (unless ``headerless_ok``: a file written before headers existed,
    read without checks), is of another format or version, does not match its
    header's count and checksum, or holds a line that is not a JSON object.
    ``what`` names the content in messages ("evaluation records"), ``rerun``
    says how to make a new file; ``check(record)`` may return a reason to
    reject a line (e.g. missing fields).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, ValueError) as e:
        raise ModelFileError(f"{path}: unreadable {what} ({one_line(e)})") from None
    lines = text.splitlines(keepends=True)
    try:
        header = json.loads(lines[0]) if lines else None
    except ValueError:
        header = None
    if isinstance(header, dict) and "format" in header:
        lines = lines[1:]
        if header.get("format") != fmt:
            raise ModelFileError(f"{path}: is a {header.get('format')!r} file, expected {fmt!r}")
        if header.get("format_version") != version:
            raise ModelFileError(f"{path}: format version {header.get('format_version')} but this catgrasp_drake "
                                 f"reads version {version}; {rerun}")
        count = sum(1 for line in lines if line.strip())
        if header.get("sha256") != text_sha256("".join(lines)) or header.get("records", count) != count:
            raise ModelFileError(f"{path}: checksum mismatch ({count} record lines, header says "
                                 f"{header.get('records')}); the file is corrupt or was edited")
        first = 2
    elif headerless_ok:
        first = 1
    else:
        raise ModelFileError(f"{path}: no header line; not a {fmt!r} file")
    records = []
    for n, line in enumerate(lines, start=first):
        if not line.strip():
            continue
        try:
            r = json.loads(line)
        except ValueError as e:
            raise ModelFileError(f"{path}: line {n} is not JSON ({one_line(e, with_type=False)}); "
                                 "the file is corrupt") from None
        if not isinstance(r, dict):
            raise ModelFileError(f"{path}: line {n} is a JSON {type(r).__name__}, not a trial record")
        why = check(r) if check is not None else None
        if why:
            raise ModelFileError(f"{path}: line {n} {why}")
        records.append(r)
    return records
