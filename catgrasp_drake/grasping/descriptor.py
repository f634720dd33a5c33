"""Fixed-length grasp descriptor ς for regression (paper, section III-D).

The readable record is :class:`~catgrasp_drake.grasping.motion.GraspMotion`;
this module flattens it into a vector and back:

    [ for each control pose (in the template's order):  p (3), R[:, 0] (3), R[:, 1] (3) ]
    [ for each regressed posture ("preshape", "closed"): q (9) ]

Rotations use the continuous 6-D representation (the first two columns of R),
which is linear-regression friendly; :func:`motion_from_descriptor` maps any
6-D vector back to a proper rotation by Gram-Schmidt (x = a/|a|, z ∥ x × b,
y = z × x). The ``open`` posture and the lift/hold parameters are not
regressed: they come from the template motion.
"""

from __future__ import annotations

import numpy as np

from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import NUM_HAND_JOINTS, GraspMotion

REGRESSED_POSTURES = ("preshape", "closed")
_POSE_SIZE = 9


def descriptor_size(num_poses: int, num_postures: int = len(REGRESSED_POSTURES)) -> int:
    return num_poses * _POSE_SIZE + num_postures * NUM_HAND_JOINTS


def descriptor_vector(motion: GraspMotion) -> np.ndarray:
    """The motion's descriptor (frame as in ``motion.frame``)."""
    parts = []
    for X in motion.poses:
        parts += [X[:3, 3], X[:3, 0], X[:3, 1]]
    parts += [motion.posture(name) for name in REGRESSED_POSTURES]
    return np.concatenate(parts)


def rotation_from_6d(a, b) -> np.ndarray:
    """Proper rotation whose first column is ``a/|a|`` and second lies in span(a, b)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    na = np.linalg.norm(a)
    if na < 1e-9:
        raise InputError("descriptor: degenerate rotation (zero first column)")
    x = a / na
    z = np.cross(x, b)
    nz = np.linalg.norm(z)
    if nz < 1e-9:
        raise InputError("descriptor: degenerate rotation (parallel columns)")
    z /= nz
    return np.column_stack([x, np.cross(z, x), z])


def motion_from_descriptor(vector, template: GraspMotion) -> GraspMotion:
    """Rebuild a motion in ``template.frame`` from a descriptor vector."""
    v = np.asarray(vector, dtype=float)
    K = len(template.poses)
    if v.shape != (descriptor_size(K),):
        raise InputError(f"descriptor: expected {descriptor_size(K)} values for {K} poses, got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise InputError("descriptor: contains NaN or inf")
    poses = np.tile(np.eye(4), (K, 1, 1))
    for k in range(K):
        p, a, b = v[9 * k: 9 * k + 3], v[9 * k + 3: 9 * k + 6], v[9 * k + 6: 9 * k + 9]
        poses[k, :3, :3] = rotation_from_6d(a, b)
        poses[k, :3, 3] = p
    postures = dict(template.postures)
    off = 9 * K
    for i, name in enumerate(REGRESSED_POSTURES):
        postures[name] = v[off + i * NUM_HAND_JOINTS: off + (i + 1) * NUM_HAND_JOINTS]
    return GraspMotion(poses, template.pose_names, postures, template.frame, template.lift_height, template.hold_time)


def motion_functional_point(motion: GraspMotion, anchor_H) -> np.ndarray:
    """The grasp's functional point (``anchor_H``: m, hand frame -- the trigger or handle centre carried by
    the hand; None: the hand frame's origin) in the motion's frame, at the ``grasp`` control pose (m)."""
    P = motion.pose("grasp")
    a = np.zeros(3) if anchor_H is None else np.asarray(anchor_H, float)
    return P[:3, :3] @ a + P[:3, 3]


def functional_point(vector, template: GraspMotion, anchor_H) -> np.ndarray:
    """:func:`motion_functional_point` of the descriptor ``vector`` (the descriptor's frame, m)."""
    return motion_functional_point(motion_from_descriptor(vector, template), anchor_H)
