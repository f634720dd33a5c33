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
    try:
        a = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a numeric (N, {dim}) array, got {type(points).__name__}") from None
    if a.ndim != 2 or a.shape[1] != dim:
        raise InputError(f"{name}: expected shape (N, {dim}), got {a.shape}")
    if a.shape[0] < min_points:
        if a.shape[0] == 0:
            raise InputError(f"{name}: the point cloud is empty")
        raise InputError(f"{name}: needs at least {min_points} points, got {a.shape[0]}")
    if not np.all(np.isfinite(a)):
        bad = int(np.count_nonzero(~np.all(np.isfinite(a), axis=1)))
        raise InputError(f"{name}: {bad} of {a.shape[0]} points contain NaN or inf; remove them first")
    if check_units:
        extent = float(np.linalg.norm(a.max(axis=0) - a.min(axis=0)))
        if extent > MAX_OBJECT_EXTENT_M:
            raise InputError(
                f"{name}: the cloud spans {extent:.3g} units; expected metres (< {MAX_OBJECT_EXTENT_M} m). "
                "Is it in millimetres? Divide by 1000."
            )
    return np.ascontiguousarray(a)


def positive(value, name: str) -> float:
    """Return ``value`` as a finite float > 0 or raise InputError."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a positive number, got {value!r}") from None
    if not np.isfinite(v) or v <= 0.0:
        raise InputError(f"{name}: must be a finite number > 0, got {value!r}")
    return v


def outlier_weight(w) -> float:
    """The uniform-outlier weight of a CPD-style mixture, checked to lie in [0, 1)."""
    try:
        w = float(w)
    except (TypeError, ValueError):
        raise InputError(f"w: expected a number in [0, 1), got {w!r}") from None
    if not (0.0 <= w < 1.0):
        raise InputError(f"w: the outlier weight must be in [0, 1), got {w}")
    return w
