"""The dense CPD deformation field, its inverse, and pose warping (paper eqs. 2, 4, 14).

A deformation is given by the canonical points ``C`` (M, 3), the kernel
weights ``W`` (M, 3) and the kernel width ``beta`` (m):

    f(p) = p + v(p),   v(p) = sum_m exp(-|p - c_m|^2 / (2 beta^2)) W_m      (eqs. 2, 4)

It is defined everywhere, so points added after training (grasp control
poses) deform like the canonical points. Its Jacobian is analytic:

    J(p) = I + dv/dp = I - (1 / beta^2) sum_m g_m(p) W_m (p - c_m)^T.

Inverse (eq. 14): the paper's estimate
``p0 = o - sum_i g(o, z_i + v(z_i)) v(z_i) / sum_i g(o, z_i + v(z_i))`` over the
canonical points ``z_i``, evaluated with a max-shift so that a point far from
everything gets the displacement of the nearest deformed point instead of
0/0, is refined by damped Newton steps on ``f(p) = o`` until
``|f(p) - o| <= tol`` (default 1e-9 m). Eq. 14 alone is off by up to a few
millimetres for drill-sized deformations; with the refinement the inverse is
exact to ``tol`` wherever ``f`` is injective. A strongly deformed field can
fold a few millimetres off the surface (``det J`` -> 0; e.g. beta = 0.02 m
with 2 cm displacements, 1 cm off the surface): there the returned point is
*a* preimage (residual still <= tol), not necessarily the original one.

Pose warping: position ``p -> f(p)``; rotation ``R -> orthonormalize(J(p) R)``,
i.e. the rotation basis vectors ``r_i`` deformed as the points ``p + eps r_i``
in the limit ``eps -> 0`` (the analytic Jacobian; ``eps`` may be given to use
finite points instead, e.g. ``eps = 0.01`` m, which must stay well below
``beta`` to be local). The inverse warp uses ``J(p)^-1`` at the canonical
position; since the orthonormalisation is the polar factor,
``inverse_warp(warp(X)) == X`` up to the inverse tolerance.
"""

from __future__ import annotations

import functools

import numpy as np

from catgrasp_drake.core.kernels import gaussian_kernel, kernel_width, sqdist
from catgrasp_drake.core.rotations import orthonormalize
from catgrasp_drake.core.validation import MAX_COORDINATE_M, as_points, count, non_negative, real_array
from catgrasp_drake.errors import InputError

_CHUNK = 1024


def _check_field(canonical, W, beta):
    C = as_points(canonical, "canonical", min_points=1)
    W = real_array(W, "W", "(M, 3) array")
    if W.shape != C.shape:
        raise InputError(f"W: expected shape {C.shape} (one 3-vector per canonical point), got {W.shape}")
    if not np.all(np.isfinite(W)):
        raise InputError("W: contains NaN or inf")
    if float(np.abs(W).max()) > MAX_COORDINATE_M:
        raise InputError(f"W: kernel weights reach {float(np.abs(W).max()):.3g} m; "
                         f"expected metres (<= {MAX_COORDINATE_M:g})")
    return C, W, kernel_width(beta)


def displacement(canonical, W, beta, points) -> np.ndarray:
    """``v(points) = G(points, canonical) W`` (K, 3)."""
    C, W, beta = _check_field(canonical, W, beta)
    P = as_points(points, "points", min_points=0)
    out = np.empty_like(P)
    for lo in range(0, len(P), _CHUNK):
        out[lo:lo + _CHUNK] = gaussian_kernel(P[lo:lo + _CHUNK], C, beta) @ W
    return out


def deform_points(canonical, W, beta, points) -> np.ndarray:
    """``points + G(points, canonical) W``: the dense deformation field applied to any (K, 3) points."""
    P = as_points(points, "points", min_points=0)
    return P + displacement(canonical, W, beta, P)


def _deform_canonical(C: np.ndarray, W: np.ndarray, beta: float) -> np.ndarray:
    """``deform_points(C, W, beta, C)`` (checked inputs), bit for bit, with the (M, M) kernel of ``C`` computed once
    per canonical shape and width (:func:`_self_kernel_chunks`): every warp of a model's poses needs it."""
    out = np.empty_like(C)
    for k, G in enumerate(_self_kernel_chunks(C.tobytes(), C.shape, beta)):
        out[k * _CHUNK:(k + 1) * _CHUNK] = G @ W
    return C + out


@functools.lru_cache(maxsize=4)
def _self_kernel_chunks(data: bytes, shape: tuple, beta: float) -> tuple:
    """The row chunks of ``G(C, C)`` exactly as :func:`displacement` computes them for ``points = C`` (C given by
    its float64 bytes and shape: the cache compares them exactly; at most 4 shapes kept)."""
    C = np.frombuffer(data, dtype=np.float64).reshape(shape)
    return tuple(gaussian_kernel(C[lo:lo + _CHUNK], C, beta) for lo in range(0, shape[0], _CHUNK))


