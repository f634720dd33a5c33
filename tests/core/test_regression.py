"""Ridge regressor latent x -> canonical grasp descriptor."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.regression import fit_ridge
from catgrasp_drake.errors import InputError


def test_recovers_a_known_linear_map():
    rng = np.random.default_rng(0)
    A, b = rng.normal(size=(7, 3)), rng.normal(size=7)
    X = rng.normal(size=(40, 3))
    reg = fit_ridge(X, X @ A.T + b, alpha=0.0)
    assert np.allclose(reg.coef, A) and np.allclose(reg.intercept, b)
    assert np.allclose(reg.predict(X[0]), A @ X[0] + b)


def test_instances_count_equally_and_successes_are_averaged():
    # three instances with 1, 4 and 2 successes; a saturated model (q = 2) passes through each group mean
    x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    groups = [0, 1, 1, 1, 1, 2, 2]
    X = x[groups]
    rng = np.random.default_rng(1)
    Y = rng.normal(size=(7, 4))
    reg = fit_ridge(X, Y, alpha=0.0, groups=groups)
    for g in range(3):
        assert np.allclose(reg.predict(x[g]), Y[np.array(groups) == g].mean(axis=0))


def test_ridge_shrinks_toward_the_mean():
    rng = np.random.default_rng(2)
    X = rng.normal(size=(10, 2))
    Y = X @ np.array([[3.0, -1.0]]).T
    weak, strong = fit_ridge(X, Y, alpha=0.0), fit_ridge(X, Y, alpha=100.0)
    assert np.linalg.norm(strong.coef) < 0.1 * np.linalg.norm(weak.coef)


def test_bad_input():
    with pytest.raises(InputError, match="no training samples"):
        fit_ridge(np.zeros((0, 2)), np.zeros((0, 3)))
    with pytest.raises(InputError, match="same n"):
        fit_ridge(np.zeros((3, 2)), np.zeros((4, 3)))
    with pytest.raises(InputError, match="NaN"):
        fit_ridge(np.array([[np.nan, 0.0]]), np.zeros((1, 3)))
    reg = fit_ridge(np.eye(3), np.eye(3))
    with pytest.raises(InputError, match="expects 3"):
        reg.predict(np.zeros(2))
