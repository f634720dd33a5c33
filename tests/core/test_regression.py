"""Ridge regressor latent x -> canonical grasp descriptor."""

from __future__ import annotations

import json

import numpy as np
import pytest

from catgrasp_drake.core.regression import (
    REGRESSOR_GRID,
    fit_ridge,
    instance_means,
    regressor_from_arrays,
    regressor_to_arrays,
)
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


# ----------------------------------------------------------------------------- shape-dependent regressors
def _grasps_determined_by_shape(seed=0, n_instances=14, rows=3, noise=0.02, linear=False):
    """Seeded instances: latent x (q = 3) determines the grasp descriptor (D = 4), plus a little noise."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n_instances, 3))
    if linear:
        y = x @ rng.normal(size=(3, 4))
    else:
        y = np.column_stack([np.sin(2 * x[:, 0]), np.cos(1.5 * x[:, 1]), x[:, 0] * x[:, 2], np.tanh(x[:, 1])])
    X = np.repeat(x, rows, axis=0)
    Y = np.repeat(y, rows, axis=0) + noise * rng.normal(size=(n_instances * rows, 4))
    return X, Y, np.repeat(np.arange(n_instances), rows)


def _err(pred, rows):
    return float(np.mean(np.linalg.norm(rows - pred, axis=1)))


def test_kernel_ridge_recovers_a_nonlinear_shape_to_grasp_map_that_ridge_and_the_mean_miss():
    from catgrasp_drake.core.regression import REGRESSOR_GRID as G
    from catgrasp_drake.core.regression import leave_one_instance_out, nested_loo_error, select_regressor

    X, Y, g = _grasps_determined_by_shape(n_instances=30)
    errors = {name: min(leave_one_instance_out(X, Y, g, lambda a, b, c, h=h, f=G[name][0]: f(a, b, c, **h), _err)
                        for h in G[name][1]) for name in G}
    assert errors["kernel_ridge"] < 0.6 * errors["ridge"] and errors["kernel_ridge"] < 0.6 * errors["mean"]
    assert errors["kernel_ridge"] < errors["nearest"]
    name, h, e = select_regressor(X, Y, g, _err)
    assert name == "kernel_ridge" and e == pytest.approx(errors["kernel_ridge"])
    honest = nested_loo_error(X, Y, g, _err, tuple(G))
    assert e <= honest < errors["mean"]  # the nested figure is no better than the selection's own


def test_on_a_linear_map_ridge_is_as_good_as_any_and_the_mean_is_worse():
    from catgrasp_drake.core.regression import select_regressor

    X, Y, g = _grasps_determined_by_shape(seed=3, linear=True)
    name, _, e = select_regressor(X, Y, g, _err)
    _, _, e_mean = select_regressor(X, Y, g, _err, names=("mean",))
    assert name in ("ridge", "kernel_ridge") and e < 0.3 * e_mean


def test_kernel_ridge_fits_instance_means_and_rejects_bad_input():
    from catgrasp_drake.core.regression import fit_kernel_ridge, fit_nearest, instance_means

    X, Y, g = _grasps_determined_by_shape(n_instances=6, noise=0.0)
    labels, x, y = instance_means(X, Y, g)
    model = fit_kernel_ridge(X, Y, length_scale=1.0, alpha=1e-10, groups=g)
    np.testing.assert_allclose(model.predict(x), y, atol=1e-6)  # interpolates with alpha -> 0
    np.testing.assert_allclose(fit_nearest(X, Y, groups=g).predict(x[2] + 1e-3), y[2])
    with pytest.raises(InputError, match="length_scale"):
        fit_kernel_ridge(X, Y, length_scale=0.0, alpha=1.0, groups=g)
    with pytest.raises(InputError, match="different latent"):
        instance_means(X + np.arange(len(X))[:, None], Y, g)
    with pytest.raises(InputError, match="latent vector"):
        model.predict([1.0, 2.0])


def test_robustness_weights_act_within_an_instance_and_every_instance_still_counts_once():
    # instance 1 has two grasps weighted 3:1; a saturated model passes through each weighted mean
    x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    groups = np.array([0, 1, 1, 2])
    Y = np.array([[1.0, 0.0], [4.0, 8.0], [0.0, 0.0], [2.0, 2.0]])
    w = np.array([0.5, 0.9, 0.3, 1.0])
    reg = fit_ridge(x[groups], Y, alpha=0.0, groups=groups, weights=w)
    np.testing.assert_allclose(reg.predict(x[1]), [3.0, 6.0], atol=1e-12)
    np.testing.assert_allclose(reg.predict(x[0]), Y[0], atol=1e-12)
    _, xm, ym = instance_means(x[groups], Y, groups, w)
    np.testing.assert_allclose(ym, [[1.0, 0.0], [3.0, 6.0], [2.0, 2.0]])
    with pytest.raises(InputError, match="weights"):
        fit_ridge(x[groups], Y, groups=groups, weights=[1.0, -1.0, 1.0, 1.0])
    with pytest.raises(InputError, match="positive total weight"):
        fit_ridge(x[groups], Y, groups=groups, weights=[0.0, 1.0, 1.0, 1.0])


@pytest.mark.parametrize("name", ["ridge", "kernel_ridge", "nearest"])
def test_every_regressor_kind_round_trips_through_arrays(name):
    rng = np.random.default_rng(3)
    X, Y = rng.normal(size=(6, 2)), rng.normal(size=(6, 5))
    fit, grid = REGRESSOR_GRID[name]
    reg = fit(X, Y, np.arange(6), **grid[-1])
    arrays, meta = regressor_to_arrays(reg)
    json.dumps(meta)
    again = regressor_from_arrays(arrays, meta)
    assert again.kind == reg.kind and again.shape == (2, 5)
    x = rng.normal(size=(3, 2))
    np.testing.assert_array_equal(again.predict(x), reg.predict(x))
    with pytest.raises(InputError, match="unknown kind"):
        regressor_from_arrays(arrays, meta | {"kind": "forest"})
    first = next(iter(arrays))
    with pytest.raises(InputError, match="missing"):
        regressor_from_arrays({k: v for k, v in arrays.items() if k != first}, meta)
    with pytest.raises(InputError, match="inconsistent"):
        regressor_from_arrays(arrays | {first: arrays[first][:, :1].T}, meta)


def test_the_one_standard_error_rule_keeps_the_mean_on_noise_and_the_shape_map_where_there_is_one():
    """Grasps independent of shape (13 instances, like the committed models): the least-error rule may pick a
    flexible family by luck, the one-SE rule keeps the mean, and its nested error is no worse than the least-error
    rule's. Grasps determined by shape: both rules find kernel ridge."""
    from catgrasp_drake.core.regression import nested_loo_error, select_regressor

    rng = np.random.default_rng(5)
    X = np.repeat(rng.normal(size=(13, 9)), 3, axis=0)
    Y = rng.normal(size=(39, 4))
    g = np.repeat(np.arange(13), 3)
    name, h, e = select_regressor(X, Y, g, _err, rule="one_se")
    assert (name, h) == ("mean", {})
    _, _, e_min = select_regressor(X, Y, g, _err)
    assert e_min <= e  # the least error is the least; the rule trades a little of it for simplicity
    assert nested_loo_error(X, Y, g, _err, ("mean", "nearest", "ridge", "kernel_ridge"), rule="one_se") <= \
        nested_loo_error(X, Y, g, _err, ("mean", "nearest", "ridge", "kernel_ridge")) + 1e-12
    X, Y, g = _grasps_determined_by_shape(n_instances=30)
    assert select_regressor(X, Y, g, _err, rule="one_se")[0] == "kernel_ridge"
    with pytest.raises(InputError, match="rule"):
        select_regressor(X, Y, g, _err, rule="best")
