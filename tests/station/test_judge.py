"""The success judge on synthetic contact data (no simulation)."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.station.judge import (
    ContactRecord,
    JudgeSpec,
    Snapshot,
    judge,
    points_in_region,
    tilt_deg,
)

TRIGGER = {"center": [0.0, 0.005, 0.12], "half_extents": [0.01, 0.009, 0.015]}
HANDLE = {"center": [0.0, 0.06, 0.05], "half_extents": [0.01, 0.02, 0.03]}


def _X(p=(0.65, 0.0, 0.0), yaw=0.0, roll=0.0):
    c, s = np.cos(yaw), np.sin(yaw)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    cr, sr = np.cos(roll), np.sin(roll)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    X = np.eye(4)
    X[:3, :3] = Rz @ Rx
    X[:3, 3] = p
    return X


def _spec(category="drill", regions=None):
    return JudgeSpec(object_model="drill_00", hand_model="svh", arm_model="ur10", table_model="table",
                     index_distal_body="svh::svh_index_distal_link", category=category,
                     regions=regions if regions is not None else {"trigger": TRIGGER}, lift_height=0.12)


def _c(a, b, *pts, force=1.0):
    return ContactRecord(a, b, tuple(tuple(map(float, p)) for p in pts), force)


X0 = _X()
X_LIFT = _X((0.65, 0.0, 0.12))
P_TRIGGER_W = np.array([0.65, 0.005, 0.24])  # trigger centre after a 12 cm lift
ON_TABLE = (_c("drill_00::body", "table::top", (0.65, 0, 0)),)
HELD = (
    _c("drill_00::body", "svh::svh_index_distal_link", P_TRIGGER_W),
    _c("drill_00::body", "svh::svh_thumb_distal_link", (0.66, -0.03, 0.22)),
)


def _snaps(before=ON_TABLE, X_before=X0, X_after=X_LIFT, end=HELD, X_end=X_LIFT):
    return (Snapshot(0.0, X0, ON_TABLE), Snapshot(2.0, X_before, before),
            Snapshot(4.0, X_after, ()), Snapshot(6.0, X_end, end))


def test_functional_success():
    v = judge(_spec(), *_snaps())
    assert v.grasp_success and v.functional_success and v.failure_reason is None
    assert v.object_rise_m == pytest.approx(0.12)


def test_trigger_missed():
    end = (_c("drill_00::body", "svh::svh_index_distal_link", (0.65, -0.06, 0.20)), HELD[1])
    v = judge(_spec(), *_snaps(end=end))
    assert v.grasp_success and not v.functional_success and v.failure_reason == "trigger_missed"


def test_trigger_margin():
    # 3 mm outside the box in y: inside with the 5 mm margin, outside with none
    p = P_TRIGGER_W + [0, 0.009 + 0.003, 0]
    end = (_c("drill_00::body", "svh::svh_index_distal_link", p), HELD[1])
    assert judge(_spec(), *_snaps(end=end)).functional_success
    spec0 = JudgeSpec(**{**_spec().__dict__, "region_margin": 0.0})
    assert judge(spec0, *_snaps(end=end)).failure_reason == "trigger_missed"


def test_other_finger_on_trigger_does_not_count():
    end = (_c("drill_00::body", "svh::svh_middle_distal_link", P_TRIGGER_W), HELD[1])
    assert judge(_spec(), *_snaps(end=end)).failure_reason == "trigger_missed"


def test_collision_before_closing_table():
    before = ON_TABLE + (_c("svh::svh_pinky_distal_link", "table::top", (0.6, 0, 0)),)
    v = judge(_spec(), *_snaps(before=before))
    assert v.failure_reason == "collision_before_closing" and "pinky" in v.detail


def test_collision_before_closing_push():
    v = judge(_spec(), *_snaps(X_before=_X((0.70, 0.0, 0.0))))
    assert v.failure_reason == "collision_before_closing" and "pushed" in v.detail


def test_tipped_before_closing_fails_but_turn_about_vertical_does_not():
    v = judge(_spec(), *_snaps(X_before=_X(roll=np.radians(35))))
    assert v.failure_reason == "collision_before_closing" and "tipped 35 deg" in v.detail
    v = judge(_spec(), *_snaps(X_before=_X(roll=np.radians(15))))  # nudged, then held: the outcome decides
    assert v.functional_success
    # brushed round 25 deg on the table, then grasped and held: judged by the outcome
    v = judge(_spec(), *_snaps(X_before=_X(yaw=np.radians(25))))
    assert v.grasp_success and v.functional_success


def test_dropped_and_not_lifted():
    v = judge(_spec(), *_snaps(end=ON_TABLE, X_end=X0))
    assert v.failure_reason == "dropped" and not v.grasp_success
    v = judge(_spec(), *_snaps(X_after=X0, end=ON_TABLE, X_end=X0))
    assert v.failure_reason == "not_lifted"
    v = judge(_spec(), *_snaps(X_after=_X((0.65, 0, 0.01)), end=ON_TABLE + HELD, X_end=_X((0.65, 0, 0.01))))
    assert v.failure_reason == "not_lifted"


def test_slipped():
    v = judge(_spec(), *_snaps(end=ON_TABLE + HELD, X_end=X0))
    assert v.failure_reason == "slipped"
    v = judge(_spec(), *_snaps(end=HELD, X_end=_X((0.65, 0, 0.03))))
    assert v.failure_reason == "slipped"


def test_touched_other():
    end = HELD + (_c("drill_00::body", "ur10::ur10_wrist_3_link", (0.6, 0, 0.3)),)
    v = judge(_spec(), *_snaps(end=end))
    assert v.failure_reason == "touched_other" and "ur10" in v.detail


def test_mug_rules():
    spec = JudgeSpec(**{**_spec("mug", {"handle": HANDLE}).__dict__, "object_model": "drill_00"})
    p_handle = np.array([0.65, 0.06, 0.05 + 0.12])
    end = (_c("drill_00::body", "svh::svh_middle_distal_link", p_handle),)
    assert judge(spec, *_snaps(end=end)).functional_success
    off = (_c("drill_00::body", "svh::svh_middle_distal_link", (0.65, -0.05, 0.2)),)
    assert judge(spec, *_snaps(end=off)).failure_reason == "handle_missed"
    X_tilt = _X((0.65, 0.0, 0.12), roll=np.radians(30))
    v = judge(spec, *_snaps(end=end, X_end=X_tilt))
    assert v.grasp_success and v.failure_reason == "tilted"


def test_primitive_object_has_no_functional_rule():
    spec = JudgeSpec(**{**_spec(None, {}).__dict__})
    assert judge(spec, *_snaps(end=HELD[1:])).functional_success


def test_region_and_tilt_helpers():
    X = _X((1.0, 2.0, 3.0), yaw=np.pi / 2)
    p = X[:3, :3] @ np.array(TRIGGER["center"]) + X[:3, 3]
    assert points_in_region([p], X, TRIGGER, 0.0).tolist() == [True]
    assert points_in_region([p + [0.5, 0, 0]], X, TRIGGER, 0.0).tolist() == [False]
    assert tilt_deg(_X(), _X(roll=np.radians(20))) == pytest.approx(20.0)


def test_missing_functional_region_is_an_outcome_not_an_exception():
    v = judge(_spec(regions={}), *_snaps())
    assert v.grasp_success and not v.functional_success and v.failure_reason == "no_functional_region"
