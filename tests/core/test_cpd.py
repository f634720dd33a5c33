"""Coherent Point Drift: exactness, recovery of known deformations, stability, input errors."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core import cpd
from catgrasp_drake.core.cpd import CPDIteration, joint_normalization, nonrigid_cpd, rigid_cpd
from catgrasp_drake.core.kernels import gaussian_kernel, low_rank_kernel, sqdist
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


def test_the_em_loop_stops_on_the_floor_on_no_mass_and_on_max_iter():
    """The stopping rules of the one EM loop (core.em.em_loop) as rigid_cpd and nonrigid_cpd report them."""
    Y = blob((0.03, 0.06, 0.09, 0.0, 0.01), 200)
    c, s = np.cos(0.4), np.sin(0.4)
    X = Y @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]).T
    seen = []
    r = rigid_cpd(Y, X, callback=seen.append)  # an exact fit: sigma2 reaches its floor
    assert r.converged and r.iterations == len(seen) < 100 and r.sigma2 < 1e-12
    assert np.abs(r.transformed - X).max() < 1e-9
    r = rigid_cpd(Y, X, tol=0.0, max_iter=5)
    assert not r.converged and r.iterations == 5
    # far-off targets with a tiny given sigma2 and outliers: every target is an outlier, nothing moves
    # (the E-step that found no mass is counted as an iteration, as before the loop was shared)
    for fit in (rigid_cpd(Y, X + 0.3, w=0.5, sigma2=1e-12), nonrigid_cpd(Y, X + 0.05, w=0.5, sigma2=1e-14)):
        assert not fit.converged and fit.iterations == 1
        assert np.all(fit.P1 == 0.0) and np.allclose(fit.transformed, Y, rtol=0.0, atol=1e-15)


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


# --------------------------------------------------------------------------- truncated and float32 E-steps


def _estep_problem(seed=5, n=600, far=True):
    """A deformed volume cloud as targets of a moved source (normalised units, ~unit size), plus one far target."""
    rng = np.random.default_rng(seed)
    Y = rng.uniform(-1.0, 1.0, size=(n, 3)) * [0.5, 1.0, 1.5]
    X = Y + 0.05 * np.sin(2.0 * Y) + rng.normal(scale=0.01, size=Y.shape)
    if far:
        X = np.vstack([X, [[0.0, 0.0, 3.0]]])  # a target with no source within 9 sigma: computed exactly
    return Y, X


def _l1_bound(X):
    """|dP1|_1, |dPt1|_inf, |dPX|_inf allowed by TRUNCATION_RTOL (each posterior column within 2 rtol in L1),
    with room for the dense reference's own rounding."""
    N = len(X)
    r = 2.0 * cpd.TRUNCATION_RTOL
    return N * r + 1e-10, r + 1e-12, N * r * float(np.abs(X).max()) + 1e-10


@pytest.mark.parametrize("w", [0.0, 0.1])
def test_truncated_estep_equals_the_dense_one_within_its_bound(w):
    Y, X = _estep_problem()
    sigma2 = 0.02**2  # 9 sigma = 0.18: ~0.4 % of the pairs
    e_step = cpd.TruncatedEStep(X, w)
    got = e_step(Y, sigma2)
    assert e_step.mode == "sparse"
    ref = cpd.estep(Y, X, sigma2, w)
    b_p1, b_pt1, b_px = _l1_bound(X)
    assert np.abs(got.P1 - ref.P1).sum() <= b_p1
    assert np.abs(got.Pt1 - ref.Pt1).max() <= b_pt1
    assert np.abs(got.PX - ref.PX).max() <= b_px
    assert abs(got.Np - ref.Np) <= b_p1
    assert abs(got.nll - ref.nll) <= len(X) * 2 * cpd.TRUNCATION_RTOL + 1e-9 * abs(ref.nll)
    # the far target keeps its exact (tiny) posterior mass, computed in the log domain
    assert got.Pt1[-1] == pytest.approx(ref.Pt1[-1], rel=1e-9, abs=1e-300)


def test_truncated_estep_is_the_dense_one_while_sigma_is_large():
    Y, X = _estep_problem(far=False)
    e_step = cpd.TruncatedEStep(X, 0.05)
    got = e_step(Y, 0.3**2)  # 9 sigma spans the cloud: every pair counts
    assert e_step.mode == "dense"
    ref = cpd.estep(Y, X, 0.3**2, 0.05)
    assert np.array_equal(got.PX, ref.PX) and np.array_equal(got.P1, ref.P1) and got.nll == ref.nll
    wide = cpd.TruncatedEStep(X, 0.05)
    wide(Y, 1.0)  # 9 sigma spans both clouds' bounding box: dense, and no k-d tree is built
    assert wide.mode == "dense" and wide._trees is None


