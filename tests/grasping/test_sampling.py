"""Sampling grasp motions around a reference (paper: max 0.04 m, max 0.2 rad)."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.rotations import rotation_angle
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.sampling import SamplingParams, perturb_poses, perturbations


def test_perturbations_respect_the_paper_limits_and_fill_them():
    T = perturbations(np.random.default_rng(0), 2000)
    t = np.linalg.norm(T[:, :3, 3], axis=1)
    a = rotation_angle(T[:, :3, :3])
    assert t.max() <= 0.04 + 1e-12 and a.max() <= 0.2 + 1e-9
    assert t.max() > 0.035 and a.max() > 0.19  # the whole range is used
    # components are centred normals with the requested spread (truncation barely bites at 0.04)
    assert np.abs(T[:, :3, 3].mean(axis=0)).max() < 0.001
    assert T[:, :3, 3].std(axis=0) == pytest.approx([0.015] * 3, rel=0.1)
    # uniform rotations restricted to a ball: P(angle <= a) ∝ (a - sin a) for small balls
    frac_half = np.mean(a <= 0.1)
    expected = (0.1 - np.sin(0.1)) / (0.2 - np.sin(0.2))
    assert frac_half == pytest.approx(expected, abs=0.04)


def test_perturbation_is_seeded():
    a = perturbations(np.random.default_rng(7), 5)
    b = perturbations(np.random.default_rng(7), 5)
    assert np.array_equal(a, b)


def test_perturbing_about_the_grasp_moves_the_grasp_by_the_translation_only():
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[0, :3, 3] = [0.0, -0.1, 0.1]  # pregrasp
    poses[1, :3, 3] = [0.0, -0.05, 0.1]  # grasp
    T = perturbations(np.random.default_rng(1), 1)[0]
    out = perturb_poses(poses, T, pivot=poses[1, :3, 3])
    assert np.allclose(out[1, :3, 3], poses[1, :3, 3] + T[:3, 3])
    # the pregrasp keeps its distance to the grasp (one rigid motion for the whole sequence)
    assert np.linalg.norm(out[0, :3, 3] - out[1, :3, 3]) == pytest.approx(0.05)
    assert np.allclose(out[1, :3, :3], T[:3, :3])


def test_bad_parameters():
    with pytest.raises(InputError):
        SamplingParams(max_rotation=-0.1)
