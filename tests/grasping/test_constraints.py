"""Functional constraints reject known bad orientations and keep good ones."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.constraints import box_distance, load_constraint

TRIGGER = {"trigger": {"center": [0.0, 0.02, 0.12], "half_extents": [0.01, 0.01, 0.015]}}


def _pose(R=np.eye(3), p=(0.0, 0.0, 0.0)):
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = R, p
    return X


def test_box_distance():
    r = TRIGGER["trigger"]
    assert box_distance([0.0, 0.02, 0.12], r) == 0.0
    assert box_distance([0.0, 0.05, 0.12], r) == pytest.approx(0.02)
    assert box_distance([0.02, 0.05, 0.12], r) == pytest.approx(np.hypot(0.01, 0.02))


def test_trigger_rule_keeps_the_reference_and_rejects_rotations_that_miss_the_trigger():
    c = load_constraint("drill")
    # reference: the index tip (0.1 m along H +z) lands on the trigger centre
    tip_H = np.array([0.0, 0.0, 0.1])
    ref = _pose(Rotation.from_euler("x", -90, degrees=True).as_matrix())  # H +z -> O +y
    ref[:3, 3] = np.array([0.0, 0.02, 0.12]) - ref[:3, :3] @ tip_H
    assert c.check(ref, ref, TRIGGER, tip_H) == (True, "")
    # turning the hand 25 degrees about the grasp's vertical swings the tip 4 cm sideways: rejected
    turn = _pose(Rotation.from_euler("z", 25, degrees=True).as_matrix())
    bad = ref.copy()
    bad[:3, :3] = turn[:3, :3] @ ref[:3, :3]
    ok, reason = c.check(bad, ref, TRIGGER, tip_H)
    assert not ok and "index tip" in reason
    # a small 3 degree turn is kept
    small = ref.copy()
    small[:3, :3] = Rotation.from_euler("z", 3, degrees=True).as_matrix() @ ref[:3, :3]
    assert c.check(small, ref, TRIGGER, tip_H)[0]


def test_upright_rule_rejects_tilting_a_mug():
    c = load_constraint("mug")
    ref = _pose()
    tilted = _pose(Rotation.from_euler("y", 12, degrees=True).as_matrix())
    spun = _pose(Rotation.from_euler("z", 11, degrees=True).as_matrix())  # about the vertical: fine
    assert not c.check(tilted, ref, {}, None)[0]
    assert c.check(spun, ref, {}, None)[0]


def test_unknown_category():
    with pytest.raises(InputError, match="known: drill, mug, spray_bottle"):
        load_constraint("teapot")
