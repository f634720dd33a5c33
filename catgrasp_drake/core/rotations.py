"""Rotations: orthonormalisation, quaternions, uniform and bounded random sampling (numpy only).

Quaternions are scalar-first ``(w, x, y, z)`` (Drake's convention), unit norm,
and returned with ``w >= 0``. Every function accepts one item or a batch
(leading dimensions) unless stated.
"""

from __future__ import annotations

import numpy as np

from catgrasp_drake.core.validation import count, real_array, real_number
from catgrasp_drake.errors import InputError

#: Most rotations/quaternions drawn in one call (7 * 10^7 floats, ~0.5 GB).
MAX_SAMPLES = 10_000_000


def _as_generator(rng) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        if rng < 0:
            raise InputError(f"rng: an int seed must be >= 0, got {rng}")
        return np.random.default_rng(int(rng))
    raise InputError(f"rng: expected a numpy.random.Generator or an int seed, got {type(rng).__name__}")


def orthonormalize(R) -> np.ndarray:
    """Nearest proper rotation (Frobenius norm) to each 3x3 matrix: ``U diag(1, 1, det(U V^T)) V^T``.

    ``R`` is (3, 3) or (..., 3, 3). This is the orthogonal factor of the polar
    decomposition, with the sign of the last singular direction flipped if
    needed so that ``det = +1``.
    """
    A = real_array(R, "orthonormalize", "(..., 3, 3) array")
    if A.shape[-2:] != (3, 3):
        raise InputError(f"orthonormalize: expected (..., 3, 3) matrices, got {A.shape}")
    if not np.all(np.isfinite(A)):
        raise InputError("orthonormalize: matrices contain NaN or inf")
    if A.size:  # the polar factor is scale-invariant: keep SVD away from overflow and underflow
        big = np.abs(A).max(axis=(-2, -1), keepdims=True)
        odd = (big > 1e100) | ((big < 1e-100) & (big > 0))
        if np.any(odd):
            A = np.where(odd, A / np.where(odd, big, 1.0), A)
    U, _, Vt = np.linalg.svd(A)
    d = np.sign(np.linalg.det(U @ Vt))
    d = np.where(d == 0, 1.0, d)
    U = U.copy()
    U[..., :, 2] *= d[..., None]
    return U @ Vt


def shoemake_quaternions(rng, n: int) -> np.ndarray:
    """``n`` uniformly distributed unit quaternions (Shoemake 1992, "Uniform random rotations").

    From three uniform numbers u1, u2, u3:
    ``(sqrt(1-u1) sin 2pi u2, sqrt(1-u1) cos 2pi u2, sqrt(u1) sin 2pi u3, sqrt(u1) cos 2pi u3)``,
    returned scalar-first with ``w >= 0``. Shape (n, 4).
    """
    rng = _as_generator(rng)
    n = count(n, "n", 0, MAX_SAMPLES)
    u1, u2, u3 = rng.random((3, n))
    a, b = np.sqrt(1.0 - u1), np.sqrt(u1)
    q = np.stack([b * np.cos(2 * np.pi * u3), a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2),
                  b * np.sin(2 * np.pi * u3)], axis=1)
    return _canonical_sign(q)


def _canonical_sign(q: np.ndarray) -> np.ndarray:
    return np.where(q[..., :1] < 0, -q, q)


def quaternion_angle(q) -> np.ndarray:
    """Rotation angle (rad, in [0, pi]) of unit quaternions (..., 4)."""
    q = np.asarray(q, dtype=np.float64)
    return 2.0 * np.arccos(np.clip(np.abs(q[..., 0]) / np.linalg.norm(q, axis=-1), 0.0, 1.0))


