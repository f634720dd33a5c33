"""Gaussian kernels of CPD and the deformation field: exact, and a low-rank approximation.

``gaussian_kernel(A, B, beta)`` is ``G[i, j] = exp(-|a_i - b_j|^2 / (2 beta^2))``
(metres in, dimensionless out); ``low_rank_kernel`` gives the top eigenpairs of
``G(Y, Y)`` by seeded randomised subspace iteration, for sources too large for
an exact M x M kernel. numpy + scipy only.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from catgrasp_drake.core.validation import as_points, positive
from catgrasp_drake.errors import InputError

#: ``low_rank_kernel(..., "auto")`` keeps the smallest rank whose eigenvalues hold this share of trace(G).
AUTO_RANK_TRACE = 1.0 - 1e-4
#: Block size (elements) of the kernel products built without storing G.
KERNEL_BLOCK_ELEMENTS = 1 << 19
#: ``low_rank_kernel`` keeps the row blocks of ``G(Y, Y)`` between its products up to this many elements
#: (64 MiB; M <= 2896), and recomputes them block by block above (memory O(M x block)).
KERNEL_STORE_ELEMENTS = 1 << 23


def gaussian_kernel(A, B, beta) -> np.ndarray:
    """``G[i, j] = exp(-|a_i - b_j|^2 / (2 beta^2))`` for (K, D) ``A`` and (L, D) ``B``."""
    A = _kernel_points(A, "A")
    B = _kernel_points(B, "B")
    if A.shape[1] != B.shape[1]:
        raise InputError(f"gaussian_kernel: expected (K, D) and (L, D) arrays, got {A.shape} and {B.shape}")
    beta = kernel_width(beta)
    d2 = sqdist(A, B)
    d2 *= -0.5 / (beta * beta)
    np.maximum(d2, -700.0, out=d2)
    np.exp(d2, out=d2)
    d2[d2 < 1e-150] = 0.0  # no subnormals downstream (they slow BLAS/LAPACK ~10x)
    return d2


def kernel_width(beta, name: str = "beta") -> float:
    """``beta`` checked to be a positive width whose square neither underflows nor overflows."""
    beta = positive(beta, name)
    if not (1e-150 < beta < 1e150):
        raise InputError(f"{name}: kernel width {beta:g} is out of the usable range (1e-150, 1e150)")
    return beta


def _kernel_points(A, name: str) -> np.ndarray:
    try:
        A = np.asarray(A)
        if A.dtype.kind not in "iufO":
            raise TypeError
        A = A.astype(np.float64, copy=False)
    except (TypeError, ValueError):
        raise InputError(f"gaussian_kernel: {name} must be a numeric (K, D) array of real numbers") from None
    if A.ndim != 2:
        raise InputError(f"gaussian_kernel: {name} must be a (K, D) array, got shape {A.shape}")
    if not np.all(np.isfinite(A)) or (A.size and float(np.abs(A).max()) > 1e100):
        raise InputError(f"gaussian_kernel: {name} contains NaN, inf or coordinates beyond 1e100")
    return A


def sqdist(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Squared distances (K, L), exact to rounding (centred, clipped at 0)."""
    c = 0.5 * (A.mean(axis=0) + B.mean(axis=0)) if len(A) and len(B) else 0.0
    A = A - c
    B = B - c
    d2 = (A * A).sum(1)[:, None] + (B * B).sum(1)[None, :]
    d2 -= 2.0 * (A @ B.T)
    np.maximum(d2, 0.0, out=d2)
    return d2


