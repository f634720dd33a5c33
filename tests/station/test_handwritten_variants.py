"""``diagrams/handwritten_sweep.py --shift/--rotate`` (``station.handwritten.shifted_motion``): a variant of a
hand-written grasp is a rigid motion of the whole grasp about the anchor region's centre (known answers, no
simulation)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from catgrasp_drake.data.dataset import load_annotations
from catgrasp_drake.station.handwritten import load_handwritten_motion, shifted_motion


def test_no_variant_is_the_identity():
    motion = load_handwritten_motion("spray_bottle", "spray_bottle_04")
    same = shifted_motion(motion, "spray_bottle", "spray_bottle_04", (0, 0, 0), (0, 0, 0))
    np.testing.assert_allclose(same.poses, motion.poses, atol=1e-15)


def test_a_variant_turns_the_grasp_about_the_trigger_then_shifts_it():
    motion = load_handwritten_motion("drill", "drill_05")
    centre = np.asarray(load_annotations("drill", "drill_05")["regions"]["trigger"]["center"])
    shift, angles = np.array([0.01, -0.02, 0.005]), (5.0, -25.0, 10.0)
    v = shifted_motion(motion, "drill", "drill_05", shift, angles)
    R = Rotation.from_euler("xyz", angles, degrees=True).as_matrix()
    for X, Y in zip(motion.poses, v.poses):
        np.testing.assert_allclose(Y[:3, :3], R @ X[:3, :3], atol=1e-12)
        # the trigger centre, seen from the hand, has moved by the shift only
        np.testing.assert_allclose(Y[:3, 3] - (R @ (X[:3, 3] - centre) + centre), shift, atol=1e-12)
    assert v.pose_names == motion.pose_names and v.frame == "object"