def jacobian(canonical, W, beta, points) -> np.ndarray:
    """Jacobians ``J(p) = I + dv/dp`` (K, 3, 3) of the deformation at (K, 3) points."""
    C, W, beta = _check_field(canonical, W, beta)
    P = as_points(points, "points", min_points=0)
    WC = (W[:, :, None] * C[:, None, :]).reshape(len(C), 9)
    out = np.empty((len(P), 3, 3))
    for lo in range(0, len(P), _CHUNK):
        p = P[lo:lo + _CHUNK]
        g = gaussian_kernel(p, C, beta)
        v = g @ W
        gWC = (g @ WC).reshape(-1, 3, 3)
        out[lo:lo + _CHUNK] = np.eye(3) - (v[:, :, None] * p[:, None, :] - gWC) / beta**2
    return out


def inverse_deform_points(
    canonical,
    W,
    beta,
    points,
    *,
    refine: bool = True,
    tol: float = 1e-9,
    max_iter: int = 50,
    return_residual: bool = False,
):
    """Map observed-space points back to the canonical space (eq. 14 + Newton refinement).

    Returns (K, 3) canonical points, and with ``return_residual`` also the
    residual norms ``|f(p) - o|`` (K,) in metres. ``refine=False`` gives the
    paper's eq. 14 alone.
    """
    C, W, beta = _check_field(canonical, W, beta)
    O = as_points(points, "points", min_points=0)
    tol = non_negative(tol, "tol")
    max_iter = count(max_iter, "max_iter", 0)
    if not isinstance(refine, (bool, np.bool_)):
        raise InputError(f"refine: expected True or False, got {refine!r}")
    if len(O) == 0:
        return (O.copy(), np.zeros(0)) if return_residual else O.copy()
    V = gaussian_kernel(C, C, beta) @ W  # v(z_i) at the canonical points
    D = C + V
    p = np.empty_like(O)
    for lo in range(0, len(O), _CHUNK):
        o = O[lo:lo + _CHUNK]
        d2 = sqdist(o, D) / (2.0 * beta**2)
        a = np.exp(-(d2 - d2.min(axis=1, keepdims=True)))
        p[lo:lo + _CHUNK] = o - (a @ V) / a.sum(axis=1, keepdims=True)
    res = deform_points(C, W, beta, p) - O
    rn = np.linalg.norm(res, axis=1)
    if refine:
        for _ in range(max_iter):
            todo = rn > tol
            if not np.any(todo):
                break
            J = jacobian(C, W, beta, p[todo])
            try:
                step = np.linalg.solve(J, res[todo][:, :, None])[:, :, 0]
            except np.linalg.LinAlgError:
                step = res[todo]
            # damped Newton: halve the step until the residual decreases
            idx = np.flatnonzero(todo)
            alpha = np.ones(len(idx))
            for _ in range(20):
                cand = p[idx] - alpha[:, None] * step
                r_c = deform_points(C, W, beta, cand) - O[idx]
                n_c = np.linalg.norm(r_c, axis=1)
                ok = n_c < rn[idx]
                if np.all(ok | (alpha < 1e-6)):
                    break
                alpha = np.where(ok, alpha, 0.5 * alpha)
            better = n_c < rn[idx]
            sel = idx[better]
            p[sel] = cand[better]
            res[sel] = r_c[better]
            rn[sel] = n_c[better]
            if not np.any(better):
                break
    return (p, rn) if return_residual else p


def _check_poses(X) -> tuple[np.ndarray, bool]:
    X = real_array(X, "poses", "(4, 4) or (K, 4, 4) array")
    single = X.ndim == 2
    if single:
        X = X[None]
    if X.ndim != 3 or X.shape[1:] != (4, 4):
        raise InputError(f"poses: expected (4, 4) or (K, 4, 4) homogeneous matrices, got {X.shape}")
    if not np.all(np.isfinite(X)):
        raise InputError("poses: contain NaN or inf")
    if X.size and float(np.abs(X[:, :3, 3]).max()) > MAX_COORDINATE_M:
        raise InputError(f"poses: translations reach {float(np.abs(X[:, :3, 3]).max()):.3g}; expected metres "
                         f"within {MAX_COORDINATE_M:g} m of the origin")
    return X, single


def _check_anchor(anchor) -> np.ndarray:
    if anchor is None:
        return np.zeros(3)
    a = real_array(anchor, "anchor", "3-vector").reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or float(np.abs(a).max()) > MAX_COORDINATE_M:
        raise InputError(f"anchor: expected a finite 3-vector (m, in the pose's own frame), got {np.shape(anchor)}")
    return a


