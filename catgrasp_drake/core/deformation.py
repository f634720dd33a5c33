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

import numpy as np

from catgrasp_drake.core.cpd import _sqdist, gaussian_kernel
from catgrasp_drake.core.rotations import orthonormalize
from catgrasp_drake.core.validation import as_points, positive
from catgrasp_drake.errors import InputError

_CHUNK = 1024


def _check_field(canonical, W, beta):
    C = as_points(canonical, "canonical", min_points=1)
    W = np.asarray(W, dtype=np.float64)
    if W.shape != C.shape:
        raise InputError(f"W: expected shape {C.shape} (one 3-vector per canonical point), got {W.shape}")
    if not np.all(np.isfinite(W)):
        raise InputError("W: contains NaN or inf")
    return C, W, positive(beta, "beta")


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
    if len(O) == 0:
        return (O.copy(), np.zeros(0)) if return_residual else O.copy()
    V = gaussian_kernel(C, C, beta) @ W  # v(z_i) at the canonical points
    D = C + V
    p = np.empty_like(O)
    for lo in range(0, len(O), _CHUNK):
        o = O[lo:lo + _CHUNK]
        d2 = _sqdist(o, D) / (2.0 * beta**2)
        a = np.exp(-(d2 - d2.min(axis=1, keepdims=True)))
        p[lo:lo + _CHUNK] = o - (a @ V) / a.sum(axis=1, keepdims=True)
    res = deform_points(C, W, beta, p) - O
    rn = np.linalg.norm(res, axis=1)
    if refine:
        for _ in range(int(max_iter)):
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
    X = np.asarray(X, dtype=np.float64)
    single = X.ndim == 2
    if single:
        X = X[None]
    if X.ndim != 3 or X.shape[1:] != (4, 4):
        raise InputError(f"poses: expected (4, 4) or (K, 4, 4) homogeneous matrices, got {X.shape}")
    if not np.all(np.isfinite(X)):
        raise InputError("poses: contain NaN or inf")
    return X, single


def warp_poses(canonical, W, beta, X, *, eps: float | None = None) -> np.ndarray:
    """Warp canonical-frame poses (K, 4, 4) (or one (4, 4)) through the deformation.

    Position ``f(p)``; rotation ``orthonormalize(J(p) R)`` (``eps=None``) or, with
    ``eps`` > 0, the basis deformed as the points ``p + eps r_i``. The result
    has proper rotations (det +1).
    """
    Xa, single = _check_poses(X)
    C, W, beta = _check_field(canonical, W, beta)
    p = Xa[:, :3, 3]
    R = Xa[:, :3, :3]
    fp = deform_points(C, W, beta, p)
    if eps is None:
        A = jacobian(C, W, beta, p) @ R
    else:
        eps = positive(eps, "eps")
        ends = (p[:, None, :] + eps * np.swapaxes(R, 1, 2)).reshape(-1, 3)  # p + eps * column i
        fe = deform_points(C, W, beta, ends).reshape(-1, 3, 3)
        A = np.swapaxes((fe - fp[:, None, :]) / eps, 1, 2)
    out = np.tile(np.eye(4), (len(Xa), 1, 1))
    out[:, :3, :3] = orthonormalize(A)
    out[:, :3, 3] = fp
    return out[0] if single else out


def inverse_warp_poses(canonical, W, beta, X, *, tol: float = 1e-9) -> np.ndarray:
    """Map observed-space poses back to the canonical frame (inverse of :func:`warp_poses`)."""
    Xa, single = _check_poses(X)
    C, W, beta = _check_field(canonical, W, beta)
    p = inverse_deform_points(C, W, beta, Xa[:, :3, 3], tol=tol)
    J = jacobian(C, W, beta, p)
    out = np.tile(np.eye(4), (len(Xa), 1, 1))
    out[:, :3, :3] = orthonormalize(np.linalg.solve(J, Xa[:, :3, :3]))
    out[:, :3, 3] = p
    return out[0] if single else out
