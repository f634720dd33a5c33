"""Coherent Point Drift: exactness, recovery of known deformations, stability, input errors."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.cpd import CPDIteration, joint_normalization, nonrigid_cpd, rigid_cpd
from catgrasp_drake.core.kernels import gaussian_kernel, low_rank_kernel
from catgrasp_drake.errors import InputError

from .test_synthetic_shapes import blob, fibonacci_sphere


def _smooth_warp(P, rng, beta=0.04, amp=0.01, n_ctrl=12):
    """A known smooth deformation in CPD's own model class: P + G(P, ctrl) A."""
    ctrl = P[rng.choice(len(P), n_ctrl, replace=False)]
    A = rng.normal(scale=amp, size=(n_ctrl, 3))
    return P + gaussian_kernel(P, ctrl, beta) @ A


def test_gaussian_kernel_values():
    A = np.zeros((1, 3))
    B = np.array([[1.0, 0, 0], [0, 2.0, 0]])
    G = gaussian_kernel(A, B, 1.0)
    assert np.allclose(G, [[np.exp(-0.5), np.exp(-2.0)]])


def test_recovers_a_known_smooth_deformation():
    # points filling a volume: on a smooth surface CPD may slide points tangentially
    # (it matches surfaces, not labels), which a per-point error would count as wrong
    rng = np.random.default_rng(0)
    Y = rng.uniform([-0.03, -0.06, 0.0], [0.03, 0.06, 0.18], size=(400, 3))
    X = _smooth_warp(Y, rng, beta=0.05, amp=0.01)
    disp = np.sqrt(((X - Y) ** 2).sum(1).mean())
    r = nonrigid_cpd(Y, X, beta=0.05, lam=1.0, max_iter=300, tol=1e-8)
    rms = np.sqrt(((r.transformed - X) ** 2).sum(1).mean())
    assert disp > 0.02
    assert rms < 1e-3 * disp, (rms, disp)  # measured 4e-11 m
    # the field: transformed == source + G W
    assert np.allclose(Y + gaussian_kernel(Y, Y, 0.05) @ r.W, r.transformed, atol=1e-9)
    assert r.converged and np.isfinite(r.objective)


def test_matches_the_reference_formulas_of_pycpd():
    pycpd = pytest.importorskip("pycpd")
    rng = np.random.default_rng(1)
    Y = blob((0.03, 0.06, 0.09, 0.0, 0.01), 200)
    X = _smooth_warp(Y, rng) + rng.normal(scale=1e-3, size=Y.shape)
    c, s = joint_normalization(Y, X)  # on pre-normalised data both use the same units
    Yn, Xn = (Y - c) / s, (X - c) / s
    reg = pycpd.DeformableRegistration(X=Xn, Y=Yn, alpha=2.0, beta=0.5, w=0.1, max_iterations=30, tolerance=0.0)
    TY, _ = reg.register()
    r = nonrigid_cpd(Yn, Xn, beta=0.5, lam=2.0, w=0.1, max_iter=30, tol=0.0)
    assert r.iterations == 30
    assert np.abs(r.transformed - TY).max() < 1e-8
    assert abs(r.sigma2 - reg.sigma2) < 1e-10


def test_low_rank_kernel_is_close_to_exact():
    rng = np.random.default_rng(2)
    Y = blob((0.03, 0.06, 0.09, 0.01, 0.01), 600)
    X = _smooth_warp(Y, rng)
    ex = nonrigid_cpd(Y, X, beta=0.03, lam=2.0, max_iter=60, tol=0.0)
    lr = nonrigid_cpd(Y, X, beta=0.03, lam=2.0, max_iter=60, tol=0.0, low_rank="auto")
    assert lr.rank < 600 and lr.kernel_trace_kept >= 0.9999
    rms_ex = np.sqrt(((ex.transformed - X) ** 2).sum(1).mean())
    rms_lr = np.sqrt(((lr.transformed - X) ** 2).sum(1).mean())
    assert abs(rms_lr - rms_ex) <= 0.05 * rms_ex + 1e-6
    # W is projected so that the exact kernel reproduces the low-rank displacements
    assert np.allclose(Y + gaussian_kernel(Y, Y, 0.03) @ lr.W, lr.transformed, atol=1e-6)


