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


def fit_ridge(X, Y, *, alpha: float = 1e-2, groups=None) -> LinearRegressor:
    """Fit ``Y (n, D) ~ X (n, q)``; ``groups`` (n,) labels rows of the same instance.

    With ``groups``, rows are weighted 1/size-of-their-group (see module doc).
    ``alpha`` >= 0 is the ridge penalty in units of the (unit-variance) latent space.
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
        w = np.ones(X.shape[0])
    else:
        g = np.asarray(groups)
        if g.shape != (X.shape[0],):
            raise InputError(f"regression: groups must label each of the {X.shape[0]} rows, got shape {g.shape}")
        if g.dtype.kind == "f" and not np.all(np.isfinite(g)):
            raise InputError("regression: groups contain NaN or inf")
        _, inverse, counts = np.unique(g, return_inverse=True, return_counts=True)
        w = 1.0 / counts[inverse.reshape(-1)]
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
