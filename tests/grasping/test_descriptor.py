"""Grasp descriptor vector <-> GraspMotion."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.descriptor import descriptor_size, descriptor_vector, motion_from_descriptor
from catgrasp_drake.grasping.motion import GraspMotion


def _motion(seed=0) -> GraspMotion:
    rng = np.random.default_rng(seed)
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[:, :3, :3] = Rotation.random(2, random_state=seed).as_matrix()
    poses[:, :3, 3] = rng.normal(size=(2, 3)) * 0.1
    postures = {k: rng.uniform(0, 1, 9) for k in ("open", "preshape", "closed")}
    return GraspMotion(poses, ("pregrasp", "grasp"), postures)


def test_round_trip_is_exact():
    m = _motion()
    v = descriptor_vector(m)
    assert v.shape == (descriptor_size(2),) == (36,)
    back = motion_from_descriptor(v, m)
    assert np.allclose(back.poses, m.poses) and np.allclose(back.posture("closed"), m.posture("closed"))
    assert np.array_equal(back.posture("open"), m.posture("open"))


def test_a_perturbed_vector_still_gives_proper_rotations():
    m = _motion(1)
    v = descriptor_vector(m) + np.random.default_rng(2).normal(scale=0.2, size=36)
    back = motion_from_descriptor(v, m)
    for X in back.poses:
        R = X[:3, :3]
        assert np.allclose(R.T @ R, np.eye(3), atol=1e-9) and np.linalg.det(R) == pytest.approx(1.0)


def test_averaging_descriptors_averages_poses():
    # the mean of two descriptors of rotations about z by +-a gives the identity rotation
    m = _motion()
    a, b = m.poses.copy(), m.poses.copy()
    for P, s in ((a, 1), (b, -1)):
        P[:, :3, :3] = Rotation.from_euler("z", s * 0.3).as_matrix()
    va = descriptor_vector(GraspMotion(a, m.pose_names, dict(m.postures)))
    vb = descriptor_vector(GraspMotion(b, m.pose_names, dict(m.postures)))
    mean = motion_from_descriptor((va + vb) / 2, m)
    assert np.allclose(mean.poses[0, :3, :3], np.eye(3), atol=1e-9)


def test_bad_vectors():
    m = _motion()
    with pytest.raises(InputError, match="expected 36"):
        motion_from_descriptor(np.zeros(10), m)
    with pytest.raises(InputError, match="degenerate"):
        motion_from_descriptor(np.zeros(36), m)