def local_rotations(canonical, W, beta, points, radius: float) -> np.ndarray:
    """Rotations (K, 3, 3) best aligning the canonical points near each of ``points`` with their deformed selves.

    Weighted Procrustes (no scale) with weights ``exp(-|c - p|^2 / (2 radius^2))``
    over the canonical points c -> f(c): the deformation's rotation averaged
    over a neighbourhood of ``radius`` (m), robust where the field's
    Jacobian turns sharply at a thin feature (a trigger, a handle).
    """
    C, W, beta = _check_field(canonical, W, beta)
    P = as_points(points, "points", min_points=0)
    radius = kernel_width(radius, "rotation_radius")
    D = _deform_canonical(C, W, beta)
    out = np.empty((len(P), 3, 3))
    for k, p in enumerate(P):
        w = np.exp(-((C - p) ** 2).sum(axis=1) / (2 * radius**2))
        if w.sum() < 1e-12:
            out[k] = np.eye(3)
            continue
        w = w / w.sum()
        mc, md = w @ C, w @ D
        H = ((C - mc) * w[:, None]).T @ (D - md)
        U, _, Vt = np.linalg.svd(H)
        S = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
        out[k] = Vt.T @ S @ U.T
    return out


def warp_poses(canonical, W, beta, X, *, eps: float | None = None, anchor=None,
               rotation_radius: float | None = None) -> np.ndarray:
    """Warp canonical-frame poses (K, 4, 4) (or one (4, 4)) through the deformation.

    The point warped is the pose's ``anchor`` (3,) -- a point fixed in the
    posed body (e.g. the grasp centre of a hand whose frame origin is at the
    wrist), default its origin: ``a = X anchor`` goes to ``f(a)``, the
    rotation becomes ``orthonormalize(J(a) R)`` (``eps=None``) or, with
    ``eps`` > 0, the basis deformed as the points ``a + eps r_i``, and the
    body stays rigid: the new origin is ``f(a) - R' anchor``. The deformation
    is a local field (Gaussian kernel of width beta); anchoring at the grasp
    centre moves the hand with the surface it grasps rather than with the
    field ~10 cm away at its wrist. With ``rotation_radius`` (m) the
    rotation is instead ``local_rotations(...) R``: the field's rotation
    averaged over that neighbourhood of the anchor (a hand spans several
    centimetres; the Jacobian at one point of a thin feature can turn it by
    30 degrees). Rotations are proper (det +1).
    """
    Xa, single = _check_poses(X)
    C, W, beta = _check_field(canonical, W, beta)
    anc = _check_anchor(anchor)
    R = Xa[:, :3, :3]
    p = Xa[:, :3, 3] + R @ anc
    fp = deform_points(C, W, beta, p)
    if rotation_radius is not None:
        A = local_rotations(C, W, beta, p, rotation_radius) @ R
    elif eps is None:
        A = jacobian(C, W, beta, p) @ R
    else:
        eps = kernel_width(eps, "eps")
        ends = (p[:, None, :] + eps * np.swapaxes(R, 1, 2)).reshape(-1, 3)  # p + eps * column i
        fe = deform_points(C, W, beta, ends).reshape(-1, 3, 3)
        A = np.swapaxes((fe - fp[:, None, :]) / eps, 1, 2)
    out = np.tile(np.eye(4), (len(Xa), 1, 1))
    out[:, :3, :3] = orthonormalize(A)
    out[:, :3, 3] = fp - out[:, :3, :3] @ anc
    return out[0] if single else out


def inverse_warp_poses(canonical, W, beta, X, *, tol: float = 1e-9, anchor=None,
                       rotation_radius: float | None = None) -> np.ndarray:
    """Map observed-space poses back to the canonical frame (inverse of :func:`warp_poses`, same options)."""
    Xa, single = _check_poses(X)
    C, W, beta = _check_field(canonical, W, beta)
    anc = _check_anchor(anchor)
    a = Xa[:, :3, 3] + Xa[:, :3, :3] @ anc
    p = inverse_deform_points(C, W, beta, a, tol=tol)
    out = np.tile(np.eye(4), (len(Xa), 1, 1))
    if rotation_radius is not None:
        out[:, :3, :3] = np.swapaxes(local_rotations(C, W, beta, p, rotation_radius), 1, 2) @ Xa[:, :3, :3]
    else:
        out[:, :3, :3] = orthonormalize(np.linalg.solve(jacobian(C, W, beta, p), Xa[:, :3, :3]))
    out[:, :3, 3] = p - out[:, :3, :3] @ anc
    return out[0] if single else out