def test_low_rank_eigenpairs():
    Y = fibonacci_sphere(300) * 0.1
    # 36 = 1 + 3 + 5 + ... + 11: a gap in the sphere's spherical-harmonic eigenvalue clusters
    Q, lam, kept = low_rank_kernel(Y, 0.05, 36)
    G = gaussian_kernel(Y, Y, 0.05)
    ev = np.linalg.eigvalsh(G)[::-1][:36]
    assert np.allclose(lam[:25], ev[:25], rtol=1e-5)
    assert np.allclose(lam, ev, rtol=1e-3)  # the last cluster is nearly degenerate
    assert np.allclose(Q.T @ Q, np.eye(36), atol=1e-10)
    assert np.allclose(Q.T @ G @ Q, np.diag(lam), atol=1e-6 * lam[0])  # Rayleigh-Ritz pairs
    assert 0 < kept <= 1


def test_rigid_with_scale_and_outliers():
    from catgrasp_drake.core.rotations import rotation_angle, sample_rotations_within

    Y = blob((0.03, 0.06, 0.09, 0.01, 0.01), 400)
    R = sample_rotations_within(np.random.default_rng(3), 1, 0.5)[0]  # within CPD's basin of attraction
    X = 1.3 * Y @ R.T + np.array([0.05, -0.02, 0.01])
    X = np.vstack([X, np.random.default_rng(4).uniform(-0.2, 0.3, size=(30, 3))])  # 7 % outliers
    r = rigid_cpd(Y, X, scale=True, w=0.2)
    assert rotation_angle(r.R @ R.T) < 1e-2
    assert abs(r.s - 1.3) < 1e-2
    assert np.allclose(r.t, [0.05, -0.02, 0.01], atol=2e-3)
    assert np.isclose(np.linalg.det(r.R), 1.0)
    assert np.allclose(r.transform(Y), r.transformed)


def test_points_far_from_everything_stay_finite():
    Y = blob((0.03, 0.06, 0.09, 0.0, 0.0), 100)
    X = Y + 0.002
    X_far = np.vstack([X, [[500.0, 500.0, 500.0]]])
    for w in (0.0, 0.1):
        r = nonrigid_cpd(Y, X_far, beta=0.03, lam=3.0, w=w, max_iter=30)
        assert np.all(np.isfinite(r.transformed)) and np.isfinite(r.sigma2) and np.isfinite(r.objective)
        r2 = rigid_cpd(Y, X_far, w=w)
        assert np.all(np.isfinite(r2.transformed))
    # a tiny given sigma2 (every kernel value underflows) is handled in the log domain
    r = nonrigid_cpd(Y, Y + 0.05, beta=0.03, lam=3.0, sigma2=1e-12, max_iter=5)
    assert np.all(np.isfinite(r.transformed))


def test_callback_and_convergence_on_the_objective():
    Y = blob((0.03, 0.06, 0.09, 0.0, 0.0), 150)
    X = Y * 1.05
    seen = []
    r = nonrigid_cpd(Y, X, beta=0.03, lam=3.0, max_iter=200, tol=1e-4, callback=seen.append)
    assert r.converged and r.iterations < 200
    assert [c.iteration for c in seen] == list(range(1, len(seen) + 1))
    assert isinstance(seen[0], CPDIteration) and seen[0].transformed.shape == Y.shape
    objs = [c.objective for c in seen]
    assert all(b <= a + 1e-9 * abs(a) for a, b in zip(objs, objs[1:]))  # EM never increases f


@pytest.mark.parametrize(
    "source,target,match",
    [
        (np.zeros((0, 3)), np.ones((5, 3)), "empty"),
        (np.ones((2, 3)), np.ones((5, 3)), "at least 3"),
        (np.full((5, 3), np.nan), np.ones((5, 3)), "NaN"),
        (np.ones((5, 3)), np.ones((5, 2)), r"shape \(N, 3\)"),
        ("abc", np.ones((5, 3)), "numeric"),
    ],
)
def test_bad_inputs_raise_one_line_input_errors(source, target, match):
    with pytest.raises(InputError, match=match) as ei:
        nonrigid_cpd(source, target, beta=0.02, lam=3.0)
    assert "\n" not in str(ei.value)
    with pytest.raises(InputError, match=match):
        rigid_cpd(source, target)


def test_bad_parameters():
    Y = blob((0.03, 0.06, 0.09, 0.0, 0.0), 50)
    for kw, match in [({"beta": 0}, "beta"), ({"lam": -1}, "lam"), ({"w": 1.0}, "w"), ({"max_iter": 0}, "max_iter"),
                      ({"low_rank": "many"}, "low_rank")]:
        with pytest.raises(InputError, match=match):
            nonrigid_cpd(Y, Y, **kw)
