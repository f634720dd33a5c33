"""Category shape space: CPD deformation fields -> PCA-EM latent space (paper Sec. III-C, Alg. 1 lines 1-4).

Training: non-rigid CPD from the canonical shape C (M, 3) to every instance
T_i gives W_i (M, 3); the flattened y_i = vec(W_i) (p = 3M values) are
normalised (per-feature mean removed; divided by a standard deviation, see
``standardize``), stacked into Y (K, p), and PCA-EM (eqs. 9-10) finds the
principal subspace. ``q`` is the smallest number of components holding at
least ``variance`` of the total variance.

Latent coordinates are *whitened*: ``x_j = (l_j . y) / sqrt(ev_j)``, with
``l_j`` the j-th unit principal direction and ``ev_j`` its variance, so the
training vectors have unit variance per component and an N(0, I) prior on x
is meaningful (the paper's x = y L differs only by this per-component scale).

``standardize``: ``"global"`` (default) divides every feature by one number,
the RMS standard deviation of all features, which keeps PCA's Euclidean
metric on the displacement weights; ``"feature"`` divides each feature by its
own standard deviation (the paper's literal "unit variance"; features that
barely vary are then amplified -- measured worse on the real drills).

Canonical choice ``"auto"`` (Alg. 1 line 1, "the one with the lower
reconstruction energy"): for every candidate c, CPD from T_c to all others,
build the latent space, reconstruct every instance from its q-dimensional
latent vector, and take the mean symmetric squared Chamfer distance (m^2)
between the reconstructed shape C + G W(x_i) and T_i; the candidate with the
lowest energy wins. Costs K (K - 1) CPD runs; pass ``registrations`` to reuse
them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, Mapping, Sequence

import numpy as np
from scipy.spatial import cKDTree

from catgrasp_drake.core.cpd import DEFAULT_BETA_M, DEFAULT_LAMBDA, nonrigid_cpd
from catgrasp_drake.core.deformation import deform_points
from catgrasp_drake.core.fileio import load_arrays, save_arrays
from catgrasp_drake.core.kernels import gaussian_kernel, kernel_width
from catgrasp_drake.core.validation import as_points, count, non_negative, positive, real_array, real_number
from catgrasp_drake.errors import InputError, ModelFileError

FILE_KIND = "catgrasp.shape_space"
FILE_VERSION = 1
#: Largest accepted |x_j| of a whitened latent vector (the training set has |x_j| ~ 1).
MAX_LATENT = 1e6
#: Below this RMS spread of the CPD weights (m) the instances are taken as identical.
_MIN_STD_M = 1e-7


# --------------------------------------------------------------------------- PCA-EM


@dataclass(frozen=True)
class PCAResult:
    """``components`` (q, p) orthonormal rows sorted by decreasing ``variances`` (q,)
    (variance of the data along each, divisor K - 1); ``mean`` (p,)."""

    components: np.ndarray
    variances: np.ndarray
    mean: np.ndarray
    iterations: int
    converged: bool


def pca_em(Y, q: int, *, center: bool = True, max_iter: int = 1000, tol: float = 1e-12, seed: int = 0) -> PCAResult:
    """Principal subspace of ``Y`` (K, p) by EM (Roweis 1998; paper eqs. 9-10).

    With L (p, q): E-step ``X = Y L (L^T L)^-1``, M-step ``L = Y^T X (X^T X)^-1``,
    from a seeded random start, until the relative change of the
    reconstruction error is below ``tol``. The converged subspace is then
    rotated to the principal axes (SVD of the q-dimensional projection) so
    that the result equals SVD-based PCA up to the signs of the components.
    """
    try:
        Y = np.asarray(Y, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"pca_em: expected a numeric (K, p) data matrix, got {type(Y).__name__}") from None
    if Y.ndim != 2 or Y.shape[0] < 2 or Y.shape[1] < 1:
        raise InputError(f"pca_em: expected a (K >= 2, p) data matrix, got shape {Y.shape}")
    if not np.all(np.isfinite(Y)):
        raise InputError("pca_em: data contain NaN or inf")
    if float(np.abs(Y).max()) > 1e150:
        raise InputError("pca_em: data values beyond 1e150 (their squares overflow); rescale the data")
    K, p = Y.shape
    q = count(q, "pca_em: q", 1, min(K, p))
    max_iter = count(max_iter, "pca_em: max_iter", 1)
    tol = non_negative(tol, "pca_em: tol")
    mean = Y.mean(axis=0) if center else np.zeros(p)
    Yc = Y - mean
    rng = np.random.default_rng(seed)
    L = rng.standard_normal((p, q))
    err_prev = math.inf
    converged = False
    it = 0
    total = float((Yc * Yc).sum())
    for it in range(1, int(max_iter) + 1):  # noqa: B007 (the count is returned)
        X = np.linalg.lstsq(L, Yc.T, rcond=None)[0].T  # = Y L (L^T L)^-1   (K, q)
        L = np.linalg.lstsq(X, Yc, rcond=None)[0].T  # = Y^T X (X^T X)^-1 (p, q)
        err = float(((Yc - X @ L.T) ** 2).sum())
        if abs(err_prev - err) <= tol * max(total, 1e-300):
            converged = True
            break
        err_prev = err
    Qb, _ = np.linalg.qr(L)
    Z = Yc @ Qb
    _, S, Vt = np.linalg.svd(Z, full_matrices=False)
    comps = (Qb @ Vt.T).T
    variances = S**2 / (K - 1)
    order = np.argsort(variances)[::-1]
    return PCAResult(comps[order], variances[order], mean, it, converged)


# --------------------------------------------------------------------------- shape space


@dataclass(frozen=True, eq=False)
class ShapeSpace:
    """A category's latent space of deformations of the canonical shape.

    ``W(x) = W_mean + reshape(feature_std * (x * sqrt(eigenvalues)) @ components)``;
    ``components`` (q, 3M) orthonormal; ``latent_train`` (K, q) the training
    instances' latent vectors; ``W_train`` (K, M, 3) their CPD weights.
    """

    canonical: np.ndarray
    beta: float
    lam: float
    w: float
    W_mean: np.ndarray
    feature_std: np.ndarray
    components: np.ndarray
    eigenvalues: np.ndarray
    latent_train: np.ndarray
    W_train: np.ndarray
    variance: float = 0.95
    total_variance: float = 0.0
    canonical_index: int = -1
    standardize: str = "global"
    meta: dict = field(default_factory=dict)

    # ----- sizes
    @property
    def q(self) -> int:
        return int(self.components.shape[0])

    @property
    def n_points(self) -> int:
        return int(self.canonical.shape[0])

    @property
    def explained_variance_ratio(self) -> np.ndarray:
        return self.eigenvalues / self.total_variance if self.total_variance > 0 else np.zeros(self.q)

    # ----- latent <-> W
    def _check_x(self, x) -> np.ndarray:
        x = real_array(x, "latent vector", f"({self.q},) vector")
        if x.shape[-1:] != (self.q,) or x.ndim > 2:
            raise InputError(f"latent vector: expected shape ({self.q},) or (n, {self.q}), got {x.shape}")
        if not np.all(np.isfinite(x)):
            raise InputError("latent vector contains NaN or inf")
        if x.size and float(np.abs(x).max()) > MAX_LATENT:
            raise InputError(f"latent vector: values reach {float(np.abs(x).max()):.3g}; whitened latent "
                             f"coordinates are O(1) (|x| <= {MAX_LATENT:g})")
        return x

    def decode(self, x) -> np.ndarray:
        """Latent x (q,) -> W (M, 3); a batch (n, q) -> (n, M, 3)."""
        x = self._check_x(x)
        y = (x * np.sqrt(self.eigenvalues)) @ self.components * self.feature_std
        return self.W_mean + y.reshape(x.shape[:-1] + (self.n_points, 3))

    def encode(self, W) -> np.ndarray:
        """W (M, 3) -> latent x (q,) (orthogonal projection onto the space); (n, M, 3) -> (n, q)."""
        W = real_array(W, "W", f"({self.n_points}, 3) array")
        if W.shape[-2:] != (self.n_points, 3) or W.ndim > 3:
            raise InputError(f"W: expected shape ({self.n_points}, 3) or (n, {self.n_points}, 3), got {W.shape}")
        if not np.all(np.isfinite(W)) or float(np.abs(W).max()) > 1e6:
            raise InputError("W: contains NaN, inf or values beyond 1e6 m")
        y = (W - self.W_mean).reshape(W.shape[:-2] + (-1,)) / self.feature_std
        return (y @ self.components.T) / np.sqrt(self.eigenvalues)

    @cached_property
    def kernel(self) -> np.ndarray:
        """G(C, C) (M, M), computed once."""
        return gaussian_kernel(self.canonical, self.canonical, self.beta)

    @cached_property
    def displacement_basis(self) -> tuple[np.ndarray, np.ndarray]:
        """``(V0 (M, 3), B (q, M, 3))`` with ``C + G W(x) = C + V0 + sum_j x_j B_j`` (linear in x)."""
        G = self.kernel
        V0 = G @ self.W_mean
        Bw = (np.sqrt(self.eigenvalues)[:, None] * self.components * self.feature_std).reshape(self.q, self.n_points, 3)
        B = np.einsum("ij,qjk->qik", G, Bw)
        return V0, B

    def deform(self, x, points=None) -> np.ndarray:
        """Canonical points deformed by W(x) (``points=None``), or any canonical-frame (K, 3) points."""
        W = self.decode(x)
        if W.ndim != 2:
            raise InputError("deform: pass one latent vector at a time")
        if points is None:
            V0, B = self.displacement_basis
            return self.canonical + V0 + np.tensordot(np.asarray(x, dtype=float), B, axes=1)
        return deform_points(self.canonical, W, self.beta, points)

    def check_latent(self, x) -> np.ndarray:
        """Return ``x`` as a float (q,) or (n, q) array or raise InputError."""
        return self._check_x(x)

    # ----- files
    def to_arrays(self) -> tuple[dict, dict]:
        """``(arrays, meta)``: the space as named numeric arrays plus a JSON-able dict
        (for embedding in another file; :meth:`save` writes exactly these)."""
        arrays = {
            "canonical": self.canonical,
            "W_mean": self.W_mean,
            "feature_std": self.feature_std,
            "components": self.components,
            "eigenvalues": self.eigenvalues,
            "latent_train": self.latent_train,
            "W_train": self.W_train,
        }
        meta = {
            "beta": float(self.beta),
            "lam": float(self.lam),
            "w": float(self.w),
            "variance": float(self.variance),
            "total_variance": float(self.total_variance),
            "canonical_index": int(self.canonical_index),
            "standardize": self.standardize,
            "q": self.q,
            "n_points": self.n_points,
            "extra": dict(self.meta),
        }
        return arrays, meta

    @classmethod
    def from_arrays(cls, arrays, meta, *, source: str = "shape space") -> "ShapeSpace":
        """Inverse of :meth:`to_arrays`; ModelFileError (naming ``source``) if anything is missing or inconsistent."""
        need = ["canonical", "W_mean", "feature_std", "components", "eigenvalues", "latent_train", "W_train"]
        missing = [k for k in need if k not in arrays]
        if missing:
            raise ModelFileError(f"{source}: shape space lacks arrays {missing}")
        bad = [k for k in need if not (np.issubdtype(np.asarray(arrays[k]).dtype, np.integer)
                                       or np.issubdtype(np.asarray(arrays[k]).dtype, np.floating))]
        if bad:
            raise ModelFileError(f"{source}: shape space arrays {bad} are not real numbers")
        arrays = {k: np.asarray(arrays[k], dtype=np.float64) for k in need}
        try:
            M, q = int(meta["n_points"]), int(meta["q"])
            ok = (
                arrays["canonical"].shape == (M, 3)
                and arrays["W_mean"].shape == (M, 3)
                and arrays["feature_std"].shape == (3 * M,)
                and arrays["components"].shape == (q, 3 * M)
                and arrays["eigenvalues"].shape == (q,)
                and arrays["latent_train"].ndim == 2
                and arrays["latent_train"].shape[1] == q
                and arrays["W_train"].shape[1:] == (M, 3)
                and arrays["W_train"].shape[0] == arrays["latent_train"].shape[0]
            )
            beta, lam, w = float(meta["beta"]), float(meta["lam"]), float(meta["w"])
        except (KeyError, TypeError, ValueError):
            raise ModelFileError(f"{source}: shape space header is incomplete") from None
        if not ok:
            raise ModelFileError(f"{source}: shape space arrays have inconsistent shapes (M={M}, q={q})")
        if not all(np.all(np.isfinite(a)) for a in arrays.values()) or np.any(arrays["eigenvalues"] <= 0):
            raise ModelFileError(f"{source}: shape space arrays contain NaN/inf or non-positive variances")
        try:
            kernel_width(beta)
            positive(lam, "lam")
            if not 0.0 <= w < 1.0:
                raise InputError(f"w = {w}")
        except InputError as e:
            raise ModelFileError(f"{source}: shape space header has a bad CPD parameter ({e})") from None
        try:
            return cls(
                canonical=arrays["canonical"],
                beta=beta,
                lam=lam,
                w=w,
                W_mean=arrays["W_mean"],
                feature_std=arrays["feature_std"],
                components=arrays["components"],
                eigenvalues=arrays["eigenvalues"],
                latent_train=arrays["latent_train"],
                W_train=arrays["W_train"],
                variance=float(meta.get("variance", 0.95)),
                total_variance=float(meta.get("total_variance", 0.0)),
                canonical_index=int(meta.get("canonical_index", -1)),
                standardize=str(meta.get("standardize", "global")),
                meta=dict(meta.get("extra", {})),
            )
        except (TypeError, ValueError, AttributeError, OverflowError):
            raise ModelFileError(f"{source}: shape space header has a bad field") from None

    def save(self, path) -> None:
        """Write the space to ``path`` (.npz + JSON header, kind ``catgrasp.shape_space`` v1, atomic, no pickle)."""
        arrays, meta = self.to_arrays()
        save_arrays(path, arrays, kind=FILE_KIND, version=FILE_VERSION, meta=meta)

    @classmethod
    def load(cls, path) -> "ShapeSpace":
        """Read a file written by :meth:`save`; ModelFileError if corrupt, of another kind/version or inconsistent."""
        arrays, meta = load_arrays(path, kind=FILE_KIND, version=FILE_VERSION)
        return cls.from_arrays(arrays, meta, source=str(path))


def _fit_space(canonical, Ws: np.ndarray, *, beta, lam, w, variance, standardize, canonical_index,
               max_q=None, meta=None) -> ShapeSpace:
    K, M, _ = Ws.shape
    Y = Ws.reshape(K, -1)
    mean = Y.mean(axis=0)
    Yc = Y - mean
    feat_var = Yc.var(axis=0, ddof=1)
    if standardize == "global":
        std = math.sqrt(float(feat_var.mean()))
        if std <= _MIN_STD_M:
            raise InputError("build_shape_space: all instances deform the canonical shape identically; "
                             "no shape variation")
        feature_std = np.full(Y.shape[1], std)
    elif standardize == "feature":
        fs = np.sqrt(feat_var)
        floor = 1e-6 * max(float(fs.max()), 1e-300)
        if fs.max() <= _MIN_STD_M:
            raise InputError("build_shape_space: all instances deform the canonical shape identically; "
                             "no shape variation")
        feature_std = np.maximum(fs, floor)
    else:
        raise InputError(f"standardize: expected 'global' or 'feature', got {standardize!r}")
    Yn = Yc / feature_std
    q_full = min(K - 1, Yn.shape[1])
    pca = pca_em(Yn, q_full, center=False)
    ev = pca.variances
    total = float((Yn * Yn).sum()) / (K - 1)
    keep = ev > 1e-12 * max(float(ev[0]), 1e-300)
    ev, comps = ev[keep], pca.components[keep]
    csum = np.cumsum(ev) / total
    q = int(min(len(ev), np.searchsorted(csum, variance - 1e-12) + 1))
    if max_q is not None:
        q = max(1, min(q, int(max_q)))
    ev, comps = ev[:q], comps[:q]
    latent = (Yn @ comps.T) / np.sqrt(ev)
    return ShapeSpace(
        canonical=np.array(canonical, dtype=np.float64),
        beta=float(beta),
        lam=float(lam),
        w=float(w),
        W_mean=mean.reshape(M, 3),
        feature_std=feature_std,
        components=comps,
        eigenvalues=ev,
        latent_train=latent,
        W_train=Ws.copy(),
        variance=float(variance),
        total_variance=total,
        canonical_index=int(canonical_index),
        standardize=standardize,
        meta=dict(meta or {}),
    )


def _sym_chamfer_sq(A: np.ndarray, B: np.ndarray) -> float:
    da, _ = cKDTree(B).query(A)
    db, _ = cKDTree(A).query(B)
    return 0.5 * (float((da**2).mean()) + float((db**2).mean()))


def reconstruction_energy(space: ShapeSpace, instances: Sequence[np.ndarray]) -> float:
    """Mean symmetric squared Chamfer distance (m^2) between each training instance and its
    reconstruction ``C + G W(x_i)`` from its latent vector (the ``"auto"`` canonical criterion)."""
    errs = [_sym_chamfer_sq(space.deform(x), np.asarray(T, dtype=float)) for x, T in zip(space.latent_train, instances)]
    return float(np.mean(errs))


def build_shape_space(
    instances: Sequence,
    *,
    canonical_index: int | str | None = None,
    beta: float = DEFAULT_BETA_M,
    lam: float = DEFAULT_LAMBDA,
    w: float = 0.0,
    variance: float = 0.95,
    max_q: int | None = None,
    standardize: str = "global",
    max_iter: int = 150,
    tol: float = 1e-5,
    low_rank=None,
    registrations: Mapping[tuple[int, int], np.ndarray] | None = None,
    progress: Callable[[int, int], object] | None = None,
) -> ShapeSpace:
    """Build a category shape space from ``instances`` (list of (N_i, 3) clouds, canonical frame, metres).

    ``canonical_index``: an index into ``instances``, or ``None``/``"auto"``
    for the instance with the lowest reconstruction energy (module doc).
    ``variance``: fraction of variance kept (q is the smallest number of
    components reaching it); ``max_q`` caps q. CPD parameters as in
    :func:`catgrasp_drake.core.cpd.nonrigid_cpd`. ``registrations`` maps
    ``(canonical, instance)`` index pairs to precomputed CPD ``W`` (M, 3);
    missing pairs are computed. ``progress(done, total)`` is called after each CPD.
    """
    if isinstance(instances, np.ndarray) and instances.ndim == 2:
        raise InputError("instances: expected a list of (N_i, 3) clouds, got a single array")
    clouds = [as_points(T, f"instances[{i}]", min_points=3, check_units=True) for i, T in enumerate(instances)]
    K = len(clouds)
    if K < 2:
        raise InputError(f"instances: a shape space needs at least 2 instances, got {K}")
    variance = real_number(variance, "variance")
    if not (0.0 < variance <= 1.0):
        raise InputError(f"variance: must be in (0, 1], got {variance}")
    beta = kernel_width(beta)
    lam = positive(lam, "lam")
    if max_q is not None:
        max_q = count(max_q, "max_q", 1)
    if standardize not in ("global", "feature"):
        raise InputError(f"standardize: expected 'global' or 'feature', got {standardize!r}")
    cache: dict[tuple[int, int], np.ndarray] = dict(registrations or {})

    if canonical_index is None or canonical_index == "auto":
        candidates = list(range(K))
    else:
        try:
            c = count(canonical_index, "canonical_index", minimum=-(2**62))
        except InputError:
            raise InputError(f"canonical_index: expected an int, 'auto' or None, got {canonical_index!r}") from None
        if not (0 <= c < K):
            raise InputError(f"canonical_index: {c} is out of range for {K} instances")
        candidates = [c]
    total = sum(1 for c in candidates for i in range(K) if i != c and (c, i) not in cache)
    done = 0

    def W_for(c: int, i: int) -> np.ndarray:
        nonlocal done
        if i == c:
            return np.zeros_like(clouds[c])
        if (c, i) not in cache:
            r = nonrigid_cpd(clouds[c], clouds[i], beta=beta, lam=lam, w=w, max_iter=max_iter, tol=tol,
                             low_rank=low_rank)
            cache[(c, i)] = r.W
            done += 1
            if progress is not None:
                progress(done, total)
        W = np.asarray(cache[(c, i)], dtype=np.float64)
        if W.shape != clouds[c].shape:
            raise InputError(f"registrations[{(c, i)}]: expected shape {clouds[c].shape}, got {W.shape}")
        return W

    best, best_e, energies = None, math.inf, {}
    for c in candidates:
        Ws = np.stack([W_for(c, i) for i in range(K)])
        space = _fit_space(clouds[c], Ws, beta=beta, lam=lam, w=w, variance=variance, standardize=standardize,
                           canonical_index=c, max_q=max_q)
        if len(candidates) == 1:
            return space
        e = reconstruction_energy(space, clouds)
        energies[c] = e
        if e < best_e:
            best, best_e = space, e
    return _with_meta(best, {"canonical_energies": {str(k): float(v) for k, v in energies.items()}})


def _with_meta(space: ShapeSpace, extra: dict) -> ShapeSpace:
    fields = {k: getattr(space, k) for k in ShapeSpace.__dataclass_fields__}
    fields["meta"] = {**space.meta, **extra}
    return ShapeSpace(**fields)
