"""Sampling grasping motions around a reference motion (paper, section III-D).

A sampled motion is the reference motion moved by one random rigid
perturbation about its grasp control pose, so pre-grasp and grasp stay
consistent: translation with each component ~ N(0, std), resampled until its
norm is <= ``max_translation`` (0.04 m in the paper), and a rotation from
Shoemake's uniform quaternions kept when its angle is <= ``max_rotation``
(0.2 rad). Perturbations are expressed in the object frame and applied about
the grasp position: X' = T(p_g + dt) R T(-p_g) X.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catgrasp_drake.core.rotations import sample_rotations_within
from catgrasp_drake.errors import InputError


@dataclass(frozen=True)
class SamplingParams:
    """Perturbation ranges (metres, radians); the paper's maxima by default."""

    translation_std: float = 0.015
    max_translation: float = 0.04
    max_rotation: float = 0.2

    def __post_init__(self):
        if not (self.translation_std >= 0 and self.max_translation >= 0 and 0 <= self.max_rotation <= np.pi):
            raise InputError(f"sampling parameters out of range: {self}")


def sample_translations(rng: np.random.Generator, n: int, std: float, max_norm: float) -> np.ndarray:
    """``n`` translations with components ~ N(0, std), norms <= max_norm (rejection)."""
    out = np.zeros((0, 3))
    if std == 0 or max_norm == 0:
        return np.zeros((n, 3))
    while len(out) < n:
        t = rng.normal(0.0, std, size=(2 * (n - len(out)) + 8, 3))
        out = np.vstack([out, t[np.linalg.norm(t, axis=1) <= max_norm]])
    return out[:n]


def perturbations(rng: np.random.Generator, n: int, params: SamplingParams = SamplingParams()) -> np.ndarray:
    """``n`` perturbations as (n, 4, 4) homogeneous transforms (rotation part, translation part)."""
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = sample_rotations_within(rng, n, params.max_rotation)
    T[:, :3, 3] = sample_translations(rng, n, params.translation_std, params.max_translation)
    return T


def perturb_poses(poses: np.ndarray, perturbation: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """Apply one perturbation (4x4) about ``pivot`` (3,) to control poses (K, 4, 4), object frame."""
    P = np.eye(4)
    P[:3, 3] = pivot
    Pinv = np.eye(4)
    Pinv[:3, 3] = -pivot
    return P @ perturbation @ Pinv @ poses
