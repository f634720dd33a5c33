"""Dense deformation field: forward, inverse (eq. 14 + Newton), pose warping."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.cpd import nonrigid_cpd
from catgrasp_drake.core.deformation import (
    deform_points,
    inverse_deform_points,
    inverse_warp_poses,
    jacobian,
    warp_poses,
)
from catgrasp_drake.core.rotations import quat_to_matrix, rotation_angle, shoemake_quaternions
from catgrasp_drake.errors import InputError

from .test_synthetic_shapes import blob

BETA = 0.02


@pytest.fixture(scope="module")
def field():
    C = blob((0.03, 0.06, 0.09, 0.0, 0.01), 300)
    T = blob((0.035, 0.07, 0.11, 0.015, 0.02), 300)
    r = nonrigid_cpd(C, T, beta=BETA, lam=3.0)
    return C, r.W, r


def test_forward_field_at_canonical_points(field):
    C, W, r = field
    assert np.allclose(deform_points(C, W, BETA, C), r.transformed, atol=1e-9)
    far = np.array([[5.0, 5.0, 5.0]])
    assert np.allclose(deform_points(C, W, BETA, far), far)  # the field vanishes far away


def test_jacobian_matches_finite_differences(field):
    C, W, _ = field
    p = C[:5] + 0.003
    J = jacobian(C, W, BETA, p)
    h = 1e-6
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        fd = (deform_points(C, W, BETA, p + e) - deform_points(C, W, BETA, p - e)) / (2 * h)
        assert np.allclose(J[:, :, k], fd, atol=1e-6)


def test_inverse_inverts_the_forward_field(field):
    C, W, _ = field
    rng = np.random.default_rng(0)
    p = C + rng.normal(scale=0.005, size=C.shape)  # canonical points and points off the surface
    o = deform_points(C, W, BETA, p)
    back, res = inverse_deform_points(C, W, BETA, o, return_residual=True)
    assert res.max() <= 1e-9
    assert np.abs(back - p).max() < 1e-8  # stated tolerance: 1e-9 m residual -> ~1e-8 m in position
    # the paper's eq. 14 alone is only approximate
    eq14 = inverse_deform_points(C, W, BETA, o, refine=False)
    assert np.abs(eq14 - p).max() > 1e-5
    # far points: finite, identity
    far = np.array([[3.0, -2.0, 1.0]])
    assert np.allclose(inverse_deform_points(C, W, BETA, far), far)


def test_warped_rotations_are_proper_and_inverse_warp_round_trips(field):
    C, W, _ = field
    rng = np.random.default_rng(1)
    X = np.tile(np.eye(4), (20, 1, 1))
    X[:, :3, :3] = quat_to_matrix(shoemake_quaternions(rng, 20))
    X[:, :3, 3] = C[rng.choice(len(C), 20)] + rng.normal(scale=0.002, size=(20, 3))
    Xw = warp_poses(C, W, BETA, X)
    R = Xw[:, :3, :3]
    assert np.allclose(R @ np.swapaxes(R, 1, 2), np.eye(3), atol=1e-10)
    assert np.allclose(np.linalg.det(R), 1.0)
    assert np.allclose(Xw[:, :3, 3], deform_points(C, W, BETA, X[:, :3, 3]))
    assert np.allclose(Xw[:, 3], [0, 0, 0, 1])
    back = inverse_warp_poses(C, W, BETA, Xw)
    assert np.abs(back[:, :3, 3] - X[:, :3, 3]).max() < 1e-8
    assert rotation_angle(back[:, :3, :3] @ np.swapaxes(X[:, :3, :3], 1, 2)).max() < 1e-7
    # finite basis points converge to the analytic Jacobian
    Xe = warp_poses(C, W, BETA, X, eps=1e-7)
    assert rotation_angle(Xe[:, :3, :3] @ np.swapaxes(R, 1, 2)).max() < 1e-4
    # single pose in, single pose out
    assert warp_poses(C, W, BETA, X[0]).shape == (4, 4)


def test_anchored_warp_moves_the_anchor_with_the_field_and_keeps_the_body_rigid(field):
    """A hand frame 15 cm from the surface, anchored at a surface point it grasps."""
    C, W, _ = field
    rng = np.random.default_rng(2)
    anchor = np.array([0.0, 0.03, 0.15])  # grasp centre in the hand frame (m)
    X = np.tile(np.eye(4), (10, 1, 1))
    X[:, :3, :3] = quat_to_matrix(shoemake_quaternions(rng, 10))
    grasped = C[rng.choice(len(C), 10)]
    X[:, :3, 3] = grasped - X[:, :3, :3] @ anchor  # the anchor sits on the surface
    Xw = warp_poses(C, W, BETA, X, anchor=anchor)
    a_w = Xw[:, :3, 3] + Xw[:, :3, :3] @ anchor
    assert np.allclose(a_w, deform_points(C, W, BETA, grasped))  # the anchor follows the surface
    unanchored = warp_poses(C, W, BETA, X)
    # the origin (15 cm away, where the field has died out) would not have followed
    moved = np.linalg.norm(deform_points(C, W, BETA, grasped) - grasped, axis=1)
    miss = np.linalg.norm(unanchored[:, :3, 3] + unanchored[:, :3, :3] @ anchor - a_w, axis=1)
    assert moved.max() > 1e-3 and miss.max() > 0.5 * moved.max()
    back = inverse_warp_poses(C, W, BETA, Xw, anchor=anchor)
    assert np.abs(back[:, :3, 3] - X[:, :3, 3]).max() < 1e-8
    assert rotation_angle(back[:, :3, :3] @ np.swapaxes(X[:, :3, :3], 1, 2)).max() < 1e-7
    with pytest.raises(InputError, match="anchor"):
        warp_poses(C, W, BETA, X, anchor=[0.0, np.nan, 0.0])


def test_local_rotations_recover_a_rigid_rotation_of_the_neighbourhood():
    """Build W so that the canonical points near the origin rotate rigidly by 20 deg about z."""
    from catgrasp_drake.core.deformation import local_rotations
    from catgrasp_drake.core.kernels import gaussian_kernel
    from catgrasp_drake.core.rotations import rotz

    rng = np.random.default_rng(3)
    C = rng.uniform(-0.05, 0.05, size=(150, 3))
    R = rotz(np.radians(20))
    W = np.linalg.solve(gaussian_kernel(C, C, BETA) + 1e-10 * np.eye(len(C)), C @ R.T - C)
    assert np.allclose(deform_points(C, W, BETA, C), C @ R.T, atol=1e-6)
    Rl = local_rotations(C, W, BETA, np.zeros((1, 3)), 0.03)[0]
    assert rotation_angle(Rl @ R.T) < np.radians(0.5)
    X = np.eye(4)
    Xw = warp_poses(C, W, BETA, X, anchor=[0.0, 0.0, 0.0], rotation_radius=0.03)
    assert rotation_angle(Xw[:3, :3] @ R.T) < np.radians(0.5)
    back = inverse_warp_poses(C, W, BETA, Xw, anchor=[0.0, 0.0, 0.0], rotation_radius=0.03)
    assert np.allclose(back, X, atol=1e-8)


def test_bad_inputs(field):
    C, W, _ = field
    with pytest.raises(InputError, match="W"):
        deform_points(C, W[:-1], BETA, C)
    with pytest.raises(InputError, match="beta"):
        deform_points(C, W, 0.0, C)
    with pytest.raises(InputError, match="poses"):
        warp_poses(C, W, BETA, np.eye(3))
    with pytest.raises(InputError, match="NaN"):
        deform_points(C, W, BETA, np.full((2, 3), np.nan))


@pytest.mark.parametrize("n_points", [300, 1500])  # one kernel chunk, and two (deformation._CHUNK = 1024)
def test_the_canonical_self_kernel_is_computed_once_and_changes_no_bit(n_points):
    """local_rotations deforms every canonical point; the (M, M) kernel of C is kept per shape and width, and the
    deformed points are bit for bit deform_points(C, W, beta, C) for any W, before and after the cache is filled."""
    from catgrasp_drake.core import deformation

    rng = np.random.default_rng(n_points)
    C = rng.uniform(-0.08, 0.08, size=(n_points, 3))
    deformation._self_kernel_chunks.cache_clear()
    for _ in range(3):
        W = rng.normal(scale=0.01, size=C.shape)
        assert np.array_equal(deformation._deform_canonical(C, W, BETA), deform_points(C, W, BETA, C))
    info = deformation._self_kernel_chunks.cache_info()
    assert info.misses == 1 and info.hits == 2
    assert len(deformation._self_kernel_chunks(C.tobytes(), C.shape, BETA)) == -(-n_points // deformation._CHUNK)
    # another shape or width is another kernel, not a stale one
    C2 = C.copy()
    C2[0, 0] += 1e-3
    W = rng.normal(scale=0.01, size=C.shape)
    assert np.array_equal(deformation._deform_canonical(C2, W, BETA), deform_points(C2, W, BETA, C2))
    assert np.array_equal(deformation._deform_canonical(C, W, 2 * BETA), deform_points(C, W, 2 * BETA, C))