def test_float32_estep_within_its_stated_bound():
    Y, X = _estep_problem(far=False, n=400)
    # sigma 0.1 and 0.05: most exponents lie below -87, where float32's normal range ends (they are clamped there)
    assert (sqdist(Y, X) / (2 * 0.1**2) > -cpd._EXP_CLAMP32).mean() > 0.5
    for sigma2 in (0.3**2, 0.1**2, 0.05**2):
        ref = cpd.estep(Y, X, sigma2, 0.05)
        got = cpd.estep(Y, X, sigma2, 0.05, dtype=np.float32)
        ctr = X.mean(0)
        bound = 8 * cpd.EPS32 * cpd.exponent_bound(Y - ctr, X - ctr, sigma2)
        # kernel values within exp(bound) - 1, plus float32 sums of M terms
        rel = 2.0 * bound + 2.0 * len(Y) * cpd.EPS32
        assert np.abs(got.P1 - ref.P1).max() <= rel * ref.P1.max()
        assert np.abs(got.PX - ref.PX).max() <= rel * np.abs(ref.PX).max()
        assert np.abs(got.Pt1 - ref.Pt1).max() <= rel
    e_step = cpd.TruncatedEStep(X, 0.05, fast=True)
    e_step(Y, 0.3**2)
    assert e_step.mode == "dense32"


def test_kernel32_estep_within_its_stated_bound_at_any_sigma_and_distance():
    """exp in float32 on float64 exponents: every kernel value within KERNEL32_RTOL of float64's however small
    sigma2 is (the float32 E-step's bound grows as 1/sigma2), columns whose every exponent lies below -87 redone
    exactly, and the sums float64, so P1 and Pt1 add up to the same Np and a cloud 1 km away is no worse."""
    Y, X = _estep_problem(far=True, n=400)
    rtol = cpd.KERNEL32_RTOL
    assert rtol < 6e-6
    for offset in (0.0, 1000.0):
        for sigma2 in (0.3**2, 0.05**2, 0.005**2):
            ref = cpd.estep(Y + offset, X + offset, sigma2, 0.05)
            got = cpd.estep(Y + offset, X + offset, sigma2, 0.05, kernel32=True)
            # a posterior is a ratio of kernel sums: within 2 rtol of the reference's, relative
            assert np.all(np.abs(got.P1 - ref.P1) <= 2 * rtol * ref.P1 + 1e-12)
            assert np.all(np.abs(got.Pt1 - ref.Pt1) <= 2 * rtol * ref.Pt1 + 1e-12)
            assert np.all(np.abs(got.PX - ref.PX) <= 2 * rtol * ref.P1[:, None] * np.abs(X + offset).max() + 1e-9)
            assert abs(got.nll - ref.nll) <= len(X) * rtol
            assert got.P1.sum() == pytest.approx(got.Pt1.sum(), rel=1e-12)
            if sigma2 < 0.1**2:  # the far target: every exponent below -87, redone in the log domain in float64
                assert got.Pt1[-1] == pytest.approx(ref.Pt1[-1], rel=1e-9, abs=1e-300)
    # where float32's own bound is useless (1/sigma2 large), kernel32 is still within its bound
    ctr = X.mean(0)
    assert 8 * cpd.EPS32 * cpd.exponent_bound(Y - ctr, X - ctr, 0.005**2) > 1e-2
    # with float32 inputs the flag changes nothing
    a = cpd.estep(Y, X, 0.05**2, 0.05, dtype=np.float32)
    b = cpd.estep(Y, X, 0.05**2, 0.05, dtype=np.float32, kernel32=True)
    assert np.array_equal(a.PX, b.PX) and a.nll == b.nll


def test_every_e_step_recovers_a_known_deformation_and_agrees():
    rng = np.random.default_rng(0)
    Y = rng.uniform([-0.03, -0.06, 0.0], [0.03, 0.06, 0.18], size=(500, 3))
    X = _smooth_warp(Y, rng, beta=0.05, amp=0.01)
    disp = np.sqrt(((X - Y) ** 2).sum(1).mean())
    modes = []
    orig = cpd.TruncatedEStep.__call__

    def spy(self, T, s2):
        out = orig(self, T, s2)
        modes.append(self.mode)
        return out

    results = {}
    for e_step in cpd.E_STEPS:
        cpd.TruncatedEStep.__call__ = spy
        try:
            results[e_step] = nonrigid_cpd(Y, X, beta=0.05, lam=1.0, max_iter=300, tol=1e-8, e_step=e_step,
                                           low_rank="auto")
        finally:
            cpd.TruncatedEStep.__call__ = orig
        rms = np.sqrt(((results[e_step].transformed - X) ** 2).sum(1).mean())
        assert rms < 2e-3 * disp, (e_step, rms, disp)
    assert {"sparse", "dense", "dense32"} <= set(modes)  # every path of the truncated E-step was used
    ex = results["exact"].transformed
    assert np.abs(results["truncated"].transformed - ex).max() < 1e-9  # m
    assert np.abs(results["fast"].transformed - ex).max() < 1e-5 * disp


