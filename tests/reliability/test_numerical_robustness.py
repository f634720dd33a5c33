"""Numerical robustness with known answers: CPD and inference for a cloud 1 km away, for sigma^2
collapsing to 0 (identical clouds), and for rank-deficient shape spaces (fewer distinct instances
than latent dimensions)."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.cpd import nonrigid_cpd, rigid_cpd
from catgrasp_drake.core.inference import SIGMA2_MIN_M2, infer_latent_pose
from catgrasp_drake.core.rotations import rotz
from catgrasp_drake.core.shape_space import build_shape_space, pca_em
from catgrasp_drake.errors import InputError

from ..core.test_synthetic_shapes import blob, family
from .harness import attempt

KM = np.array([1000.0, -300.0, 50.0])  # ~1.05 km


@pytest.fixture(scope="module")
def shape():
    return blob((0.03, 0.06, 0.09, 0.01, 0.01), 200)


# ----------------------------------------------------------------------------- sigma^2 -> 0

def test_cpd_identical_clouds_give_zero_deformation(shape):
    """sigma^2 collapses to its floor; no division by zero, and the answer is the identity."""
    r = nonrigid_cpd(shape, shape, beta=0.03, lam=3.0)
    assert r.converged and np.isfinite(r.objective)
    assert 0.0 < r.sigma2 < 1e-10  # m^2: at the floor (SIGMA2_FLOOR in normalised units), not 0 or NaN
    assert np.abs(r.W).max() < 1e-9 and np.abs(r.transformed - shape).max() < 1e-12
    q = rigid_cpd(shape, shape)
    assert q.converged and abs(q.s - 1.0) < 1e-12
    np.testing.assert_allclose(q.R, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(q.t, 0.0, atol=1e-12)


def test_cpd_tiny_given_sigma2_stays_finite(shape):
    """A given sigma^2 of 1e-300 m^2: every kernel value underflows; log-domain E-step, finite result."""
    for sigma2 in (1e-300, 1e-30):
        r = nonrigid_cpd(shape, shape + 0.004, beta=0.03, lam=3.0, sigma2=sigma2, max_iter=20)
        assert np.all(np.isfinite(r.transformed)) and np.isfinite(r.sigma2) and np.isfinite(r.objective)
        q = rigid_cpd(shape, shape + 0.004, sigma2=sigma2, max_iter=50)
        assert np.all(np.isfinite(q.transformed)) and np.isfinite(q.s)


def test_inference_on_the_canonical_shape_itself(small_space):
    """Observing exactly the mean shape: sigma^2 falls to its 0.1 mm floor, the completion is the shape."""
    obs = small_space.deform(np.zeros(small_space.q))
    r = infer_latent_pose(small_space, obs, max_iter=200, w=0.0)
    assert SIGMA2_MIN_M2 <= r.sigma2 < 1e-6
    assert np.abs(r.completed - obs).max() < 2e-3
    assert np.linalg.norm(r.x) < 1.0 and abs(r.s - 1.0) < 0.02
    np.testing.assert_allclose(r.R, np.eye(3), atol=0.02)


# ----------------------------------------------------------------------------- 1 km away

def test_rigid_cpd_recovers_a_1km_translation(shape):
    """From the identity every posterior is uniform and the scale used to collapse to 5e-8; now exact."""
    R = rotz(0.3)
    far = 1.1 * shape @ R.T + KM
    r = rigid_cpd(shape, far)
    np.testing.assert_allclose(r.R, R, atol=1e-6)
    assert abs(r.s - 1.1) < 1e-6
    np.testing.assert_allclose(r.transform(shape), far, atol=1e-6)


def test_nonrigid_cpd_refuses_clouds_1km_apart_with_a_clear_message(shape):
    out = attempt("cpd.nonrigid_cpd", "known:far_1km", nonrigid_cpd, shape, shape + KM, expect="reject",
                  words=("apart",))
    assert "rigid_cpd" in str(out.error)


def test_inference_of_an_instance_1km_away(small_space):
    """Centroid matching starts the fit at the cloud: the far instance is completed to the millimetre."""
    x = small_space.latent_train[2]
    obs = small_space.deform(x) @ rotz(0.2).T + KM
    r = infer_latent_pose(small_space, obs, yaw_candidates=[0.2], max_iter=100, prior=0.0)
    assert np.all(np.isfinite(r.x)) and np.isfinite(r.energy)
    assert np.abs(r.completed - obs).max() < 5e-3
    np.testing.assert_allclose(r.t, KM + np.zeros(3), atol=0.05)
    assert r.confidence > 0.5


def test_inference_of_a_shape_unlike_the_category_stays_finite(small_space):
    """Far from the canonical shape in shape (a thin rod, a 2 m-wide plate, a single line): finite answers."""
    rng = np.random.default_rng(0)
    rod = np.c_[rng.normal(0, 0.002, 300), rng.normal(0, 0.002, 300), rng.uniform(0, 0.4, 300)]
    plate = np.c_[rng.uniform(-1, 1, 300), rng.uniform(-1, 1, 300), np.zeros(300)]
    line = np.outer(np.linspace(0, 0.2, 50), [1.0, 1.0, 0.0])
    for name, obs in (("rod", rod), ("plate", plate), ("line", line)):
        out = attempt("inference.infer_latent_pose", f"known:{name}", infer_latent_pose, small_space, obs,
                      yaw_candidates=4, max_iter=40)
        r = out.value
        assert np.all(np.isfinite(r.completed)) and np.all(np.isfinite(r.x)) and 0.5 <= r.s <= 2.0
        assert 0.0 <= r.confidence <= 1.0


# ----------------------------------------------------------------------------- rank-deficient shape spaces

def test_pca_em_on_rank_one_data_asked_for_more_components():
    """q = 3 components of rank-1 data (fewer directions than latent dimensions): orthonormal, the extra
    variances 0, the first component the data's direction."""
    d = np.random.default_rng(1).normal(size=12)
    Y = np.outer(np.arange(4.0), d)
    p = pca_em(Y, 3)
    np.testing.assert_allclose(p.components @ p.components.T, np.eye(3), atol=1e-9)
    assert p.variances[0] > 1.0 and np.all(np.abs(p.variances[1:]) < 1e-12)
    assert abs(abs(p.components[0] @ d / np.linalg.norm(d)) - 1.0) < 1e-9


