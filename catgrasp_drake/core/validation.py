"""Input checks shared by the whole package (numpy only).

Each check raises :class:`catgrasp_drake.errors.InputError` with a one-line
message naming the argument and the problem.
"""

from __future__ import annotations

import numpy as np

from catgrasp_drake.errors import InputError

#: A cloud whose bounding box diagonal exceeds this (metres) is taken to be in
#: millimetres (objects handled here are hand-sized, < 1 m).
MAX_OBJECT_EXTENT_M = 3.0
#: No coordinate of a point set may exceed this (metres): nothing handled here is 1000 km away,
#: and far larger values overflow squared distances (|x| > 1e154) -- a unit or parsing error.
MAX_COORDINATE_M = 1e6


def as_points(
    points,
    name: str = "points",
    *,
    min_points: int = 1,
    dim: int = 3,
    check_units: bool = False,
) -> np.ndarray:
    """Return ``points`` as a C-contiguous float64 ``(N, dim)`` array or raise InputError.

    Rejects non-numeric input, wrong shapes, fewer than ``min_points`` rows and
    NaN/inf. With ``check_units`` a cloud larger than :data:`MAX_OBJECT_EXTENT_M`
    is rejected as probably being in millimetres.
    """
    if isinstance(points, (str, bytes, dict)) or points is None:
        raise InputError(f"{name}: expected a numeric (N, {dim}) array, got {type(points).__name__}")
    try:
        raw = np.asarray(points)
        if raw.dtype.kind not in "iufO":  # complex, bool, strings, dates, structured: not coordinates
            raise TypeError
        a = raw.astype(np.float64, copy=False)
    except (TypeError, ValueError, OverflowError):
        kind = getattr(getattr(points, "dtype", None), "name", type(points).__name__)
        raise InputError(f"{name}: expected a numeric (N, {dim}) array of real numbers, got {kind}") from None
    if a.ndim != 2 or a.shape[1] != dim:
        raise InputError(f"{name}: expected shape (N, {dim}), got {a.shape}")
    if a.shape[0] < min_points:
        if a.shape[0] == 0:
            raise InputError(f"{name}: the point cloud is empty")
        raise InputError(f"{name}: needs at least {min_points} points, got {a.shape[0]}")
    if not np.all(np.isfinite(a)):
        bad = int(np.count_nonzero(~np.all(np.isfinite(a), axis=1)))
        raise InputError(f"{name}: {bad} of {a.shape[0]} points contain NaN or inf; remove them first")
    big = float(np.abs(a).max()) if a.size else 0.0
    if big > MAX_COORDINATE_M:
        raise InputError(f"{name}: coordinates reach {big:.3g}; expected metres within {MAX_COORDINATE_M:g} m of "
                         "the origin (wrong units?)")
    if check_units:
        extent = float(np.linalg.norm(a.max(axis=0) - a.min(axis=0)))
        if extent > MAX_OBJECT_EXTENT_M:
            raise InputError(
                f"{name}: the cloud spans {extent:.3g} units; expected metres (< {MAX_OBJECT_EXTENT_M} m). "
                "Is it in millimetres? Divide by 1000."
            )
    return np.ascontiguousarray(a)


def real_array(value, name: str, what: str = "array") -> np.ndarray:
    """``value`` as a float64 array of real numbers (any shape) or InputError naming ``what`` was expected.

    Strings, None, complex, bool and ragged input are refused; the caller checks shape and finiteness.
    """
    if isinstance(value, (str, bytes, dict)) or value is None:
        raise InputError(f"{name}: expected a numeric {what}, got {type(value).__name__}")
    try:
        raw = np.asarray(value)
        if raw.dtype.kind not in "iufO":
            raise TypeError
        return raw.astype(np.float64, copy=False)
    except (TypeError, ValueError, OverflowError):
        kind = getattr(getattr(value, "dtype", None), "name", type(value).__name__)
        raise InputError(f"{name}: expected a numeric {what} of real numbers, got {kind}") from None


def vector3(value, name: str) -> np.ndarray:
    """A finite 3-vector (metres) within :data:`MAX_COORDINATE_M` of the origin, or InputError."""
    a = real_array(value, name, "3-vector").reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputError(f"{name}: expected a finite 3-vector (m), got shape {np.shape(value)}")
    if float(np.abs(a).max()) > MAX_COORDINATE_M:
        raise InputError(f"{name}: coordinates reach {float(np.abs(a).max()):.3g}; expected metres within "
                         f"{MAX_COORDINATE_M:g} m of the origin")
    return a


def _short(value) -> str:
    r = repr(value).replace("\n", " ")
    return r if len(r) <= 60 else r[:57] + "..."


def real_number(value, name: str) -> float:
    """Return ``value`` (a real number, not a bool or a string) as a finite float or raise InputError."""
    if isinstance(value, (bool, np.bool_, str, bytes)) or value is None:
        raise InputError(f"{name}: expected a number, got {_short(value)}")
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: expected a number, got {_short(value)}") from None
    if not np.isfinite(v):
        raise InputError(f"{name}: must be a finite number, got {_short(value)}")
    return v


def positive(value, name: str) -> float:
    """Return ``value`` as a finite float > 0 or raise InputError."""
    v = real_number(value, name)
    if v <= 0.0:
        raise InputError(f"{name}: must be a finite number > 0, got {_short(value)}")
    return v


def non_negative(value, name: str) -> float:
    """Return ``value`` as a finite float >= 0 or raise InputError."""
    v = real_number(value, name)
    if v < 0.0:
        raise InputError(f"{name}: must be >= 0, got {_short(value)}")
    return v


def count(value, name: str, minimum: int = 1, maximum: int | None = None) -> int:
    """Return ``value`` (an integer, or a float with an integer value) as an int in
    ``[minimum, maximum]`` or raise InputError."""
    if isinstance(value, (bool, np.bool_, str, bytes)) or value is None:
        raise InputError(f"{name}: expected an integer, got {_short(value)}")
    if isinstance(value, (int, np.integer)):
        n = int(value)
    else:
        try:
            f = float(value)
            n = int(f)
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"{name}: expected an integer, got {_short(value)}") from None
        if f != n:
            raise InputError(f"{name}: expected an integer, got {_short(value)}")
    if n < minimum or (maximum is not None and n > maximum):
        rng = f">= {minimum}" if maximum is None else f"in [{minimum}, {maximum}]"
        raise InputError(f"{name}: must be an integer {rng}, got {n}")
    return n


def outlier_weight(w) -> float:
    """The uniform-outlier weight of a CPD-style mixture, checked to lie in [0, 1)."""
    v = real_number(w, "w")
    if not (0.0 <= v < 1.0):
        raise InputError(f"w: the outlier weight must be in [0, 1), got {v}")
    return v