class _KernelProduct:
    """``B -> G(Y, Y) @ B`` in fixed row blocks, optionally stored and computed in a thread pool.

    Each row block is ``gaussian_kernel(Y[lo:hi], Y, beta) @ B[...]``, whatever the storage and the
    threads, so the result is the same bit for bit (blocks are independent; the layout depends on M only).
    """

    def __init__(self, Y: np.ndarray, beta: float, *, pool=None, store: bool | None = None):
        M = Y.shape[0]
        nb = max(16, KERNEL_BLOCK_ELEMENTS // max(M, 1))
        self.Y, self.beta, self.pool = Y, beta, pool
        self.bounds = [(lo, min(M, lo + nb)) for lo in range(0, M, nb)]
        self.store = (M * M <= KERNEL_STORE_ELEMENTS) if store is None else bool(store)
        self.blocks = None

    def _map(self, fn):
        if self.pool is not None and len(self.bounds) > 1:
            return list(self.pool.map(fn, range(len(self.bounds))))
        return [fn(k) for k in range(len(self.bounds))]

    def _block(self, k):
        lo, hi = self.bounds[k]
        return gaussian_kernel(self.Y[lo:hi], self.Y, self.beta)

    def __call__(self, B: np.ndarray) -> np.ndarray:
        if self.store and self.blocks is None:
            self.blocks = self._map(self._block)
        blocks = self.blocks
        out = np.empty((self.Y.shape[0], B.shape[1]))

        def product(k):
            lo, hi = self.bounds[k]
            out[lo:hi] = (blocks[k] if blocks is not None else self._block(k)) @ B

        self._map(product)
        return out


def low_rank_kernel(Y, beta: float, rank, *, power_iterations: int = 2, seed: int = 0, pool=None):
    """Top eigenpairs of ``G(Y, Y)``: returns ``(Q (M, K), lam (K,), kept_trace_fraction)``.

    Randomised subspace iteration (Halko et al. 2011, Alg. 4.4 + 5.3; the power iterations
    normalised by a pivoted LU, as scikit-learn's randomized_svd and fbpca do) with a fixed seed
    (deterministic). ``rank`` is an int K or ``"auto"``: the smallest K whose eigenvalues hold
    :data:`AUTO_RANK_TRACE` of ``trace(G) = M`` (predicted from a 300-point subsample's spectrum,
    verified, doubled if short).
    ``pool`` (a ``concurrent.futures`` executor) computes the kernel's row blocks in threads; the
    blocks are kept between the products up to :data:`KERNEL_STORE_ELEMENTS`. Neither changes a bit
    of the result.
    """
    Y = as_points(Y, "source", min_points=1)
    M = Y.shape[0]
    rng = np.random.default_rng(seed)
    product = _KernelProduct(Y, beta, pool=pool)
    if rank == "auto":
        # predict K from the spectrum of a strided subsample (eigenvalues scale ~ M / m), then verify
        m = min(M, 300)
        sub = Y[(np.arange(m) * (M / m)).astype(int)]
        ev = np.sort(np.linalg.eigvalsh(gaussian_kernel(sub, sub, beta)))[::-1]
        k_pred = int(np.searchsorted(np.cumsum(ev) / m, AUTO_RANK_TRACE) + 1)
        k = min(M, int(1.25 * k_pred) + 8)
        while True:
            Q, lam = _randomized_eigh(Y, beta, k, power_iterations, rng, product)
            kept = float(lam.sum()) / M
            if kept >= AUTO_RANK_TRACE or k >= M:
                break
            k = min(M, 2 * k)
        # trim to the smallest prefix that reaches the target
        csum = np.cumsum(lam) / M
        k_use = int(min(len(lam), np.searchsorted(csum, AUTO_RANK_TRACE) + 1))
        return Q[:, :k_use], lam[:k_use], float(csum[k_use - 1])
    try:
        k = int(rank)
    except (TypeError, ValueError):
        raise InputError(f"low_rank: expected None, a positive int or 'auto', got {rank!r}") from None
    if k < 1:
        raise InputError(f"low_rank: rank must be >= 1, got {k}")
    k = min(k, M)
    Q, lam = _randomized_eigh(Y, beta, k, power_iterations, rng, product)
    return Q, lam, float(lam.sum()) / M


def _randomized_eigh(Y, beta, k, power_iterations, rng, product):
    M = Y.shape[0]
    if M <= 2 * k + 10 or M <= 200:
        lam, Q = scipy.linalg.eigh(gaussian_kernel(Y, Y, beta), subset_by_index=[M - k, M - 1])
    else:
        p = min(M - k, max(10, k // 4))
        Z = product(rng.standard_normal((M, k + p)))
        for _ in range(power_iterations):
            # between power iterations any well-conditioned basis of span(Z) will do: the pivoted LU factor
            # (P L spans the same space; 7x cheaper than a QR here); the last one is a QR (orthonormal)
            Z = product(scipy.linalg.lu(Z, permute_l=True, check_finite=False)[0])
        Z, _ = np.linalg.qr(Z)
        GZ = product(Z)
        Bs = Z.T @ GZ
        lam, S = np.linalg.eigh(0.5 * (Bs + Bs.T))
        Q = Z @ S
        lam, Q = lam[-k:], Q[:, -k:]
    order = np.argsort(lam)[::-1]
    lam = np.maximum(lam[order], 0.0)
    Q = Q[:, order]
    keep = lam > 1e-12 * max(lam[0], 1e-300)
    return np.ascontiguousarray(Q[:, keep]), lam[keep]
