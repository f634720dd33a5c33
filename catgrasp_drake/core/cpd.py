"""Coherent Point Drift: non-rigid (paper eqs. 1-8) and rigid with scale (numpy + scipy only).

Model (Myronenko & Song 2010): the ``M`` source points, moved by a transform
``T``, are the centres of an isotropic Gaussian mixture with variance
``sigma2``, plus a uniform outlier component of weight ``w``; the ``N`` target
points are drawn from it. EM minimises

    f = -sum_n log( sum_m exp(-|x_n - T(y_m)|^2 / (2 sigma2)) + c ) + (N D / 2) log sigma2
        + lam / 2 * tr(W^T G W)                           (non-rigid only)

with ``c = (2 pi sigma2)^(D/2) w / (1 - w) * M / N`` (paper eq. 7), non-rigid
``T(Y) = Y + G W`` with the Gaussian kernel ``G_ij = exp(-|y_i - y_j|^2 / (2 beta^2))``
(eqs. 4-5) and the M-step ``(G + lam sigma2 d(P1)^-1) W = d(P1)^-1 P X - Y``
(eq. 8), solved in the equivalent division-free form
``(d(P1) G + lam sigma2 I) W = P X - d(P1) Y``.

Units and normalisation
-----------------------
Both clouds are normalised *jointly* (one shift, one scale: the RMS distance of
the union from its centroid) before EM, as in Myronenko's reference code, so
that ``w`` (whose uniform density is ``1/N`` in the paper's formula) means the
same thing for objects in metres as for unit-size data, and ``lam`` is
dimensionless. Inputs and outputs are in the caller's units (metres):

* ``beta`` -- kernel width in metres (converted internally to ``beta / scale``);
* ``lam`` -- dimensionless, applied in normalised coordinates (the paper's);
* ``w`` -- outlier weight in [0, 1);
* ``sigma2`` -- initial variance in m^2, or None for the data estimate
  ``sum_mn |x_n - y_m|^2 / (D M N)``.

The paper's values ``beta = 1, lambda = 3, sigma2 = 0.01`` were given in
normalised units; for a drill (RMS radius ~0.07 m) ``beta = 1`` would be a 0.07 m
kernel. The defaults of this module (``DEFAULT_BETA_M = 0.02`` m,
``DEFAULT_LAMBDA = 3``) were chosen on the real drill set (see
benchmarks/RESULTS_core.md).

Convergence: EM stops when the objective ``f`` changes by less than
``tol`` per target point (``|f_k - f_{k-1}| / N < tol``; differences of ``f``
do not depend on the coordinate scale), or when ``sigma2`` reaches its floor.
Both registrations run the EM loop :func:`catgrasp_drake.core.em.em_loop`
(shared with the latent inference) with their own M-step.

Speed-ups (all exact or with a stated, measured error):

* E-step without an ``M x N x D`` temporary: the exponents come from one
  GEMM of augmented coordinates, evaluated in column blocks (bounded memory:
  ``M x block`` floats per thread) and in parallel threads (numpy's ``exp`` and
  BLAS release the GIL). Columns whose every kernel value underflows (points far
  from everything) are recomputed in the log domain: no division by zero, no NaN.
* Truncated E-step (``e_step="truncated"``, the default): once ``sigma`` is small
  enough that at most 1 % of the pairs lie within ``9 sigma`` of each other, only
  those pairs are evaluated (k-d tree pair search); every dropped kernel value is
  below ``exp(-81/2) = 2.6e-18`` and a target column whose dropped mass could exceed
  ``1e-9`` of its denominator is computed exactly, so each posterior column is within
  ``2e-9`` (L1) of the dense one. Dense and exact while ``sigma`` is large.
  On the committed shape spaces' registrations it moves the deformed points by
  < 1e-12 m (``benchmarks/bench_cpd.py --committed``); ``e_step="exact"`` is the dense
  E-step throughout.
* ``e_step="fast"``: the truncated E-step, and its dense blocks in float32 while the
  exponent rounding bound ``8 eps32 (max|y| + max|x|)^2 / (2 sigma2)`` is at most
  ``3e-3`` (measured errors of the posterior sums ~1e-6 - 5e-5 relative); ~1.7x faster
  dense iterations. Not the default: on the committed shape spaces' registrations it
  moves the deformed points by up to 1.8e-5 m (the truncated E-step: < 1e-12 m).
* ``low_rank=K``: ``G ~ Q diag(lam_K) Q^T`` from the top-``K`` eigenpairs
  (randomised subspace iteration with a fixed seed; ``G``'s row blocks kept between
  the products up to 64 MiB, recomputed above); the
  M-step becomes a ``K x K`` solve. ``W`` is returned projected on ``span(Q)``
  so that the exact kernel gives the same displacements as the low-rank one
  at the source points (``G Q = Q diag(lam)``). ``low_rank="auto"`` picks ``K``
  so that the kept eigenvalues hold ``1 - 1e-4`` of ``trace(G) = M``.
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg
from scipy.spatial import cKDTree

from catgrasp_drake.core.em import EMResult, MStep, em_loop, sigma2_update, squarem
from catgrasp_drake.core.kernels import gaussian_kernel, kernel_width, low_rank_kernel, sqdist
from catgrasp_drake.core.threads import blas_single_threaded, n_threads
from catgrasp_drake.core.validation import as_points, count, non_negative, outlier_weight, positive
from catgrasp_drake.errors import InputError

#: Kernel width (m) used by the project's defaults (tuned on the real drills).
DEFAULT_BETA_M = 0.02
#: Regularisation weight (dimensionless, normalised coordinates).
DEFAULT_LAMBDA = 3.0
#: The paper's values, in its normalised units (documentation only).
PAPER_BETA, PAPER_LAMBDA, PAPER_SIGMA2 = 1.0, 3.0, 0.01
#: Floor of sigma2 in normalised units (keeps exact-fit problems finite).
SIGMA2_FLOOR = 1e-10
#: Most source points of the exact kernel (M x M doubles: 3.2 GB, O(M^3) per iteration) and of the
#: low-rank one (O(M^2) kernel evaluations per product).
MAX_SOURCE_EXACT = 20_000
MAX_SOURCE_LOW_RANK = 200_000

#: E-step block: M x block <= 512k doubles = 4 MB per thread.
BLOCK_ELEMENTS = 1 << 19


@dataclass(frozen=True)
class CPDIteration:
    """What a callback receives after each EM iteration (caller's units)."""

    iteration: int
    transformed: np.ndarray
    sigma2: float
    objective: float


@dataclass(frozen=True)
class NonRigidCPDResult:
    """Result of :func:`nonrigid_cpd` (metres unless stated).

    ``W`` (M, 3) kernel weights such that ``source + gaussian_kernel(source, source, beta) @ W``
    equals ``transformed``; ``objective`` is the final value of ``f`` in normalised
    coordinates; ``P1`` (M,) the final posterior mass of each source point;
    ``rank`` the kernel rank used (M when exact); ``kernel_trace_kept`` the
    fraction of ``trace(G)`` kept by the low-rank kernel (1.0 when exact).
    """

    W: np.ndarray
    transformed: np.ndarray
    sigma2: float
    iterations: int
    converged: bool
    objective: float
    beta: float
    lam: float
    w: float
    P1: np.ndarray
    rank: int
    kernel_trace_kept: float


@dataclass(frozen=True)
class RigidCPDResult:
    """Result of :func:`rigid_cpd`: ``transformed = s * source @ R.T + t``."""

    R: np.ndarray
    t: np.ndarray
    s: float
    transformed: np.ndarray
    sigma2: float
    iterations: int
    converged: bool
    objective: float
    P1: np.ndarray

    def transform(self, points) -> np.ndarray:
        """Apply the estimated similarity to other (K, 3) points."""
        p = as_points(points, "points")
        return self.s * p @ self.R.T + self.t


# --------------------------------------------------------------------------- helpers


def joint_normalization(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre and scale used inside CPD: centroid of the union and its RMS radius."""
    both = np.concatenate([source, target], axis=0)
    center = both.mean(axis=0)
    scale = float(np.sqrt(((both - center) ** 2).sum(1).mean()))
    if not np.isfinite(scale) or scale <= 0.0:
        scale = 1.0  # all points coincide: any scale works
    return center, scale


def initial_sigma2(source: np.ndarray, target: np.ndarray) -> float:
    """``sum_mn |x_n - y_m|^2 / (D M N)`` in O((M + N) D)."""
    M, D = source.shape
    N = target.shape[0]
    total = M * (target * target).sum() + N * (source * source).sum() - 2.0 * source.sum(0) @ target.sum(0)
    return max(float(total) / (D * M * N), 0.0)


#: Minimum number of column blocks of a threaded E-step. Fixed rather than the number of cores, so the
#: summation order, hence every result bit, does not depend on the machine (with one block per core,
#: results differed by ~1e-10 between 1, 2, 3 and 4 threads).
THREADED_BLOCKS = 2


@dataclass(frozen=True)
class EStep:
    """Sufficient statistics of one E-step: ``P1 = P 1``, ``Pt1 = P^T 1``, ``PX = P X``,
    ``Np = 1^T P 1`` and ``nll`` (negative log-likelihood of the targets, normalised units)."""

    P1: np.ndarray
    Pt1: np.ndarray
    PX: np.ndarray
    Np: float
    nll: float


_EXP_CLAMP = -300.0  # exponents below this are clamped (relative error < e^-50 per kept column)
_BAD_LOGSUM = -250.0  # a column whose largest exponent is below this is redone in the log domain
_NO_CLAMP_BOUND = 290.0  # every exponent provably >= -290 (> -300 after rounding): the clamp would change nothing
# float32 blocks: exponents are clamped at -87, where float32's normal range ends (e^-87 = 1.6e-38 > 1.18e-38), so
# no subnormal is made (3-6x slower blocks on an Intel Xeon: bench_cpd.py --subnormals); a column gains at most
# M e^-87 of mass, < M e^-27 relative to any column whose sum is above e^-60; columns below that are redone
_EXP_CLAMP32 = -87.0
_BAD_LOGSUM32 = -60.0
#: Machine epsilon of float32 (the rounding unit of ``e_step="fast"``'s exponents).
EPS32 = float(np.finfo(np.float32).eps)
#: Relative error bound of a kernel value of ``estep(kernel32=True)`` against float64: a float64 exponent
#: ``|e| <= 87`` rounded to float32 (``87 eps32 / 2``) and float32's ``exp`` (a few ulp).
KERNEL32_RTOL = 87.0 * EPS32 / 2.0 + 4.0 * EPS32


def _estep_block(Ya, Ysc, X, Xa, sigma2, log_c, lo, hi, clamp=True, kernel32=False):
    """E-step for target columns lo:hi. Returns partial [P X | P 1] (M, D+1), Pt1 block, sum log den.

    Exponents are clamped at -300 (float32: -87) before ``exp`` so that no subnormal number is
    ever produced (subnormals slow BLAS and ``exp`` down by 10x); a column whose
    kernel sum is below ``e^-250`` is recomputed exactly with a max-shift, so
    the clamp changes a kept column by less than ``M e^-50`` relative.
    ``clamp=False`` when no exponent can be below -300 (the clamp is then a no-op).
    With float32 ``Ya``/``Xa`` (``e_step="fast"``) the kernel values, their sums and products are float32
    (clamp at -87, log-domain redo below ``e^-60``; the redo and the accumulation across blocks are float64).
    ``kernel32`` with float64 ``Ya``/``Xa``: the exponents in float64 (clamped at -87 and redone below ``e^-60``
    as float32's), their ``exp`` in float32, everything after in float64, so a kernel value's relative error is at
    most ``87 eps32 / 2`` plus float32 exp's few ulp (:data:`KERNEL32_RTOL`, < 6e-6) whatever ``sigma2``.
    """
    f32 = Ya.dtype == np.float32
    E = Ya @ Xa[lo:hi].T  # exponents -|y - x|^2 / (2 sigma2), (M, nb)
    if f32 or kernel32:
        np.maximum(E, _EXP_CLAMP32, out=E)
    elif clamp:
        np.maximum(E, _EXP_CLAMP, out=E)
    if kernel32:  # (estep passes it only with float64 exponents)
        # float32 exp of the float64 exponents, stored back as float64: the sums and products below stay float64,
        # so P1, Pt1 and PX are consistent sums of the same kernel values (Np the same either way to 1e-16: in
        # float32 they differ by ~1e-6 relative, a shift of ~1e-6 |X| in the M-step's means, 1 mm at 1 km)
        E[...] = np.exp(E, dtype=np.float32)
    else:
        np.exp(E, out=E)
    s = E.sum(axis=0).astype(np.float64, copy=False)
    c = math.exp(min(log_c, 700.0)) if log_c > -700.0 else 0.0  # (a huge given sigma2: no overflow)
    den = s + c
    bad = s < math.exp(_BAD_LOGSUM32 if f32 or kernel32 else _BAD_LOGSUM)  # (clamped at -87: redo below e^-60)
    with np.errstate(divide="ignore"):
        logden = np.log(den)
    inv = 1.0 / np.where(bad, 1.0, den)
    pt1 = s * inv
    if np.any(bad):
        idx = np.flatnonzero(bad)
        e = -sqdist(Ysc, X[lo:hi][idx]) / (2.0 * sigma2)
        m = e.max(axis=0)
        a = np.exp(np.maximum(e - m, -700.0))
        log_shifted_c = log_c - m
        den_b = a.sum(axis=0) + np.exp(np.minimum(log_shifted_c, 700.0))
        pb = a / den_b
        pb[pb < (1e-30 if f32 else 1e-200)] = 0.0  # outliers far from everything: exactly no mass, no subnormals
        E[:, idx] = pb
        inv[idx] = 1.0
        pt1[idx] = pb.sum(axis=0)
        logden[idx] = m + np.logaddexp(np.log(a.sum(axis=0)), log_shifted_c)
    rhs = np.empty((hi - lo, X.shape[1] + 1), dtype=E.dtype)
    rhs[:, :-1] = X[lo:hi] * inv[:, None]
    rhs[:, -1] = inv
    acc = E @ rhs
    return acc.astype(np.float64, copy=False), pt1, float(logden.sum())


def _log_uniform(w, sigma2, D, M, N):
    """Log of the uniform term ``c`` of paper eq. 7 (-inf without outliers)."""
    if w > 0.0:
        return 0.5 * D * math.log(2.0 * math.pi * sigma2) + math.log(w / (1.0 - w)) + math.log(M / N)
    return -math.inf


def _augmented(Y_t, X, sigma2, dtype=np.float64):
    """Centred coordinates and the augmented factors whose product is the exponent matrix."""
    M, D = Y_t.shape
    N = X.shape[0]
    ctr = X.mean(axis=0)
    Ysc = Y_t - ctr
    Xc = X - ctr
    inv2s = 0.5 / sigma2
    Ya = np.empty((M, D + 2), dtype=dtype)
    Ya[:, :D] = Ysc / sigma2
    Ya[:, D] = -inv2s * (Ysc * Ysc).sum(1)
    Ya[:, D + 1] = 1.0
    Xa = np.empty((N, D + 2), dtype=dtype)
    Xa[:, :D] = Xc
    Xa[:, D] = 1.0
    Xa[:, D + 1] = -inv2s * (Xc * Xc).sum(1)
    return ctr, Ysc, Xc, Ya, Xa


def exponent_bound(Ysc: np.ndarray, Xc: np.ndarray, sigma2: float) -> float:
    """``(max|y| + max|x|)^2 / (2 sigma2)`` for centred clouds: bounds every exponent's magnitude and the sum
    of the magnitudes of the terms of its augmented product (hence its rounding error, ~8 eps times this)."""
    ry = math.sqrt(float((Ysc * Ysc).sum(1).max()))
    rx = math.sqrt(float((Xc * Xc).sum(1).max()))
    return (ry + rx) ** 2 / (2.0 * sigma2)


def estep(Y_t: np.ndarray, X: np.ndarray, sigma2: float, w: float, *, pool=None,
          log_uniform: float | None = None, dtype=np.float64, kernel32: bool = False) -> EStep:
    """CPD E-step for transformed source ``Y_t`` (M, D) and targets ``X`` (N, D).

    ``log_uniform`` overrides the log of the uniform-term constant ``c`` (the
    default is paper eq. 7's ``(2 pi sigma2)^(D/2) w/(1-w) M/N``). Works in any
    units but is written for normalised coordinates. ``dtype=np.float32`` evaluates
    the kernel in float32 (twice the speed; exponent error ~8 eps32 :func:`exponent_bound`).
    ``kernel32=True`` (with float64 ``dtype``): the exponents in float64, their ``exp`` in float32, the sums in
    float64 (``exp`` is most of an E-step and float32's is 3x faster here); every kernel value within a relative
    :data:`KERNEL32_RTOL` of float64's, whatever ``sigma2`` (:func:`exponent_bound` does not enter).
    """
    M, D = Y_t.shape
    N = X.shape[0]
    log_c = _log_uniform(w, sigma2, D, M, N) if log_uniform is None else log_uniform
    # centre for accurate augmented GEMM
    ctr, Ysc, Xc, Ya, Xa = _augmented(Y_t, X, sigma2, dtype)
    clamp = exponent_bound(Ysc, Xc, sigma2) > _NO_CLAMP_BOUND
    nb = max(16, BLOCK_ELEMENTS // max(M, 1))
    if pool is not None:  # at least THREADED_BLOCKS blocks, a fixed number: results independent of the cores
        nb = max(16, min(nb, -(-N // THREADED_BLOCKS)))
    bounds = [(lo, min(N, lo + nb)) for lo in range(0, N, nb)]
    args = (Ya, Ysc, Xc, Xa, sigma2, log_c)
    kernel32 = bool(kernel32) and Ya.dtype != np.float32
    if pool is not None and len(bounds) > 1:
        parts = list(pool.map(lambda b: _estep_block(*args, *b, clamp=clamp, kernel32=kernel32), bounds))
    else:
        parts = [_estep_block(*args, lo, hi, clamp=clamp, kernel32=kernel32) for lo, hi in bounds]
    acc = parts[0][0]
    for p in parts[1:]:
        acc = acc + p[0]
    Pt1 = np.concatenate([p[1] for p in parts])
    sum_logden = sum(p[2] for p in parts)
    return _statistics(acc, Pt1, sum_logden, ctr, w, sigma2, M, N, D)


def _statistics(acc, Pt1, sum_logden, ctr, w, sigma2, M, N, D) -> EStep:
    """EStep from the accumulated [P Xc | P 1] (Xc = X - ctr), P^T 1 and sum_n log den_n."""
    P1 = acc[:, -1].copy()
    P1[P1 < 1e-100] = 0.0  # keeps d(P1) G free of subnormals
    PX = acc[:, :-1] + np.outer(P1, ctr)  # undo the centring of X
    Np = float(P1.sum())
    if w > 0.0:
        const = -N * math.log((1.0 - w) / M)
    else:
        const = N * math.log(M)
    nll = -sum_logden + const + 0.5 * N * D * math.log(2.0 * math.pi * sigma2)
    return EStep(P1=P1, Pt1=Pt1, PX=PX, Np=Np, nll=nll)


#: E-step variants of :func:`nonrigid_cpd` (``e_step=``); see :class:`TruncatedEStep`.
E_STEPS = ("exact", "truncated", "fast")
#: Truncated E-step: pairs farther apart than ``TRUNCATION_K * sigma`` are dropped (each kernel value
#: below ``exp(-TRUNCATION_K^2 / 2)`` = 2.6e-18) ...
TRUNCATION_K = 9.0
#: ... and a target column is recomputed exactly unless its dropped mass, at most ``M exp(-K^2/2)``, is at
#: most this fraction of its kept denominator (so every posterior column is within 2x this in L1).
TRUNCATION_RTOL = 1e-9
#: The neighbour-list E-step is used when at most this fraction of the M x N pairs is within reach
#: (measured break-even with the dense E-step at M = N = 2000: ~1-2 %).
SPARSE_PAIR_FRACTION = 0.01
#: ... and at most this many pairs (~64 bytes each while they are processed: <= 128 MiB); dense above.
MAX_SPARSE_PAIRS = 1 << 21
#: ``e_step="fast"``: dense blocks in float32 while the exponent rounding bound ``8 eps32 B``
#: (:func:`exponent_bound`) is at most this (relative error of a kernel value); float64 below.
F32_EXPONENT_TOL = 3e-3
_PAIR_SAMPLE = 32  # targets whose neighbour counts estimate the pair fraction


class TruncatedEStep:
    """The E-step of ``nonrigid_cpd(e_step="truncated" | "fast")`` for fixed targets ``X`` (N, D).

    Per call (one EM iteration) it picks:

    * neighbour lists, when at most :data:`SPARSE_PAIR_FRACTION` of the pairs (and at most
      :data:`MAX_SPARSE_PAIRS`) lie within ``r = TRUNCATION_K sigma`` (estimated from the
      neighbour counts of a fixed subsample of the source; no tree while ``r`` spans both clouds'
      bounding box): the pairs within ``r`` from a k-d tree pair search (scipy ``cKDTree``; the trees
      of X's two fixed halves are built once and searched in two threads), their kernel values
      from the exact distances; dropped pairs have kernel values below ``exp(-K^2/2)``, and a
      column whose bound ``M exp(-K^2/2) / (s_n + c)`` exceeds :data:`TRUNCATION_RTOL` is computed
      exactly (dense, float64) -- columns with no neighbour too;
    * else the dense float64 E-step (:func:`estep`, exact), or with ``fast=True`` its float32 blocks
      while ``8 eps32`` :func:`exponent_bound` ``<=`` :data:`F32_EXPONENT_TOL`.

    ``mode`` records the choice of the last call ("sparse", "dense32", "dense").
    """

    def __init__(self, X: np.ndarray, w: float, *, fast: bool = False, pool=None):
        self.X, self.w, self.fast, self.pool = X, w, fast, pool
        N = X.shape[0]
        step = -(-N // THREADED_BLOCKS)
        self.bounds = [(lo, min(N, lo + step)) for lo in range(0, N, step)]
        self._trees = None
        self.ctr = X.mean(axis=0)
        self.Xc = X - self.ctr
        self._x_lo, self._x_hi = X.min(axis=0), X.max(axis=0)
        self._skip_above = math.inf  # no pair count is estimated for r above this (the fraction is surely too high)
        self.mode = None

    @property
    def trees(self):
        """k-d trees of the targets in :data:`THREADED_BLOCKS` fixed column ranges (built once)."""
        if self._trees is None:
            self._trees = [cKDTree(self.X[lo:hi]) for lo, hi in self.bounds]
        return self._trees

    def _sparse_pays(self, T: np.ndarray, r: float) -> bool:
        if r >= self._skip_above:
            return False
        lo = np.minimum(T.min(axis=0), self._x_lo)
        hi = np.maximum(T.max(axis=0), self._x_hi)
        if r * r >= float(((hi - lo) ** 2).sum()):  # the ball spans both clouds' box: every pair is in reach
            return False
        M, N = T.shape[0], self.X.shape[0]
        n = min(M, _PAIR_SAMPLE)
        sample = (np.arange(n) * (M / n)).astype(int)  # fixed, spread over the source's order
        frac = sum(float(np.sum(t.query_ball_point(T[sample], r, return_length=True))) for t in self.trees) / (n * N)
        if frac > SPARSE_PAIR_FRACTION or frac * M * N > MAX_SPARSE_PAIRS:
            # in a cloud of dimension <= 3 a ball's count shrinks about like r^3 at most: no new estimate until r
            # could have brought the fraction to the threshold (a speed heuristic: the error bound never depends on it)
            self._skip_above = r * (min(SPARSE_PAIR_FRACTION, MAX_SPARSE_PAIRS / (M * N)) / frac) ** (1.0 / 3.0)
            return False
        return True

    def __call__(self, T: np.ndarray, sigma2: float) -> EStep:
        X, w = self.X, self.w
        M, D = T.shape
        r = TRUNCATION_K * math.sqrt(sigma2)
        if self._sparse_pays(T, r):
            self.mode = "sparse"
            return self._sparse(T, sigma2, r)
        if self.fast:
            if 8.0 * EPS32 * exponent_bound(T - self.ctr, self.Xc, sigma2) <= F32_EXPONENT_TOL:
                self.mode = "dense32"
                return estep(T, X, sigma2, w, pool=self.pool, dtype=np.float32)
        self.mode = "dense"
        return estep(T, X, sigma2, w, pool=self.pool)

    def _sparse(self, T, sigma2, r) -> EStep:
        X, w = self.X, self.w
        M, D = T.shape
        N = X.shape[0]
        log_c = _log_uniform(w, sigma2, D, M, N)
        c = math.exp(min(log_c, 700.0)) if log_c > -700.0 else 0.0
        tree_T = cKDTree(T)
        bound = M * math.exp(-0.5 * TRUNCATION_K**2)
        Xc = self.Xc

        def part(h):  # the targets of one fixed column range (pair search without the GIL)
            lo, hi = self.bounds[h]
            pairs = tree_T.sparse_distance_matrix(self.trees[h], r, output_type="ndarray")
            i, j, d = pairs["i"], pairs["j"], pairs["v"]
            k = np.exp(d * d * (-0.5 / sigma2))
            s = np.bincount(j, k, minlength=hi - lo)
            den = s + c
            exact = den * TRUNCATION_RTOL < bound
            if np.any(exact):
                keep = ~exact[j]
                i, j, k = i[keep], j[keep], k[keep]
            p = k / den[j]
            acc = np.empty((M, D + 1))
            xs = Xc[lo:hi]
            for dim in range(D):
                acc[:, dim] = np.bincount(i, p * xs[j, dim], minlength=M)
            acc[:, D] = np.bincount(i, p, minlength=M)
            with np.errstate(divide="ignore"):
                logden = float(np.log(den[~exact]).sum())
            return acc, s / np.where(exact, 1.0, den), logden, exact  # (exact columns: redone below)

        hs = range(len(self.bounds))
        parts = list(self.pool.map(part, hs)) if self.pool is not None else [part(h) for h in hs]
        acc = parts[0][0]
        for q in parts[1:]:
            acc = acc + q[0]
        Pt1 = np.concatenate([q[1] for q in parts])
        sum_logden = sum(q[2] for q in parts)
        cols = np.flatnonzero(np.concatenate([q[3] for q in parts]))
        if len(cols):
            _, Ysc, _, Ya, _ = _augmented(T, X, sigma2)
            Xs = Xc[cols]
            Xa = np.empty((len(cols), D + 2))
            Xa[:, :D] = Xs
            Xa[:, D] = 1.0
            Xa[:, D + 1] = (-0.5 / sigma2) * (Xs * Xs).sum(1)
            extra, pt1, extra_logden = _estep_block(Ya, Ysc, Xs, Xa, sigma2, log_c, 0, len(cols))
            acc += extra
            Pt1[cols] = pt1
            sum_logden += extra_logden
        return _statistics(acc, Pt1, sum_logden, self.ctr, w, sigma2, M, N, D)


#: Clouds whose centroids are more than this many (larger) RMS radii apart are "far apart".
FAR_APART = 10.0


def _far_apart(Y: np.ndarray, X: np.ndarray) -> bool:
    radius = max(float(np.sqrt(((P - P.mean(0)) ** 2).sum(1).mean())) for P in (Y, X))
    return float(np.linalg.norm(X.mean(0) - Y.mean(0))) > FAR_APART * max(radius, 1e-300)


def _check_common(source, target, w, max_iter, tol):
    Y = as_points(source, "source", min_points=3)
    X = as_points(target, "target", min_points=3)
    w = outlier_weight(w)
    max_iter = count(max_iter, "max_iter", 1)
    tol = non_negative(tol, "tol")
    if Y.shape[1] != X.shape[1]:
        raise InputError(f"source and target dimensions differ: {Y.shape[1]} vs {X.shape[1]}")
    return Y, X, w, max_iter, tol


def _normalized(Y, X, sigma2):
    """``(center, scale, Yn, Xn, s2)``: the clouds in CPD's normalised units and the starting variance there."""
    center, scale = joint_normalization(Y, X)
    Yn, Xn = (Y - center) / scale, (X - center) / scale
    s2 = initial_sigma2(Yn, Xn) if sigma2 is None else positive(sigma2, "sigma2") / scale**2
    return center, scale, Yn, Xn, max(s2, SIGMA2_FLOOR)


def _reporter(callback, center, scale):
    """The EM loop's callback for a user ``callback(CPDIteration)`` (normalised units -> the caller's)."""
    if callback is None:
        return None
    return lambda k, T, s2, f: callback(CPDIteration(k, center + scale * T, s2 * scale**2, f))


# --------------------------------------------------------------------------- non-rigid


def _exact_mstep(G, P1, B, lam_s2):
    """Solve ``(d(P1) G + lam_s2 I) W = B`` (eq. 8 without d(P1)^-1) by Cholesky.

    On the support ``I = {P1 > 0}`` the substitution ``W = S U`` with
    ``S = d(P1)^(1/2)`` gives the SPD system ``(S G S + lam_s2 I) U = S^-1 B``;
    off the support ``B`` is zero (a point with no posterior mass has
    ``PX = 0``), so ``W`` is zero there.
    """
    I = np.flatnonzero(P1 > 0.0)
    W = np.zeros_like(B)
    if len(I) == 0:
        return W
    sq = np.sqrt(P1[I])

    def system():
        A = G[np.ix_(I, I)] if len(I) < len(P1) else G.copy()
        A *= sq[:, None]
        A *= sq[None, :]
        A[np.diag_indices(len(I))] += lam_s2
        return A

    rhs = B[I] / sq[:, None]
    try:
        c = scipy.linalg.cho_factor(system(), lower=True, overwrite_a=True, check_finite=False)
        U = scipy.linalg.cho_solve(c, rhs, overwrite_b=False, check_finite=False)
    except np.linalg.LinAlgError:  # numerically not positive definite (tiny lam * sigma2, duplicate points)
        U = scipy.linalg.lstsq(system(), rhs, check_finite=False)[0]
    W[I] = sq[:, None] * U
    return W



def _gram_and_rhs(Q, P1, B, pool):
    """``(Q^T d(P1) Q, Q^T B)`` of the low-rank M-step as one product per half of the rows, the halves in
    threads (a fixed split: the same bits for any number of cores)."""
    M, K = Q.shape
    bounds = [(lo, min(M, lo + -(-M // THREADED_BLOCKS))) for lo in range(0, M, -(-M // THREADED_BLOCKS))]

    def part(b):
        lo, hi = b
        R = np.empty((hi - lo, K + B.shape[1]))
        np.multiply(P1[lo:hi, None], Q[lo:hi], out=R[:, :K])
        R[:, K:] = B[lo:hi]
        return Q[lo:hi].T @ R

    parts = list(pool.map(part, bounds)) if pool is not None else [part(b) for b in bounds]
    S = parts[0]
    for p in parts[1:]:
        S = S + p
    return S[:, :K], S[:, K:]


def _low_rank_mstep(Q, lam_k, P1, B, lam_s2, *, pool=None, split=True):
    """Solve the M-step with ``G ~ Q diag(lam_k) Q^T`` for ``Z`` (``W = Q Z``, K x D):
    ``(Q^T d(P1) Q diag(lam_k) + lam_s2 I) Z = Q^T B``. ``split``: the products by :func:`_gram_and_rhs`."""
    if split:
        QtDQ, QtB = _gram_and_rhs(Q, P1, B, pool)
    else:
        QtDQ, QtB = Q.T @ (P1[:, None] * Q), Q.T @ B
    A = QtDQ * lam_k[None, :]
    A[np.diag_indices(len(lam_k))] += lam_s2
    try:
        return np.linalg.solve(A, QtB)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(A, QtB, rcond=None)[0]


@blas_single_threaded
def nonrigid_cpd(
    source,
    target,
    *,
    beta: float = DEFAULT_BETA_M,
    lam: float = DEFAULT_LAMBDA,
    w: float = 0.0,
    sigma2: float | None = None,
    max_iter: int = 150,
    tol: float = 1e-5,
    low_rank=None,
    e_step: str = "truncated",
    acceleration: str | None = None,
    callback: Callable[[CPDIteration], object] | None = None,
) -> NonRigidCPDResult:
    """Non-rigid CPD moving ``source`` (M, 3) onto ``target`` (N, 3), paper eqs. 5-8.

    See the module docstring for units, normalisation and convergence.
    ``low_rank``: None (exact kernel, one Cholesky per iteration, O(M^3)), an int K or
    ``"auto"``. ``e_step``: ``"truncated"`` (default: neighbour lists once sigma is small, error
    bounded by :data:`TRUNCATION_RTOL` per posterior column; dense float64 before), ``"exact"`` (dense
    float64 throughout: the E-step before the truncation existed) or ``"fast"`` (truncated, and
    float32 dense blocks while their bound allows): see :class:`TruncatedEStep`.
    ``acceleration``: None (plain EM) or ``"squarem"``: the same EM steps, extrapolated by
    :func:`~catgrasp_drake.core.em.squarem` over the kernel weights and ``log sigma2`` (the same
    fixed point; 46 instead of 69 EM steps, 0.51 -> 0.34 s at the same error on
    ``benchmarks/bench_cpd.py``'s 2000 points); ``max_iter`` then bounds the EM steps and
    ``iterations`` counts them.
    ``callback(CPDIteration)`` is called after each iteration (each EM step).
    """
    Y, X, w, max_iter, tol = _check_common(source, target, w, max_iter, tol)
    if not isinstance(e_step, str) or e_step not in E_STEPS:
        raise InputError(f"e_step: expected one of {', '.join(E_STEPS)}, got {e_step!r}")
    if acceleration not in ACCELERATIONS:
        raise InputError(f"acceleration: expected None or 'squarem', got {acceleration!r}")
    beta = kernel_width(beta)
    lam = positive(lam, "lam")
    limit = MAX_SOURCE_EXACT if low_rank is None else MAX_SOURCE_LOW_RANK
    if len(Y) > limit:
        fix = "pass low_rank='auto' or voxel_downsample the source" if low_rank is None else "voxel_downsample it"
        raise InputError(f"source: {len(Y)} points; the {'exact' if low_rank is None else 'low-rank'} kernel handles "
                         f"at most {limit} ({fix})")
    if _far_apart(Y, X):
        raise InputError(f"source and target are {float(np.linalg.norm(X.mean(0) - Y.mean(0))):.3g} m apart, over "
                         f"{FAR_APART:g}x their size: non-rigid CPD needs them roughly aligned; run rigid_cpd first")
    center, scale, Yn, Xn, s2 = _normalized(Y, X, sigma2)
    bn = beta / scale
    M, D = Yn.shape
    N = Xn.shape[0]

    # threaded by problem size only (a 1-worker pool on one core): the block layout, hence the rounding
    # of the E-step sums, is the same on every machine
    pool = ThreadPoolExecutor(n_threads()) if M * N >= 200_000 else None
    try:
        if low_rank is None:
            G = gaussian_kernel(Yn, Yn, bn)
            Q = lam_k = None
            rank, kept = M, 1.0
        else:
            Q, lam_k, kept = low_rank_kernel(Yn, bn, low_rank, pool=pool)
            G = None
            rank = Q.shape[1]
        truncated = None if e_step == "exact" else TruncatedEStep(Xn, w, fast=e_step == "fast", pool=pool)

        def e_of(k, m, s2):
            return estep(m.centres, Xn, s2, w, pool=pool) if truncated is None else truncated(m.centres, s2)

        def m_step(e, m, s2):  # params: W (exact kernel) or Z (low rank: W = Q Z)
            B = e.PX - e.P1[:, None] * Yn
            if Q is None:
                W = _exact_mstep(G, e.P1, B, lam * s2)
                V = G @ W
                return MStep(Yn + V, 0.5 * lam * float((W * V).sum()), W)
            Z = _low_rank_mstep(Q, lam_k, e.P1, B, lam * s2, pool=pool, split=e_step != "exact")
            LZ = lam_k[:, None] * Z
            return MStep(Yn + Q @ LZ, 0.5 * lam * float((Z * LZ).sum()), Z)

        start = MStep(Yn, 0.0, np.zeros((M, D)) if Q is None else np.zeros((rank, D)))
        if acceleration is None:
            r = em_loop(Xn, e_of, m_step, start, s2, n_iter=max_iter, tol=tol, sigma2_floor=SIGMA2_FLOOR,
                        callback=_reporter(callback, center, scale))
        else:
            r = _squarem_cpd(Xn, Yn, G, Q, lam_k, lam, e_of, m_step, start, s2, max_iter, tol,
                             _reporter(callback, center, scale))
    finally:
        if pool is not None:
            pool.shutdown()
    return NonRigidCPDResult(
        W=scale * (r.m.params if Q is None else Q @ r.m.params),
        transformed=center + scale * r.m.centres,
        sigma2=r.sigma2 * scale**2,
        iterations=r.iterations + (r.stop == "no_mass"),  # (counting the E-step that found no mass, as always)
        converged=r.converged,
        objective=float(r.objective),
        beta=beta,
        lam=lam,
        w=w,
        P1=r.e.P1 if r.e is not None else np.zeros(M),
        rank=rank,
        kernel_trace_kept=kept,
    )


#: ``nonrigid_cpd(acceleration=...)`` values.
ACCELERATIONS = (None, "squarem")


def _squarem_cpd(Xn, Yn, G, Q, lam_k, lam, e_of, m_step, start, s2, max_iter, tol, report) -> EMResult:
    """The non-rigid EM of :func:`nonrigid_cpd` driven by :func:`~catgrasp_drake.core.em.squarem` over
    ``theta = (W or Z flattened, log sigma2)``; returns what :func:`em_loop` would (the last E-step is the
    one at the returned parameters, or the one before them)."""
    shape = start.params.shape
    last = {}

    def at(params):
        """The MStep record of ``params``: its centres and penalty (as ``m_step`` makes them)."""
        if Q is None:
            V = G @ params
            return MStep(Yn + V, 0.5 * lam * float((params * V).sum()), params)
        LZ = lam_k[:, None] * params
        return MStep(Yn + Q @ LZ, 0.5 * lam * float((params * LZ).sum()), params)

    def em_map(theta):
        if not np.isfinite(theta).all():  # an extrapolation gone wild: rejected by its objective
            return theta, math.inf, False
        params, sigma2 = theta[:-1].reshape(shape), math.exp(min(float(theta[-1]), 700.0))
        m = at(params)
        e = e_of(0, m, sigma2)
        last.update(e=e, m=m, sigma2=sigma2)
        f = e.nll + m.penalty
        if e.Np <= 1e-300:
            return theta, f, True
        m2 = m_step(e, m, sigma2)
        s2_next = max(sigma2_update(Xn, m2.centres, e), SIGMA2_FLOOR)
        last["evals"] = last.get("evals", 0) + 1
        if report is not None:
            report(last["evals"], m2.centres, s2_next, f)
        return np.append(m2.params.ravel(), math.log(s2_next)), f, s2_next <= SIGMA2_FLOOR

    theta0 = np.append(np.asarray(start.params, float).ravel(), math.log(s2))
    r = squarem(em_map, theta0, n_points=len(Xn), max_evals=max_iter, tol=tol)
    params, sigma2 = r.theta[:-1].reshape(shape), math.exp(r.theta[-1])
    stop = {"tol": "tol", "max_evals": "max_iter"}.get(r.stop, "floor" if sigma2 <= SIGMA2_FLOOR else "no_mass")
    return EMResult(at(params), last.get("e"), r.objective, sigma2, r.evaluations, stop)


# --------------------------------------------------------------------------- rigid


def weighted_procrustes(PX, P1, Pt1, Np, X, Y, *, scale: bool = True, upright: bool = False):
    """Rigid (+ scale) CPD M-step: ``argmin sum P_mn |x_n - (s R y_m + t)|^2``.

    ``upright`` (3-D only): ``R`` is restricted to rotations about the z axis (an object standing on a
    table whose normal is z keeps its z up; closed form ``yaw = atan2(A_yx - A_xy, A_xx + A_yy)``).
    Returns ``(R, t, s, tr_AR)`` with ``R`` proper (det +1).
    """
    mu_x = (Pt1 @ X) / Np
    mu_y = (P1 @ Y) / Np
    A = PX.T @ Y - Np * np.outer(mu_x, mu_y)  # sum P (x - mu_x)(y - mu_y)^T
    if upright:
        if A.shape != (3, 3):
            raise InputError(f"upright: needs 3-D points, got {A.shape[0]}-D")
        yaw = math.atan2(A[1, 0] - A[0, 1], A[0, 0] + A[1, 1])
        c, si = math.cos(yaw), math.sin(yaw)
        R = np.array([[c, -si, 0.0], [si, c, 0.0], [0.0, 0.0, 1.0]])
        tr_AR = float(np.trace(R.T @ A))
    else:
        U, S, Vt = np.linalg.svd(A)
        C = np.ones(A.shape[0])
        C[-1] = np.sign(np.linalg.det(U @ Vt)) or 1.0
        R = (U * C) @ Vt
        tr_AR = float((S * C).sum())
    if scale:
        yPy = float(P1 @ ((Y - mu_y) ** 2).sum(1))
        s = tr_AR / yPy if yPy > 0 else 1.0
        if not np.isfinite(s) or s <= 0:
            s = 1.0
    else:
        s = 1.0
    t = mu_x - s * R @ mu_y
    return R, t, s, tr_AR


@blas_single_threaded
def rigid_cpd(
    source,
    target,
    *,
    scale: bool = True,
    w: float = 0.0,
    sigma2: float | None = None,
    max_iter: int = 100,
    tol: float = 1e-6,
    callback: Callable[[CPDIteration], object] | None = None,
) -> RigidCPDResult:
    """Rigid (``scale=True``: similarity) CPD of ``source`` onto ``target``.

    ``transformed = s * source @ R.T + t`` with a proper rotation ``R``. Same
    normalisation, outlier model and convergence rule as :func:`nonrigid_cpd`.
    """
    Y, X, w, max_iter, tol = _check_common(source, target, w, max_iter, tol)
    shift = np.zeros(Y.shape[1])
    if _far_apart(Y, X):
        # clouds far apart relative to their size (e.g. 1 km): from the identity every posterior is uniform and
        # the scale collapses to 0 for good; register the centroid-aligned source, then compose the shift
        shift = X.mean(axis=0) - Y.mean(axis=0)
        Y = Y + shift
    center, sc, Yn, Xn, s2 = _normalized(Y, X, sigma2)
    M, D = Yn.shape

    def m_step(e, m, s2):  # params: (R, t, s) in normalised units
        R, t, s, _ = weighted_procrustes(e.PX, e.P1, e.Pt1, e.Np, Xn, Yn, scale=scale)
        return MStep(s * Yn @ R.T + t, 0.0, (R, t, s))

    start = MStep(Yn, 0.0, (np.eye(D), np.zeros(D), 1.0))
    r = em_loop(Xn, lambda k, m, s2: estep(m.centres, Xn, s2, w), m_step, start, s2, n_iter=max_iter, tol=tol,
                sigma2_floor=SIGMA2_FLOOR, callback=_reporter(callback, center, sc))
    R, t, s = r.m.params
    return RigidCPDResult(
        R=R,
        t=center + sc * t - s * R @ center + s * R @ shift,
        s=float(s),
        transformed=center + sc * r.m.centres,
        sigma2=r.sigma2 * sc**2,
        iterations=r.iterations + (r.stop == "no_mass"),  # (as nonrigid_cpd)
        converged=r.converged,
        objective=float(r.objective),
        P1=r.e.P1 if r.e is not None else np.zeros(M),
    )