@pytest.mark.parametrize("e_step", ["truncated", "fast"])
def test_new_e_steps_are_identical_for_any_thread_count(monkeypatch, e_step):
    Y, X = _estep_problem(far=False)

    def run(n):
        monkeypatch.setattr(cpd, "n_threads", lambda: n)
        r = nonrigid_cpd(Y * 0.05, X * 0.05, beta=0.05, lam=3.0, max_iter=40, low_rank="auto", e_step=e_step)
        return r.W, r.sigma2

    W1, s1 = run(1)
    W2, s2 = run(3)
    assert np.array_equal(W1, W2) and s1 == s2


def test_bad_e_step():
    Y = blob((0.03, 0.06, 0.09, 0.0, 0.0), 50)
    for bad in ("dense", None, 3):
        with pytest.raises(InputError, match="e_step") as ei:
            nonrigid_cpd(Y, Y, e_step=bad)
        assert "\n" not in str(ei.value)


def test_low_rank_kernel_threads_and_storage_change_no_bit():
    from concurrent.futures import ThreadPoolExecutor

    from catgrasp_drake.core import kernels

    Y = np.random.default_rng(3).uniform(-1, 1, size=(700, 3))
    ref = kernels.low_rank_kernel(Y, 0.7, "auto")
    with ThreadPoolExecutor(3) as pool:
        threaded = kernels.low_rank_kernel(Y, 0.7, "auto", pool=pool)
    stored_before = kernels.KERNEL_STORE_ELEMENTS
    try:
        kernels.KERNEL_STORE_ELEMENTS = 0  # recompute every block
        recomputed = kernels.low_rank_kernel(Y, 0.7, "auto")
    finally:
        kernels.KERNEL_STORE_ELEMENTS = stored_before
    for other in (threaded, recomputed):
        assert np.array_equal(other[0], ref[0]) and np.array_equal(other[1], ref[1]) and other[2] == ref[2]


# ----------------------------------------------------------------------------- SQUAREM acceleration
def test_squarem_solves_a_slow_linear_map_in_a_few_cycles():
    """A contraction theta -> theta* + 0.95 (theta - theta*) (plain iteration: ~400 steps to 1e-9) with the
    objective |theta - theta*|^2: squared extrapolation is exact on a linear map once its step bound
    allows 1 / (1 - 0.95) = 20, so SQUAREM lands on theta* in a few cycles."""
    from catgrasp_drake.core.em import squarem

    target = np.array([0.3, -1.2, 2.0])

    def em_map(theta):
        return target + 0.95 * (theta - target), float(((theta - target) ** 2).sum()), False

    r = squarem(em_map, np.zeros(3), n_points=1, max_evals=500, tol=1e-12)
    assert r.stop == "tol" and r.evaluations < 20 and r.accepted >= 1
    assert np.abs(r.theta - target).max() < 1e-6


def test_squarem_cpd_reaches_the_plain_ems_fixed_point_in_fewer_steps():
    rng = np.random.default_rng(0)
    Y = rng.uniform([-0.03, -0.06, 0.0], [0.03, 0.06, 0.18], size=(500, 3))
    X = _smooth_warp(Y, rng, beta=0.05, amp=0.01)
    disp = np.sqrt(((X - Y) ** 2).sum(1).mean())
    for low_rank in (None, "auto"):
        plain = nonrigid_cpd(Y, X, beta=0.05, lam=1.0, max_iter=300, tol=1e-8, low_rank=low_rank)
        seen = []
        fast = nonrigid_cpd(Y, X, beta=0.05, lam=1.0, max_iter=300, tol=1e-8, low_rank=low_rank,
                            acceleration="squarem", callback=lambda it: seen.append(it.iteration))
        assert fast.converged and fast.iterations < 0.8 * plain.iterations, (fast.iterations, plain.iterations)
        assert seen == list(range(1, len(seen) + 1)) and len(seen) >= fast.iterations - 1
        assert np.abs(fast.transformed - plain.transformed).max() < 1e-3 * disp
        assert np.sqrt(((fast.transformed - X) ** 2).sum(1).mean()) < 2e-3 * disp
        assert np.allclose(Y + gaussian_kernel(Y, Y, 0.05) @ fast.W, fast.transformed, atol=1e-9)


def test_bad_acceleration():
    Y = blob((0.03, 0.06, 0.09, 0.0, 0.0), 50)
    with pytest.raises(InputError, match="acceleration"):
        nonrigid_cpd(Y, Y, acceleration="anderson")
