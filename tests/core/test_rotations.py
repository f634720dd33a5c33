"""Rotations: orthonormalisation, quaternions, uniform and bounded sampling."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.rotations import (
    matrix_to_quat,
    orthonormalize,
    quat_to_matrix,
    rotation_angle,
    rotz,
    sample_rotations_within,
    shoemake_quaternions,
)
from catgrasp_drake.errors import InputError


def test_orthonormalize_gives_nearest_proper_rotation():
    rng = np.random.default_rng(0)
    R = quat_to_matrix(shoemake_quaternions(rng, 50))
    noisy = R + rng.normal(scale=0.05, size=R.shape)
    out = orthonormalize(noisy)
    assert np.allclose(out @ np.swapaxes(out, 1, 2), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(out), 1.0)
    assert np.all(rotation_angle(out @ np.swapaxes(R, 1, 2)) < 0.2)
    # a reflection becomes a proper rotation
    refl = np.diag([1.0, 1.0, -1.0])
    assert np.isclose(np.linalg.det(orthonormalize(refl)), 1.0)
    assert np.allclose(orthonormalize(R[0]), R[0])


def test_quaternion_round_trip_and_convention():
    rng = np.random.default_rng(1)
    q = shoemake_quaternions(rng, 200)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0) and np.all(q[:, 0] >= 0)
    assert np.allclose(matrix_to_quat(quat_to_matrix(q)), q, atol=1e-12)
    # (w, x, y, z): 90 deg about z
    assert np.allclose(quat_to_matrix([np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]), rotz(np.pi / 2), atol=1e-12)
    # 180 deg rotations (w = 0) survive the round trip
    R = np.diag([1.0, -1.0, -1.0])
    assert np.allclose(quat_to_matrix(matrix_to_quat(R)), R, atol=1e-12)


def test_shoemake_is_uniform():
    q = shoemake_quaternions(np.random.default_rng(2), 20000)
    R = quat_to_matrix(q)
    assert np.abs(R.mean(axis=0)).max() < 0.02  # E[R] = 0 under the Haar measure
    ang = rotation_angle(R)
    # Haar angle CDF: (t - sin t) / pi
    for t in (0.5, 1.5, 2.5):
        assert abs((ang <= t).mean() - (t - np.sin(t)) / np.pi) < 0.015


@pytest.mark.parametrize("max_angle", [0.2, 0.02, 1.0])
def test_sample_rotations_within(max_angle):
    R = sample_rotations_within(np.random.default_rng(3), 2000, max_angle)
    assert R.shape == (2000, 3, 3)
    assert np.allclose(np.linalg.det(R), 1.0)
    ang = rotation_angle(R)
    assert ang.max() <= max_angle + 1e-9
    # conditional Haar CDF within the ball: (t - sin t) / (a - sin a)
    t = 0.7 * max_angle
    expected = (t - np.sin(t)) / (max_angle - np.sin(max_angle))
    assert abs((ang <= t).mean() - expected) < 0.04


def test_seeded_and_deterministic():
    a = sample_rotations_within(np.random.default_rng(5), 10, 0.2)
    b = sample_rotations_within(5, 10, 0.2)
    assert np.array_equal(a, b)


def test_rotz_batch_and_errors():
    assert rotz([0.0, 1.0]).shape == (2, 3, 3)
    assert np.allclose(rotz(0.3) @ [1, 0, 0], [np.cos(0.3), np.sin(0.3), 0])
    with pytest.raises(InputError):
        orthonormalize(np.ones((2, 2)))
    with pytest.raises(InputError):
        sample_rotations_within(0, 3, -1.0)
    with pytest.raises(InputError):
        quat_to_matrix([0, 0, 0, 0])