def test_shape_space_from_duplicate_instances_is_one_dimensional():
    """4 instances, only 2 distinct (3 could-be latent dimensions): q = 1, finite, and inference on the
    second shape recovers it exactly."""
    inst = family(np.random.default_rng(7), 2, n=80)
    space = build_shape_space([inst[0], inst[1], inst[1], inst[1]], canonical_index=0, beta=0.03, lam=3.0,
                              variance=1.0)
    assert space.q == 1 and np.all(np.isfinite(space.latent_train)) and np.all(space.eigenvalues > 0)
    np.testing.assert_allclose(space.latent_train[1:], np.repeat(space.latent_train[1:2], 3, axis=0), atol=1e-9)
    r = infer_latent_pose(space, inst[1], max_iter=100, prior=0.0)
    assert np.abs(r.completed - inst[1]).max() < 1e-3
    assert abs(r.x[0] - space.latent_train[1, 0]) < 0.05


def test_shape_space_of_two_instances_and_of_identical_instances():
    inst = family(np.random.default_rng(3), 2, n=60)
    space = build_shape_space(inst, canonical_index=0, beta=0.03, lam=3.0)
    assert space.q == 1
    np.testing.assert_allclose(np.abs(space.latent_train[:, 0]), 1 / np.sqrt(2), atol=1e-9)  # whitened, K - 1
    with pytest.raises(InputError, match="identically") as e:
        build_shape_space([inst[0], inst[0], inst[0]], canonical_index=0)
    assert "\n" not in str(e.value)
