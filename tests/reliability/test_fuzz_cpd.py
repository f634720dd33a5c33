"""Fuzzing CPD (core/cpd.py): non-rigid and rigid registration with bad clouds and parameters."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from catgrasp_drake.core.cpd import nonrigid_cpd, rigid_cpd
from catgrasp_drake.core.kernels import gaussian_kernel, low_rank_kernel

from .harness import attempt, finite_array, proper_rotations
from .strategies import MUST_REJECT, WORDS, bad_numbers, choice, clouds, number, options, scaled

_params = options({
    "beta": number(st.floats(0.005, 0.2)),
    "lam": number(st.floats(0.1, 10.0)),
    "w": number(st.floats(0.0, 0.5)),
    "sigma2": number(st.floats(1e-12, 1.0)),
    "tol": number(st.floats(0.0, 1e-3)),
    "max_iter": number(st.integers(1, 30)),
    "low_rank": choice([None, "auto", 5, 1], [("zero", 0), ("string", "many"), ("nan", float("nan")),
                                              ("negative", -3), ("fraction", 2.5)]),
})


def _labels(source, target, params):
    bad = [f"{k}={v[0]}" for k, v in params.items() if v[0] != "valid"]
    return f"source:{source[0]} target:{target[0]}" + (" " + ",".join(bad) if bad else "")


def _expect(source, target, params):
    """Must reject when a cloud cannot have a result; the message must name the problem when it is the only one."""
    expect = "reject" if source[0] in MUST_REJECT or target[0] in MUST_REJECT else None
    bad = [c[0] for c in (source, target) if c[0] != "valid"] + [k for k, v in params.items() if v[0] != "valid"]
    words = WORDS.get(bad[0], ()) if len(bad) == 1 else ()
    return expect, words


def _check_nonrigid(M):
    def check(r):
        finite_array((M, 3))(r.W)
        finite_array((M, 3))(r.transformed)
        assert np.isfinite(r.sigma2) and r.sigma2 >= 0 and np.isfinite(r.objective)
        assert 0 <= r.iterations and finite_array((M,))(r.P1) is None
    return check


def _check_rigid(M):
    def check(r):
        finite_array((M, 3))(r.transformed)
        proper_rotations(r.R)
        finite_array((3,))(r.t)
        assert np.isfinite(r.s) and r.s > 0 and np.isfinite(r.sigma2) and np.isfinite(r.objective)
    return check


def _m(source):
    """Rows of ``source`` (for the result check; only a valid source can give a result)."""
    return getattr(source, "shape", (None,))[0] if getattr(source, "ndim", 0) else (
        len(source) if isinstance(source, list) else None)


@scaled(60)
@given(source=clouds(max_n=60, valid_weight=12), target=clouds(max_n=60, valid_weight=12), params=_params)
def test_nonrigid_cpd(source, target, params):
    kwargs = {k: v[1] for k, v in params.items()}
    kwargs.setdefault("max_iter", 20)
    expect, words = _expect(source, target, params)
    attempt("cpd.nonrigid_cpd", _labels(source, target, params), nonrigid_cpd, source[1], target[1],
            check=_check_nonrigid(_m(source[1])), expect=expect, words=words, **kwargs)


@scaled(50)
@given(source=clouds(max_n=60, valid_weight=12), target=clouds(max_n=60, valid_weight=12),
       params=options({
           "scale": choice([True, False], [("string", "yes"), ("none", None)]),
           "w": number(st.floats(0.0, 0.5)),
           "sigma2": number(st.floats(1e-12, 1.0)),
           "tol": number(st.floats(0.0, 1e-3)),
           "max_iter": number(st.integers(1, 30)),
       }))
def test_rigid_cpd(source, target, params):
    kwargs = {k: v[1] for k, v in params.items()}
    kwargs.setdefault("max_iter", 30)
    expect, words = _expect(source, target, params)
    attempt("cpd.rigid_cpd", _labels(source, target, params), rigid_cpd, source[1], target[1],
            check=_check_rigid(_m(source[1])), expect=expect, words=words, **kwargs)


@scaled(30)
@given(a=clouds(min_n=1, max_n=60), beta=bad_numbers(valid=st.floats(0.001, 1.0)),
       rank=st.sampled_from([("valid", "auto"), ("valid", 3), ("valid", 1000), ("zero", 0), ("string", "x"),
                             ("none", None)]))
def test_kernels(a, beta, rank):
    label = f"points:{a[0]} beta={beta[0]}"
    attempt("cpd.gaussian_kernel", label, gaussian_kernel, a[1], a[1], beta[1], check=finite_array(ndim=2))
    attempt("cpd.low_rank_kernel", f"{label} rank={rank[0]}", low_rank_kernel, a[1], beta[1], rank[1],
            check=lambda r: (finite_array(ndim=2)(r[0]), finite_array(ndim=1)(r[1])))
