"""Linear regressor from latent shape x to a canonical grasp descriptor (paper, Alg. 1 line 6).

Ridge regression with an unpenalised intercept, solved in closed form:

    minimise  sum_i w_i ||y_i - (b + A x_i)||^2 + alpha ||A||_F^2

Several successful grasps of one training instance are all used as rows with
the same x; their weights ``w_i = 1 / n_instance`` make every instance count
equally however many successes it had, so the fit at an instance's x is the
mean of its successful descriptors (pulled toward the category mean by alpha).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catgrasp_drake.core.kernels import gaussian_kernel, sqdist
from catgrasp_drake.core.validation import non_negative, real_array
from catgrasp_drake.errors import InputError

#: Largest accepted |value| in training data and latent vectors (squares must not overflow).
_MAX_VALUE = 1e100


@dataclass(frozen=True)
class LinearRegressor:
    """y = intercept + coef @ x; ``coef`` is (D, q), ``intercept`` (D,)."""

    coef: np.ndarray
    intercept: np.ndarray
    alpha: float
    kind = "ridge"

    @property
    def shape(self) -> tuple[int, int]:
        """(q, D): latent size in, descriptor size out."""
        return self.coef.shape[1], self.coef.shape[0]

    def predict(self, x) -> np.ndarray:
        """Predict descriptors for one latent vector (q,) or a batch (n, q)."""
        x = real_array(x, "latent vector", f"({self.coef.shape[1]},) or (n, {self.coef.shape[1]}) array")
        if x.ndim not in (1, 2):
            raise InputError(f"latent vector: expected shape ({self.coef.shape[1]},) or (n, {self.coef.shape[1]}), "
                             f"got {x.shape}")
        if x.shape[-1] != self.coef.shape[1]:
            raise InputError(f"latent vector has {x.shape[-1]} values, the regressor expects {self.coef.shape[1]}")
        if not np.all(np.isfinite(x)) or (x.size and float(np.abs(x).max()) > _MAX_VALUE):
            raise InputError(f"latent vector: contains NaN, inf or values beyond {_MAX_VALUE:g}")
        return self.intercept + x @ self.coef.T


def fit_ridge(X, Y, *, alpha: float = 1e-2, groups=None, weights=None) -> LinearRegressor:
    """Fit ``Y (n, D) ~ X (n, q)``; ``groups`` (n,) labels rows of the same instance.

    With ``groups``, rows are weighted 1/size-of-their-group (see module doc), or, with ``weights``
    (n,) >= 0 as well (e.g. robustness scores), by their share of their group's total weight: every
    instance still counts as one. ``alpha`` >= 0 is the ridge penalty in units of the (unit-variance)
    latent space.
    """
    X = real_array(X, "regression: X", "(n, q) array")
    Y = real_array(Y, "regression: Y", "(n, D) array")
    if X.ndim != 2 or Y.ndim != 2 or X.shape[0] != Y.shape[0]:
        raise InputError(f"regression: X {X.shape} and Y {Y.shape} must be (n, q) and (n, D) with the same n")
    if X.shape[0] == 0:
        raise InputError("regression: no training samples (no successful grasps?)")
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
        raise InputError("regression: training data contain NaN or inf")
    if max(float(np.abs(X).max(initial=0.0)), float(np.abs(Y).max(initial=0.0))) > _MAX_VALUE:
        raise InputError(f"regression: training data have values beyond {_MAX_VALUE:g}; rescale them")
    alpha = non_negative(alpha, "regression: alpha")
    if groups is None:
        w = np.ones(X.shape[0]) if weights is None else _group_shares(np.zeros(X.shape[0]), weights)
    else:
        g = np.asarray(groups)
        if g.shape != (X.shape[0],):
            raise InputError(f"regression: groups must label each of the {X.shape[0]} rows, got shape {g.shape}")
        if g.dtype.kind == "f" and not np.all(np.isfinite(g)):
            raise InputError("regression: groups contain NaN or inf")
        w = _group_shares(g, weights)
    w = w / w.sum()
    x_mean = w @ X
    y_mean = w @ Y
    Xc, Yc = X - x_mean, Y - y_mean
    sw = np.sqrt(w)[:, None]
    # solve (Xc^T W Xc + alpha I) A^T = Xc^T W Yc via least squares on an augmented system
    q = X.shape[1]
    lhs = np.vstack([sw * Xc, np.sqrt(alpha) * np.eye(q)]) if q else np.zeros((0, 0))
    rhs = np.vstack([sw * Yc, np.zeros((q, Y.shape[1]))])
    if q:
        coef_T, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
        coef = coef_T.T
    else:
        coef = np.zeros((Y.shape[1], 0))
    intercept = y_mean - coef @ x_mean
    return LinearRegressor(coef=coef, intercept=intercept, alpha=float(alpha))


def _group_shares(g: np.ndarray, weights=None) -> np.ndarray:
    """Each row's share of its group (the shares of a group sum to 1): equal, or by ``weights`` (n,) >= 0."""
    _, inverse, counts = np.unique(g, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    if weights is None:
        return 1.0 / counts[inverse]
    w = real_array(weights, "regression: weights", "(n,) array")
    if w.shape != g.shape or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise InputError(f"regression: weights must be {g.shape[0]} finite values >= 0, got shape {w.shape}")
    totals = np.bincount(inverse, weights=w)
    if np.any(totals <= 0):
        raise InputError("regression: every group needs a positive total weight")
    return w / totals[inverse]


# ----------------------------------------------------------------------------- shape-dependent regressors
def instance_means(X, Y, groups, weights=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(labels, x (m, q), y (m, D))``: one row per instance, its latent vector and mean descriptor
    (weighted by ``weights`` (n,) >= 0 within the instance, if given).

    With every instance weighted equally (module docstring), fitting the rows is fitting these means.
    Rows of one instance must share their latent vector."""
    X = real_array(X, "regression: X", "(n, q) array")
    Y = real_array(Y, "regression: Y", "(n, D) array")
    g = np.asarray(groups)
    if X.ndim != 2 or Y.ndim != 2 or X.shape[0] != Y.shape[0] or g.shape != (X.shape[0],) or not len(g):
        raise InputError(f"regression: X {X.shape}, Y {Y.shape} and groups {g.shape} must label the same n >= 1 rows")
    labels, inverse = np.unique(g, return_inverse=True)
    inverse = inverse.reshape(-1)
    x = np.stack([X[inverse == k][0] for k in range(len(labels))])
    if any(np.abs(X[inverse == k] - x[k]).max() > 1e-9 for k in range(len(labels))):
        raise InputError("regression: rows of one instance have different latent vectors")
    if weights is None:
        y = np.stack([Y[inverse == k].mean(axis=0) for k in range(len(labels))])
    else:
        share = _group_shares(g, weights)
        y = np.stack([share[inverse == k] @ Y[inverse == k] for k in range(len(labels))])
    return labels, x, y


@dataclass(frozen=True)
class KernelRidgeRegressor:
    """y(x) = intercept + sum_i dual_i exp(-|x - x_i|^2 / (2 length_scale^2)) over the training instances."""

    x_train: np.ndarray  # (m, q)
    dual: np.ndarray  # (m, D)
    intercept: np.ndarray  # (D,)
    length_scale: float
    alpha: float
    kind = "kernel_ridge"

    @property
    def shape(self) -> tuple[int, int]:
        return self.x_train.shape[1], self.dual.shape[1]

    def predict(self, x) -> np.ndarray:
        x = real_array(x, "latent vector", f"({self.x_train.shape[1]},) or (n, {self.x_train.shape[1]}) array")
        single = x.ndim == 1
        x = np.atleast_2d(x)
        if x.ndim != 2 or x.shape[1] != self.x_train.shape[1] or not np.all(np.isfinite(x)):
            raise InputError(f"latent vector: expected finite ({self.x_train.shape[1]},) values, got {x.shape}")
        y = self.intercept + gaussian_kernel(x, self.x_train, self.length_scale) @ self.dual
        return y[0] if single else y


def fit_kernel_ridge(X, Y, *, length_scale: float, alpha: float, groups=None) -> KernelRidgeRegressor:
    """Kernel ridge (Gaussian kernel of width ``length_scale`` in latent units) on the instances' mean
    descriptors (``groups``; default every row its own instance), around their mean:
    dual = (K + alpha I)^-1 (y - mean y)."""
    if not (np.isfinite(length_scale) and length_scale > 0):
        raise InputError(f"regression: length_scale must be positive, got {length_scale}")
    alpha = non_negative(alpha, "regression: alpha")
    groups = np.arange(len(np.asarray(X))) if groups is None else groups
    _, x, y = instance_means(X, Y, groups)
    b = y.mean(axis=0)
    K = gaussian_kernel(x, x, float(length_scale))
    dual = np.linalg.solve(K + max(alpha, 1e-12) * np.eye(len(x)), y - b)
    return KernelRidgeRegressor(x, dual, b, float(length_scale), float(alpha))


@dataclass(frozen=True)
class NearestInstanceRegressor:
    """y(x) = the mean descriptor of the training instance nearest to x in the latent space."""

    x_train: np.ndarray
    y_train: np.ndarray
    kind = "nearest"

    @property
    def shape(self) -> tuple[int, int]:
        return self.x_train.shape[1], self.y_train.shape[1]

    def predict(self, x) -> np.ndarray:
        x = real_array(x, "latent vector", "(q,) or (n, q) array")
        single = x.ndim == 1
        x = np.atleast_2d(x)
        if x.shape[1] != self.x_train.shape[1] or not np.all(np.isfinite(x)):
            raise InputError(f"latent vector: expected finite ({self.x_train.shape[1]},) values, got {x.shape}")
        y = self.y_train[np.argmin(sqdist(x, self.x_train), axis=1)]
        return y[0] if single else y


def fit_nearest(X, Y, *, groups=None) -> NearestInstanceRegressor:
    groups = np.arange(len(np.asarray(X))) if groups is None else groups
    _, x, y = instance_means(X, Y, groups)
    return NearestInstanceRegressor(x, y)


#: Any fitted regressor: ``predict(x (q,) or (n, q))``, ``shape`` (q, D) and ``kind``.
Regressor = LinearRegressor | KernelRidgeRegressor | NearestInstanceRegressor
_ARRAYS = {"ridge": ("coef", "intercept"), "kernel_ridge": ("x_train", "dual", "intercept"),
           "nearest": ("x_train", "y_train")}
_SCALARS = {"ridge": ("alpha",), "kernel_ridge": ("length_scale", "alpha"), "nearest": ()}
_CLASSES = {"ridge": LinearRegressor, "kernel_ridge": KernelRidgeRegressor, "nearest": NearestInstanceRegressor}


def regressor_to_arrays(regressor: Regressor) -> tuple[dict, dict]:
    """``(arrays, meta)``: the regressor's arrays by name and a JSON-able header (its kind and scalars)."""
    kind = regressor.kind
    arrays = {name: np.asarray(getattr(regressor, name), np.float64) for name in _ARRAYS[kind]}
    return arrays, {"kind": kind} | {name: float(getattr(regressor, name)) for name in _SCALARS[kind]}


def regressor_from_arrays(arrays: dict, meta: dict) -> Regressor:
    """The inverse of :func:`regressor_to_arrays`; InputError naming what is missing or inconsistent."""
    kind = meta.get("kind")
    if kind not in _CLASSES:
        raise InputError(f"regressor: unknown kind {kind!r}; known: {', '.join(_CLASSES)}")
    try:
        a = {name: np.asarray(arrays[name], np.float64) for name in _ARRAYS[kind]}
        scalars = {name: float(meta[name]) for name in _SCALARS[kind]}
    except (KeyError, TypeError, ValueError) as e:
        raise InputError(f"regressor ({kind}): missing or malformed entry {e}") from None
    if not all(np.all(np.isfinite(v)) for v in (*a.values(), *scalars.values())):
        raise InputError(f"regressor ({kind}): arrays or parameters are not finite")
    first = next(iter(a.values()))
    rows_ok = {"ridge": lambda: first.ndim == 2 and a["intercept"].shape == first.shape[:1],
               "kernel_ridge": lambda: (first.ndim == 2 and a["dual"].ndim == 2 and len(a["dual"]) == len(first)
                                        and a["intercept"].shape == a["dual"].shape[1:]),
               "nearest": lambda: first.ndim == 2 and a["y_train"].ndim == 2 and len(a["y_train"]) == len(first)}
    if not rows_ok[kind]():
        raise InputError(f"regressor ({kind}): array shapes are inconsistent")
    return _CLASSES[kind](**a, **scalars)


#: The regressors a category model may use: name -> (fit function, hyperparameter grid).
REGRESSOR_GRID: dict = {
    "mean": (lambda X, Y, g: fit_ridge(X, Y, alpha=1e12, groups=g), [{}]),
    "nearest": (lambda X, Y, g: fit_nearest(X, Y, groups=g), [{}]),
    "ridge": (lambda X, Y, g, alpha: fit_ridge(X, Y, alpha=alpha, groups=g),
              [{"alpha": a} for a in (0.1, 1.0, 10.0, 100.0)]),
    "kernel_ridge": (lambda X, Y, g, length_scale, alpha: fit_kernel_ridge(X, Y, length_scale=length_scale,
                                                                          alpha=alpha, groups=g),
                     [{"length_scale": ell, "alpha": a} for ell in (0.5, 1.0, 2.0, 4.0) for a in (0.01, 0.1, 1.0)]),
}


def leave_one_instance_out(X, Y, groups, fit, error, *, per_instance: bool = False):
    """Mean over instances of ``error(prediction at the instance's x, that instance's rows)`` with
    ``fit(X, Y, groups)`` trained on the other instances (``per_instance``: the (n,) errors instead)."""
    g = np.asarray(groups)
    errs = []
    for label in np.unique(g):
        keep = g != label
        model = fit(X[keep], Y[keep], g[keep])
        errs.append(float(error(model.predict(X[g == label][0]), Y[g == label])))
    return np.array(errs) if per_instance else float(np.mean(errs))


#: Selection rules of :func:`select_regressor`.
SELECTION_RULES = ("min", "one_se")


#: Families from the simplest to the most flexible (the one-SE rule's order); within a family the
#: strongest penalty and the widest kernel come first.
SIMPLICITY = ("mean", "ridge", "kernel_ridge", "nearest")


def _simplicity(candidate) -> tuple:
    name, h = candidate[0], candidate[1]
    rank = SIMPLICITY.index(name) if name in SIMPLICITY else len(SIMPLICITY)
    return rank, -h.get("alpha", 0.0), -h.get("length_scale", 0.0)


def score_regressors(X, Y, groups, error, names=tuple(REGRESSOR_GRID)) -> list[tuple[str, dict, np.ndarray]]:
    """Every candidate (``names`` x their grids, in that order) with its per-instance leave-one-instance-out
    ``error`` on ``(X, Y, groups)``: ``[(name, hyperparameters, errors (n,)), ...]``."""
    out = []
    for name in names:
        fit, grid = REGRESSOR_GRID[name]
        for h in grid:
            errs = leave_one_instance_out(X, Y, groups, lambda a, b, c, h=h, fit=fit: fit(a, b, c, **h), error,
                                          per_instance=True)
            out.append((name, h, errs))
    return out


def choose_regressor(scored, rule: str = "min") -> tuple[str, dict, float]:
    """``(name, hyperparameters, mean LOO error)`` chosen from :func:`score_regressors`' list by ``rule``.

    "min": the least mean error (ties: the first listed). "one_se": the simplest candidate (:data:`SIMPLICITY`)
    whose error is within one standard error of the least (the standard error of the best candidate's
    per-instance errors) -- a choice among many candidates on few instances otherwise favours a flexible one by
    luck.
    """
    if rule not in SELECTION_RULES:
        raise InputError(f"rule: expected one of {SELECTION_RULES}, got {rule!r}")
    best = None
    for c in scored:
        if best is None or float(np.mean(c[2])) < float(np.mean(best[2])) - 1e-15:
            best = c
    if rule == "one_se":
        errs = best[2]
        bound = float(np.mean(errs)) + (float(np.std(errs, ddof=1) / np.sqrt(len(errs))) if len(errs) > 1 else 0.0)
        best = next(c for c in sorted(scored, key=_simplicity) if float(np.mean(c[2])) <= bound)  # best qualifies
    return best[0], best[1], float(np.mean(best[2]))


def simplest_within_one_se(scores: dict, order) -> str:
    """The first name of ``order`` whose mean score (higher is better) is within one standard error of the
    best mean (the standard error of the best candidate's per-instance ``scores[name]`` (n,)); ties of the
    best: the earlier in ``order``. The one-SE rule of :func:`choose_regressor` for scores to maximise."""
    order = list(order)
    if not order or any(n not in scores for n in order):
        raise InputError(f"scores: expected an entry for each of {order}, got {sorted(scores)}")
    s = {n: real_array(scores[n], f"scores[{n!r}]", "(n,) array").reshape(-1) for n in order}
    if any(not len(v) or not np.all(np.isfinite(v)) for v in s.values()):
        raise InputError("scores: every candidate needs finite per-instance scores")
    best = max(order, key=lambda n: float(np.mean(s[n])))  # max keeps the first of equal means
    b = s[best]
    bound = float(np.mean(b)) - (float(np.std(b, ddof=1)) / np.sqrt(len(b)) if len(b) > 1 else 0.0)
    return next(n for n in order if float(np.mean(s[n])) >= bound - 1e-12)


def select_regressor(X, Y, groups, error, names=tuple(REGRESSOR_GRID), rule: str = "min") -> tuple[str, dict, float]:
    """``(name, hyperparameters, LOO error)`` of the candidate (``names`` x their grids) chosen by ``rule``
    (:func:`choose_regressor`) on ``(X, Y, groups)``."""
    if rule not in SELECTION_RULES:
        raise InputError(f"rule: expected one of {SELECTION_RULES}, got {rule!r}")
    return choose_regressor(score_regressors(X, Y, groups, error, names), rule)


def nested_loo_error(X, Y, groups, error, names, rule: str = "min") -> float:
    """The honest error of :func:`select_regressor` (with ``rule``): every instance predicted by the candidate
    chosen by leave-one-instance-out on the OTHER instances (so the choice never saw it)."""
    g = np.asarray(groups)
    errs = []
    for label in np.unique(g):
        keep = g != label
        name, h, _ = select_regressor(X[keep], Y[keep], g[keep], error, names, rule)
        model = REGRESSOR_GRID[name][0](X[keep], Y[keep], g[keep], **h)
        errs.append(float(error(model.predict(X[g == label][0]), Y[g == label])))
    return float(np.mean(errs))
