"""Fuzzing the deformation field and pose warping (core/deformation.py)."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from catgrasp_drake.core.deformation import (
    deform_points,
    inverse_deform_points,
    inverse_warp_poses,
    jacobian,
    warp_poses,
)

from .harness import attempt, finite_array, rigid_poses
from .strategies import MUST_REJECT, choice, clouds, latents, number, options, poses, scaled


@st.composite
def _fields(draw, space):
    """``(label, (canonical, W, beta))``: a shape space's field for a latent x, or a damaged one."""
    xl, x = draw(latents(space.q).filter(lambda t: t[0] in ("valid", "zero", "large")))
    W = space.decode(x)
    C, beta = space.canonical, space.beta
    kind = draw(st.sampled_from(["valid"] * 6 + ["W_nan", "W_wrong_shape", "W_huge", "C_cloud", "beta_bad",
                                                 "W_string", "far_1km"]))
    if kind == "W_nan":
        W = W.copy()
        W[0, 0] = np.nan
    elif kind == "W_wrong_shape":
        W = W[:-1]
    elif kind == "W_huge":
        W = W * 1e300
    elif kind == "C_cloud":
        cl, C = draw(clouds(min_n=1, max_n=40))
        kind = f"canonical:{cl}"
        W = np.zeros(np.shape(C)) if cl not in MUST_REJECT and np.ndim(C) == 2 else W
    elif kind == "beta_bad":
        bl, beta = draw(number(st.nothing())[1])
        kind = f"beta:{bl}"
    elif kind == "W_string":
        W = "weights"
    elif kind == "far_1km":
        C = C + 1000.0
    return f"field:{kind}/x:{xl}", (C, W, beta)


@scaled(60)
@given(data=st.data())
def test_deform_and_inverse(small_space, data):
    fl, (C, W, beta) = data.draw(_fields(small_space))
    pl, P = data.draw(clouds(min_n=1, max_n=60, valid_weight=8))
    opts = data.draw(options({"tol": number(st.floats(1e-12, 1e-3)), "max_iter": number(st.integers(1, 60)),
                              "refine": choice([True, False], [("string", "yes")])}))
    label = f"{fl} points:{pl}" + "".join(f" {k}={v[0]}" for k, v in opts.items() if v[0] != "valid")
    n = len(P) if isinstance(P, np.ndarray) and P.ndim == 2 else None
    attempt("deformation.deform_points", label, deform_points, C, W, beta, P, check=finite_array((n, 3)))
    attempt("deformation.jacobian", label, jacobian, C, W, beta, P, check=finite_array((n, 3, 3)))
    kw = {k: v[1] for k, v in opts.items()}
    attempt("deformation.inverse_deform_points", label, inverse_deform_points, C, W, beta, P,
            check=finite_array((n, 3)), **kw)


@scaled(80)
@given(data=st.data())
def test_warp_poses(small_space, data):
    fl, (C, W, beta) = data.draw(_fields(small_space))
    xl, X = data.draw(poses())
    opts = data.draw(options({
        "eps": number(st.floats(1e-4, 0.01)),
        "anchor": choice([(0.0, 0.0, 0.03), (0.01, -0.02, 0.0), None],
                         [("nan", (np.nan, 0, 0)), ("wrong_shape", (0.0, 0.0)), ("string", "tip"),
                          ("huge", (1e300, 0.0, 0.0))]),
        "rotation_radius": number(st.floats(0.005, 0.1)),
    }))
    label = f"{fl} poses:{xl}" + "".join(f" {k}={v[0]}" for k, v in opts.items() if v[0] != "valid")
    kw = {k: v[1] for k, v in opts.items()}
    out = attempt("deformation.warp_poses", label, warp_poses, C, W, beta, X, check=rigid_poses, **kw)
    inv_kw = {k: v for k, v in kw.items() if k != "eps"}
    attempt("deformation.inverse_warp_poses", label, inverse_warp_poses, C, W, beta,
            out.value if out.value is not None else X, check=rigid_poses, **inv_kw)
