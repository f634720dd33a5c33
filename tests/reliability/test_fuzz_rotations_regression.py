"""Fuzzing rotations (core/rotations.py), the ridge regressor (core/regression.py) and
hidden-point removal (core/visibility.py)."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from catgrasp_drake.core.regression import LinearRegressor, fit_ridge
from catgrasp_drake.core.rotations import (
    matrix_to_quat,
    orthonormalize,
    quat_to_matrix,
    sample_rotations_within,
    shoemake_quaternions,
)
from catgrasp_drake.core.visibility import hidden_point_removal

from .harness import attempt, finite_array, proper_rotations
from .strategies import BAD_NUMBERS, clouds, scaled, seeds


@st.composite
def _matrices(draw, last=(3, 3)):
    """``(label, array)`` of (..., 3, 3) matrices or (..., 4) quaternions, valid and bad."""
    rng = np.random.default_rng(draw(seeds))
    lead = draw(st.sampled_from([(), (1,), (5,), (2, 3), (0,)]))
    a = rng.normal(size=lead + last)
    kind = draw(st.sampled_from(["valid", "valid", "nan", "inf", "zeros", "huge", "tiny", "rank_one", "wrong_shape",
                                 "string", "complex", "int", "list"]))
    if kind == "nan" and a.size:
        a.reshape(-1)[0] = np.nan
    elif kind == "inf" and a.size:
        a.reshape(-1)[-1] = -np.inf
    elif kind == "zeros":
        a = np.zeros_like(a)
    elif kind == "huge":
        a = a * 1e300
    elif kind == "tiny":
        a = a * 1e-300
    elif kind == "rank_one" and last == (3, 3):
        a = np.einsum("...i,...j->...ij", rng.normal(size=lead + (3,)), rng.normal(size=lead + (3,)))
    elif kind == "wrong_shape":
        a = rng.normal(size=lead + (last[-1] + 1,))
    elif kind == "string":
        return kind, "rotation"
    elif kind == "complex":
        a = a + 1j
    elif kind == "int":
        a = np.rint(a).astype(np.int64)
    elif kind == "list":
        return kind, a.tolist()
    return f"{kind}{lead}", a


@scaled(60)
@given(R=_matrices())
def test_orthonormalize_and_matrix_to_quat(R):
    label, a = R
    out = attempt("rotations.orthonormalize", label, orthonormalize, a, check=proper_rotations)
    attempt("rotations.matrix_to_quat", label, matrix_to_quat, a if out.value is None else out.value,
            check=lambda q: (finite_array()(q), np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0,
                                                                           atol=1e-9)))


@scaled(40)
@given(q=_matrices(last=(4,)))
def test_quat_to_matrix(q):
    attempt("rotations.quat_to_matrix", q[0], quat_to_matrix, q[1], check=proper_rotations)


_rngs = st.sampled_from([("valid", 0), ("valid", np.random.default_rng(1)), ("string", "seed"), ("none", None),
                         ("float", 1.5), ("negative", -1), ("legacy", np.random.RandomState(0))])


@scaled(50)
@given(rng=_rngs, n=st.one_of(st.integers(0, 200).map(lambda v: ("valid", v)), st.sampled_from(
    BAD_NUMBERS + (("too_many", 10**12),))),
    angle=st.one_of(st.floats(0.0, 4.0).map(lambda v: ("valid", v)), st.sampled_from(BAD_NUMBERS)))
def test_rotation_sampling(rng, n, angle):
    label = f"rng:{rng[0]} n:{n[0]} max_angle:{angle[0]}"
    attempt("rotations.shoemake_quaternions", label, shoemake_quaternions, rng[1], n[1],
            check=lambda q: (finite_array((None, 4))(q), np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0)))
    attempt("rotations.sample_rotations_within", label, sample_rotations_within, rng[1], n[1], angle[1],
            check=lambda R: (finite_array((None, 3, 3))(R), proper_rotations(R) if len(R) else None))


@st.composite
def _regression_data(draw):
    rng = np.random.default_rng(draw(seeds))
    n, q, D = draw(st.integers(0, 12)), draw(st.integers(0, 6)), draw(st.integers(1, 30))
    X, Y = rng.normal(size=(n, q)), rng.normal(size=(n, D))
    groups = rng.integers(0, 3, n) if draw(st.booleans()) else None
    kind = draw(st.sampled_from(["valid", "valid", "valid", "nan", "huge", "mismatch", "wrong_ndim", "string",
                                 "duplicate_rows", "groups_short", "groups_strings", "groups_nan", "constant"]))
    if kind == "nan" and X.size:
        X[0, 0] = np.nan
    elif kind == "huge":
        Y = Y * 1e300
    elif kind == "mismatch":
        Y = Y[:-1] if n else rng.normal(size=(1, D))
    elif kind == "wrong_ndim":
        X = X.reshape(-1)
    elif kind == "string":
        X = "latents"
    elif kind == "duplicate_rows" and n:
        X = np.repeat(X[:1], n, axis=0)
    elif kind == "groups_short":
        groups = np.zeros(n + 1, dtype=int)
    elif kind == "groups_strings":
        groups = np.array(["a", "b"] * n)[:n]
    elif kind == "groups_nan":
        groups = np.full(n, np.nan)
    elif kind == "constant":
        X = np.zeros((n, q))
    return f"{kind}(n={n},q={q})", X, Y, groups


@scaled(60)
@given(data=_regression_data(),
       alpha=st.one_of(st.floats(0.0, 10.0).map(lambda v: ("valid", v)), st.sampled_from(BAD_NUMBERS)),
       xq=st.sampled_from([("valid", None), ("nan", np.nan), ("string", "x"), ("scalar", 0.5), ("wrong_length", 99),
                           ("huge", 1e300), ("batch", "batch")]))
def test_ridge_fit_and_predict(data, alpha, xq):
    label, X, Y, groups = data
    out = attempt("regression.fit_ridge", f"{label} alpha:{alpha[0]}", fit_ridge, X, Y, alpha=alpha[1], groups=groups,
                  check=lambda r: (finite_array(ndim=2)(r.coef), finite_array(ndim=1)(r.intercept)))
    reg = out.value if out.value is not None else LinearRegressor(np.ones((4, 2)), np.zeros(4), 0.1)
    q = reg.coef.shape[1]
    rng = np.random.default_rng(0)
    x = {"valid": rng.normal(size=q), "nan": np.full(q, np.nan), "string": "x", "scalar": 0.5,
         "wrong_length": np.zeros(q + 1), "huge": np.full(q, 1e300), "batch": rng.normal(size=(3, q))}[xq[0]]
    attempt("regression.LinearRegressor.predict", f"x:{xq[0]} q={q}", reg.predict, x,
            check=finite_array())


_cams = st.sampled_from([("valid", (0.6, 0.0, 0.3)), ("valid", (0.0, 0.0, 0.1)), ("nan", (np.nan, 0.0, 0.0)),
                         ("wrong_shape", (0.0, 1.0)), ("string", "left"), ("far_1km", (1000.0, 0.0, 0.0)),
                         ("huge", (1e300, 0.0, 0.0))])


@scaled(50)
@given(points=clouds(min_n=1, max_n=200, valid_weight=6), camera=_cams,
       factor=st.one_of(st.floats(1.5, 1e4).map(lambda v: ("valid", v)), st.sampled_from(BAD_NUMBERS)))
def test_hidden_point_removal(points, camera, factor):
    label = f"points:{points[0]} camera:{camera[0]} radius_factor:{factor[0]}"
    n = len(points[1]) if (isinstance(points[1], np.ndarray) and points[1].ndim == 2) or isinstance(points[1], list) \
        else None

    def check(mask):
        assert isinstance(mask, np.ndarray) and mask.dtype == bool and mask.shape == (n,)

    attempt("visibility.hidden_point_removal", label, hidden_point_removal, points[1], camera[1],
            radius_factor=factor[1], check=check)
