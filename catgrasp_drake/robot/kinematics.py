"""Hand forward kinematics without simulation (for filtering sampled grasps).

Mimic joints are set from their leaders with the URDF multipliers/offsets
(what the coupler constraints enforce in simulation).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from pydrake.multibody.plant import MultibodyPlant

from catgrasp_drake.errors import InputError
from catgrasp_drake.robot.models import (
    HAND_ACTUATED_JOINTS,
    HAND_BASE_LINK,
    INDEX_DISTAL_LINK,
    add_hand,
    hand_mimic_joints,
)

#: The index finger's contact pad: the centre of the distal link's capsule, in that link's frame (m).
INDEX_PAD_IN_DISTAL = np.array([0.0075, 0.0, 0.0])


@lru_cache(maxsize=1)
def _hand_plant():
    plant = MultibodyPlant(0.0)
    hand = add_hand(plant)
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(HAND_BASE_LINK, hand))
    plant.Finalize()
    return plant, hand


def hand_link_pose(posture, link: str) -> np.ndarray:
    """Pose X_HL (4x4) of hand link ``link`` in the hand base frame H for a (9,) posture (rad)."""
    q = np.asarray(posture, dtype=float)
    if q.shape != (len(HAND_ACTUATED_JOINTS),) or not np.all(np.isfinite(q)):
        raise InputError(f"posture: expected {len(HAND_ACTUATED_JOINTS)} finite joint angles, got shape {q.shape}")
    plant, hand = _hand_plant()
    context = plant.CreateDefaultContext()
    values = dict(zip(HAND_ACTUATED_JOINTS, q))
    for follower, (leader, multiplier, offset) in hand_mimic_joints().items():
        values[follower] = multiplier * values[leader] + offset
    for name, v in values.items():
        plant.GetJointByName(name, hand).set_angle(context, float(v))
    X_WL = plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(link, hand))
    return X_WL.GetAsMatrix4()


def index_pad_in_hand(posture) -> np.ndarray:
    """Position (3,) of the index finger's distal pad in the hand base frame H for ``posture``."""
    X = hand_link_pose(posture, INDEX_DISTAL_LINK)
    return X[:3, :3] @ INDEX_PAD_IN_DISTAL + X[:3, 3]
