"""The robots' name and gain tables the runtime needs (the model generators in ``tools/`` write them into the URDFs).

``tools/svh_model.py`` and ``tools/ur10_model.py`` generate ``models/svh`` and
``models/ur10`` from these tables and the vendor / DH data; the runtime
(:mod:`catgrasp_drake.robot.models`) reads the same tables to name joints and
links and to set the PD gains on the parsed models, so the two cannot drift.
"""

from __future__ import annotations

# ----------------------------------------------------------------------------- SVH hand
#: Vendor link (one with a moving or no parent joint) -> project link name.
SVH_LINK_NAMES: dict[str, str] = {
    "base_link": "svh_base_link",
    "right_hand_z": "svh_thumb_base_link",
    "right_hand_a": "svh_thumb_proximal_link",
    "right_hand_b": "svh_thumb_middle_link",
    "right_hand_c": "svh_thumb_distal_link",
    "right_hand_e2": "svh_palm_flex_link",
    "right_hand_virtual_l": "svh_index_knuckle_link",
    "right_hand_l": "svh_index_proximal_link",
    "right_hand_p": "svh_index_middle_link",
    "right_hand_t": "svh_index_distal_link",
    "right_hand_k": "svh_middle_proximal_link",
    "right_hand_o": "svh_middle_middle_link",
    "right_hand_s": "svh_middle_distal_link",
    "right_hand_virtual_j": "svh_ring_knuckle_link",
    "right_hand_j": "svh_ring_proximal_link",
    "right_hand_n": "svh_ring_middle_link",
    "right_hand_r": "svh_ring_distal_link",
    "right_hand_virtual_i": "svh_pinky_knuckle_link",
    "right_hand_i": "svh_pinky_proximal_link",
    "right_hand_m": "svh_pinky_middle_link",
    "right_hand_q": "svh_pinky_distal_link",
}

#: Vendor joint -> project joint name (the 9 actuated joints first, in actuation order).
SVH_JOINT_NAMES: dict[str, str] = {
    "right_hand_Thumb_Flexion": "svh_thumb_flexion",
    "right_hand_Thumb_Opposition": "svh_thumb_opposition",
    "right_hand_Index_Finger_Proximal": "svh_index_proximal",
    "right_hand_Index_Finger_Distal": "svh_index_distal",
    "right_hand_Middle_Finger_Proximal": "svh_middle_proximal",
    "right_hand_Middle_Finger_Distal": "svh_middle_distal",
    "right_hand_Ring_Finger": "svh_ring",
    "right_hand_Pinky": "svh_pinky",
    "right_hand_Finger_Spread": "svh_finger_spread",
    "right_hand_j3": "svh_thumb_j3",
    "right_hand_j4": "svh_thumb_j4",
    "right_hand_j5": "svh_palm_j5",
    "right_hand_j12": "svh_ring_j12",
    "right_hand_j13": "svh_pinky_j13",
    "right_hand_j14": "svh_index_j14",
    "right_hand_j15": "svh_middle_j15",
    "right_hand_j16": "svh_ring_j16",
    "right_hand_j17": "svh_pinky_j17",
    "right_hand_index_spread": "svh_index_spread",
    "right_hand_ring_spread": "svh_ring_spread",
}

#: The 9 actuated hand joints, in actuation order.
SVH_ACTUATED_JOINTS: tuple[str, ...] = tuple(list(SVH_JOINT_NAMES.values())[:9])

#: (PD proportional gain [N m/rad], derivative gain [N m s/rad], effort limit [N m]) per actuated joint.
#: Kd/Kp = 0.15 s: a first-order closing time constant of ~0.15 s while the torque is
#: below the limit, so a posture step closes in ~0.5 s; Kp·0.3 rad reaches the effort
#: limit, so commanding "closed" ~0.3 rad beyond contact squeezes with the full limit.
SVH_ACTUATOR_GAINS: dict[str, tuple[float, float, float]] = {
    "svh_thumb_flexion": (12.0, 1.8, 3.5),
    "svh_thumb_opposition": (12.0, 1.8, 3.5),
    "svh_index_proximal": (10.0, 1.5, 3.0),
    "svh_index_distal": (7.0, 1.05, 2.0),
    "svh_middle_proximal": (10.0, 1.5, 3.0),
    "svh_middle_distal": (7.0, 1.05, 2.0),
    "svh_ring": (10.0, 1.5, 3.0),
    "svh_pinky": (10.0, 1.5, 3.0),
    "svh_finger_spread": (6.0, 0.9, 1.5),
}


# ----------------------------------------------------------------------------- UR10 arm
UR10_LINK_NAMES: tuple[str, ...] = (
    "ur10_base_link",
    "ur10_shoulder_link",
    "ur10_upper_arm_link",
    "ur10_forearm_link",
    "ur10_wrist_1_link",
    "ur10_wrist_2_link",
    "ur10_wrist_3_link",
)
UR10_JOINT_NAMES: tuple[str, ...] = (
    "ur10_shoulder_pan_joint",
    "ur10_shoulder_lift_joint",
    "ur10_elbow_joint",
    "ur10_wrist_1_joint",
    "ur10_wrist_2_joint",
    "ur10_wrist_3_joint",
)

#: (Kp [N m/rad], Kd [N m s/rad], effort limit [N m]) per joint. Stiff position servos (Drake's
#: SAP treats the PD implicitly, so these are stable at 5 ms steps): the static error from
#: gravity with a 1.5 kg object in the hand stays below ~2 mrad without feed-forward. Effort
#: limits: UR10 data sheet (330 N m size-4 joints, 150 N m size-3, 56 N m wrists).
UR10_ACTUATOR_GAINS: dict[str, tuple[float, float, float]] = {
    "ur10_shoulder_pan_joint": (1.0e5, 2.5e3, 330.0),
    "ur10_shoulder_lift_joint": (1.0e5, 2.5e3, 330.0),
    "ur10_elbow_joint": (5.0e4, 1.0e3, 150.0),
    "ur10_wrist_1_joint": (5.0e3, 60.0, 56.0),
    "ur10_wrist_2_joint": (5.0e3, 60.0, 56.0),
    "ur10_wrist_3_joint": (2.0e3, 20.0, 56.0),
}