def sample_rotations_within(rng, n: int, max_angle: float) -> np.ndarray:
    """``n`` rotations uniform (Haar) among those within ``max_angle`` rad of the identity.

    The paper's sampling: Shoemake uniform quaternions, kept when their angle
    is <= ``max_angle`` (rejection sampling, in vectorised batches). When the
    acceptance rate ``(a - sin a) / pi`` is below 1e-5 (``a`` < ~0.07 rad)
    rejection would need > 1e5 draws per sample, so the same distribution is
    drawn directly: angle by inverse CDF of ``(t - sin t) / (a - sin a)``,
    axis uniform on the sphere. Returns (n, 3, 3).
    """
    rng = _as_generator(rng)
    n = count(n, "n", 0, MAX_SAMPLES)
    a = real_number(max_angle, "max_angle")
    if not a >= 0.0:
        raise InputError(f"max_angle: must be a finite angle >= 0 rad, got {max_angle!r}")
    a = min(a, np.pi)
    if n == 0:
        return np.zeros((0, 3, 3))
    if a == 0.0:
        return np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    accept = (a - np.sin(a)) / np.pi
    if accept >= 1e-5:
        out = []
        have = 0
        while have < n:
            batch = int(min(5_000_000, max(1024, 1.3 * (n - have) / accept)))
            q = shoemake_quaternions(rng, batch)
            q = q[quaternion_angle(q) <= a]
            out.append(q)
            have += len(q)
        q = np.concatenate(out)[:n]
        return quat_to_matrix(q)
    # direct sampling of the same distribution
    u = rng.random(n) * (a - np.sin(a))
    t = np.cbrt(6.0 * u)  # t - sin t ~ t^3/6 for small t; refine by Newton
    for _ in range(30):
        t = t - (t - np.sin(t) - u) / np.maximum(1.0 - np.cos(t), 1e-300)
        t = np.clip(t, 0.0, a)
    axis = rng.standard_normal((n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    q = np.concatenate([np.cos(t / 2)[:, None], np.sin(t / 2)[:, None] * axis], axis=1)
    return quat_to_matrix(q)


def quat_to_matrix(q) -> np.ndarray:
    """Rotation matrices (..., 3, 3) from quaternions (..., 4) ``(w, x, y, z)`` (normalised first)."""
    q = real_array(q, "quat_to_matrix", "(..., 4) array")
    if q.shape[-1:] != (4,):
        raise InputError(f"quat_to_matrix: expected (..., 4) quaternions, got {q.shape}")
    if not np.all(np.isfinite(q)):
        raise InputError("quat_to_matrix: quaternions must be finite and non-zero")
    big = np.abs(q).max(axis=-1, keepdims=True) if q.size else np.ones(q.shape[:-1] + (1,))
    if np.any(big == 0):
        raise InputError("quat_to_matrix: quaternions must be finite and non-zero")
    odd = (big > 1e100) | (big < 1e-100)  # rescale only there: ordinary inputs keep their exact rounding
    if np.any(odd):
        q = np.where(odd, q / big, q)  # scale-free: no overflow or underflow in the norm
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q / norm, -1, 0)
    R = np.stack([
        1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
        2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
        2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
    ], axis=-1)
    return R.reshape(q.shape[:-1] + (3, 3))


def matrix_to_quat(R) -> np.ndarray:
    """Quaternions (..., 4) ``(w, x, y, z)``, ``w >= 0``, from rotation matrices (..., 3, 3).

    Numerically robust (Shepperd's method: picks the largest of w, x, y, z
    to divide by).
    """
    R = real_array(R, "matrix_to_quat", "(..., 3, 3) array")
    if R.shape[-2:] != (3, 3):
        raise InputError(f"matrix_to_quat: expected (..., 3, 3) matrices, got {R.shape}")
    if not np.all(np.isfinite(R)):
        raise InputError("matrix_to_quat: matrices contain NaN or inf")
    if R.size and float(np.abs(R).max()) > 1.0 + 1e-6:
        raise InputError("matrix_to_quat: not rotation matrices (entries beyond 1); orthonormalize them first")
    shape = R.shape[:-2]
    R = R.reshape(-1, 3, 3)
    tr = np.trace(R, axis1=1, axis2=2)
    cand = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    k = np.argmax(cand, axis=1)
    q = np.empty((len(R), 4))
    for i in range(4):
        m = k == i
        if not np.any(m):
            continue
        r = R[m]
        if i == 0:
            s = 2.0 * np.sqrt(1.0 + tr[m])
            q[m] = np.stack([0.25 * s, (r[:, 2, 1] - r[:, 1, 2]) / s, (r[:, 0, 2] - r[:, 2, 0]) / s,
                             (r[:, 1, 0] - r[:, 0, 1]) / s], 1)
        elif i == 1:
            s = 2.0 * np.sqrt(np.maximum(1.0 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2], 0.0))
            q[m] = np.stack([(r[:, 2, 1] - r[:, 1, 2]) / s, 0.25 * s, (r[:, 0, 1] + r[:, 1, 0]) / s,
                             (r[:, 0, 2] + r[:, 2, 0]) / s], 1)
        elif i == 2:
            s = 2.0 * np.sqrt(np.maximum(1.0 + r[:, 1, 1] - r[:, 0, 0] - r[:, 2, 2], 0.0))
            q[m] = np.stack([(r[:, 0, 2] - r[:, 2, 0]) / s, (r[:, 0, 1] + r[:, 1, 0]) / s, 0.25 * s,
                             (r[:, 1, 2] + r[:, 2, 1]) / s], 1)
        else:
            s = 2.0 * np.sqrt(np.maximum(1.0 + r[:, 2, 2] - r[:, 0, 0] - r[:, 1, 1], 0.0))
            q[m] = np.stack([(r[:, 1, 0] - r[:, 0, 1]) / s, (r[:, 0, 2] + r[:, 2, 0]) / s,
                             (r[:, 1, 2] + r[:, 2, 1]) / s, 0.25 * s], 1)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return _canonical_sign(q).reshape(shape + (4,))


def rotz(yaw) -> np.ndarray:
    """Rotation(s) about +z by ``yaw`` rad: (3, 3) for a scalar, (n, 3, 3) for an array."""
    y = np.asarray(yaw, dtype=np.float64)
    c, s = np.cos(y), np.sin(y)
    z, o = np.zeros_like(y), np.ones_like(y)
    return np.stack([c, -s, z, s, c, z, z, z, o], axis=-1).reshape(y.shape + (3, 3))


def rotation_angle(R) -> np.ndarray:
    """Angle (rad) of rotation matrices (..., 3, 3)."""
    R = np.asarray(R, dtype=np.float64)
    return np.arccos(np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0))
