"""Fuzzing the latent + rigid fit (core/inference.py) on a small synthetic space and the trained models."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from catgrasp_drake.core.inference import InferenceResult, infer_latent_pose

from .harness import attempt, finite_array, proper_rotations
from .strategies import MUST_REJECT, WORDS, choice, clouds, number, options, poses, scaled

_options = options({
    "camera_position": choice([(0.6, 0.0, 0.3), (0.0, -0.5, 0.2), (0.3, 0.3, 1.0)],
                              [("nan", (np.nan, 0, 0)), ("wrong_shape", (1.0, 2.0)), ("string", "front"),
                               ("at_origin", (0.0, 0.0, 0.0)), ("far_1km", (1000.0, 0.0, 0.0)),
                               ("huge", (1e300, 0, 0)), ("none_inside", [None, 0, 0])]),
    "yaw_candidates": choice([None, 3, [0.0, 1.0], [-7.0]],
                             [("zero", 0), ("negative", -2), ("nan", [np.nan]), ("empty", []), ("string", "eight"),
                              ("too_many", 10**9), ("fraction", 2.5), ("huge_yaw", [1e300])]),
    "w": number(st.floats(0.0, 0.5)),
    "prior": number(st.floats(0.0, 10.0)),
    "tol": number(st.floats(0.0, 1e-3)),
    "max_iter": number(st.integers(1, 30)),
    "search_iter": number(st.integers(1, 8)),
    "search_points": number(st.integers(3, 100)),
    "max_points": number(st.integers(3, 200)),
    "visibility_every": number(st.integers(0, 5)),
    "radius_factor": number(st.floats(2.0, 1000.0)),
    "sigma2_init": number(st.floats(1e-8, 1e-2)),
    "scale_bounds": choice([(0.5, 2.0), (1.0, 1.0), (0.1, 10.0)],
                           [("inverted", (2.0, 0.5)), ("nan", (np.nan, 2.0)), ("string", "wide"), ("one", (0.5,)),
                            ("zero", (0.0, 1.0)), ("none", None)]),
    "fit_scale": choice([True, False], [("string", "no")]),
    "residual_cpd": choice([True, False], [("string", "yes")]),
    "residual_beta": number(st.floats(0.005, 0.1)),
})


@st.composite
def _initial_pose(draw):
    kind = draw(st.sampled_from(["none", "none", "pose", "tuple", "tuple_nan", "tuple_bad_scale"]))
    if kind == "none":
        return "none", None
    if kind == "pose":
        label, X = draw(poses())
        X = np.asarray(X) if not isinstance(X, str) else X
        return f"pose:{label}", (X[0] if isinstance(X, np.ndarray) and X.ndim == 3 and len(X) else X)
    if kind == "tuple":
        return "tuple", (np.eye(3), np.zeros(3), 1.0)
    if kind == "tuple_nan":
        return "tuple_nan", (np.full((3, 3), np.nan), np.zeros(3), 1.0)
    return "tuple_bad_scale", (np.eye(3), np.zeros(3), draw(st.sampled_from([0.0, -1.0, np.nan, "big"])))


def _check(space, n_obs):
    def check(r):
        assert isinstance(r, InferenceResult)
        finite_array((space.q,))(r.x)
        proper_rotations(r.R)
        finite_array((3,))(r.t)
        assert np.isfinite(r.s) and r.s > 0
        finite_array((space.n_points, 3))(r.completed)
        assert np.isfinite(r.energy) and np.isfinite(r.sigma2) and r.sigma2 > 0
        assert 0.0 <= r.confidence <= 1.0
    return check


def _run(entry, space, observed, options, init):
    kwargs = {k: v[1] for k, v in options.items()}
    kwargs.setdefault("max_iter", 15)
    if init[1] is not None:
        kwargs["initial_pose"] = init[1]
    bad = [f"{k}={v[0]}" for k, v in options.items() if v[0] != "valid"] + ([init[0]] if init[0] != "none" else [])
    label = f"observed:{observed[0]}" + (" " + ",".join(bad) if bad else "")
    expect = "reject" if observed[0] in MUST_REJECT else None
    words = WORDS.get(observed[0], ()) if not bad and observed[0] != "valid" else ()
    attempt(entry, label, infer_latent_pose, space, observed[1], check=_check(space, None), expect=expect,
            words=words, **kwargs)


@scaled(120)
@given(observed=clouds(max_n=150, valid_weight=12), options=_options, init=_initial_pose())
def test_infer_latent_pose(small_space, observed, options, init):
    _run("inference.infer_latent_pose", small_space, observed, options, init)


@scaled(30)
@given(category=st.sampled_from(["drill", "spray_bottle", "mug"]),
       observed=clouds(min_n=30, max_n=300, valid_weight=12),
       options=_options.filter(lambda o: "residual_cpd" not in o and "yaw_candidates" not in o),
       init=st.just(("none", None)))
def test_infer_latent_pose_trained_models(trained_models, category, observed, options, init):
    _run("inference.infer_latent_pose", trained_models[category].space, observed, options, init)


@scaled(20)
@given(space=st.sampled_from([("string", "drill"), ("none", None), ("array", np.zeros((10, 3)))]))
def test_infer_needs_a_shape_space(space):
    attempt("inference.infer_latent_pose", f"space:{space[0]}", infer_latent_pose, space[1], np.zeros((10, 3)),
            expect="reject", words=("ShapeSpace",))
