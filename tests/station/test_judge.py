"""The success judge on synthetic contact data (no simulation), with known answers."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from catgrasp_drake.errors import InputError
from catgrasp_drake.station.judge import (
    ContactRecord,
    FirstMove,
    JudgeSpec,
    Snapshot,
    decided_failure,
    in_hand_motion,
    judge,
    points_in_region,
    region_grown_by,
    tilt_deg,
)

# annotated boxes as the generator writes them: the trigger's bounding box grown by 4 mm, the handle's by 3 mm
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


def _c(a, b, *pts, force=1.0, on_a=None):
    return ContactRecord(a, b, tuple(tuple(map(float, p)) for p in pts), force, "hydroelastic",
                         None if on_a is None else tuple(map(float, on_a)))


X0 = _X()
X_LIFT = _X((0.65, 0.0, 0.12))
X_OH = _X((0.05, -0.12, 0.10), yaw=0.3)  # the hand base in the object frame while held
P_TRIGGER_W = np.array([0.65, 0.005, 0.24])  # trigger centre after a 12 cm lift
ON_TABLE = (_c("drill_00::body", "table::top", (0.65, 0, 0)),)
THUMB = _c("drill_00::body", "svh::svh_thumb_distal_link", (0.66, -0.03, 0.22), on_a=(0, 0, 10))


def _index(p=P_TRIGGER_W, on_object=(0.0, -8.0, 0.0)):
    """The index distal link touching the object at ``p`` (world), force ``on_object`` (N, W) on the object."""
    return _c("drill_00::body", "svh::svh_index_distal_link", p, force=float(np.linalg.norm(on_object)),
              on_a=on_object)


HELD = (_index(), THUMB)


def _snaps(before=ON_TABLE, X_before=X0, X_after=X_LIFT, hold=None, X_hold=None, shake=None, X_shake=None,
           end=HELD, X_end=None, X_hand=None):
    """initial, before_close, after_lift, after_hold, after_shake, end (contacts at the end of the hold and
    of the shake: HELD unless given). The hand base stays where it holds the object at the end of the
    lift (``X_hand``, default X_after X_OH); the object stays there unless moved."""
    X_WH = X_hand if X_hand is not None else X_after @ X_OH
    hold = HELD if hold is None else hold
    shake = HELD if shake is None else shake
    X_hold = X_after if X_hold is None else X_hold
    X_shake = X_after if X_shake is None else X_shake
    X_end = X_after if X_end is None else X_end
    return (Snapshot(0.0, X0, ON_TABLE), Snapshot(2.0, X_before, before), Snapshot(4.0, X_after, hold, X_WH),
            Snapshot(6.0, X_hold, hold, X_WH), Snapshot(7.0, X_shake, shake, X_WH), Snapshot(7.5, X_end, end, X_WH))


def test_functional_success():
    v = judge(_spec(), *_snaps())
    assert v.grasp_success and v.functional_success and v.failure_reason is None
    assert v.object_rise_m == pytest.approx(0.12)
    assert v.trigger_force_N == pytest.approx(8.0)
    assert v.in_hand_shift_m == pytest.approx(0.0, abs=1e-12) and v.in_hand_turn_deg == pytest.approx(0.0, abs=1e-6)


# ----------------------------------------------------------------------------- the trigger: its own surface
def test_index_5mm_beside_the_trigger_is_not_functional():
    """5 mm behind the trigger's own back face: inside the old judge's box (annotated + 5 mm), outside the
    trigger's surface + 2 mm (annotated - 4 mm + 2 mm)."""
    own_half_y = TRIGGER["half_extents"][1] - 0.004
    p = P_TRIGGER_W - [0, own_half_y + 0.005, 0]
    assert points_in_region([p], X_LIFT, TRIGGER, 0.005).all()  # the old rule called this functional
    v = judge(_spec(), *_snaps(end=(_index(p), THUMB)))
    assert v.grasp_success and not v.functional_success and v.failure_reason == "trigger_missed"
    assert math.isnan(v.trigger_force_N) and "5.0 mm from the trigger" in v.detail
    assert "outside its box by y -5.0 mm, object frame" in v.detail  # where: behind it, along -y of O


def test_the_miss_detail_gives_the_direction_in_the_object_frame():
    """The object turned 90 deg about z: a point 3 mm above and 4 mm in front (+y of O, -x of W) of the
    trigger's own box is reported along the object's axes."""
    X = _X((0.65, 0.0, 0.12), yaw=math.pi / 2)
    c, h = np.array(TRIGGER["center"]), np.array(TRIGGER["half_extents"]) - 0.004
    p_O = c + [0.0, h[1] + 0.004, h[2] + 0.003]
    p_W = X[:3, :3] @ p_O + X[:3, 3]
    v = judge(_spec(), *_snaps(X_after=X, end=(_index(p_W), THUMB)))
    assert v.failure_reason == "trigger_missed"
    assert "5.0 mm from the trigger" in v.detail and "by y +4.0 z +3.0 mm" in v.detail


def test_index_on_the_trigger_surface_within_2mm_counts():
    own_half_y = TRIGGER["half_extents"][1] - 0.004
    inside = P_TRIGGER_W - [0, own_half_y + 0.0015, 0]  # 1.5 mm off the trigger's face
    outside = P_TRIGGER_W - [0, own_half_y + 0.0025, 0]  # 2.5 mm off
    assert judge(_spec(), *_snaps(end=(_index(inside), THUMB))).functional_success
    assert judge(_spec(), *_snaps(end=(_index(outside), THUMB))).failure_reason == "trigger_missed"


def test_weak_press_is_trigger_not_pressed():
    v = judge(_spec(), *_snaps(end=(_index(on_object=(0, -2.0, 0)), THUMB)))
    assert v.grasp_success and not v.functional_success and v.failure_reason == "trigger_not_pressed"
    assert v.trigger_force_N == pytest.approx(2.0) and "2.00 N" in v.detail


def test_press_across_the_travel_is_trigger_not_pressed():
    v = judge(_spec(), *_snaps(end=(_index(on_object=(8.0, 0, 0)), THUMB)))
    assert v.failure_reason == "trigger_not_pressed" and v.trigger_force_N == pytest.approx(0.0, abs=1e-12)
    v = judge(_spec(), *_snaps(end=(_index(on_object=(0, +8.0, 0)), THUMB)))  # pulling the trigger forward
    assert v.failure_reason == "trigger_not_pressed" and v.trigger_force_N == pytest.approx(-8.0)


def test_travel_direction_is_in_the_object_frame_and_can_be_overridden():
    # object turned 90 deg about z: -y_O is +x_W
    X_turned = _X((0.65, 0.0, 0.12), yaw=np.pi / 2)
    p = X_turned[:3, :3] @ np.array(TRIGGER["center"]) + X_turned[:3, 3]
    v = judge(_spec(), *_snaps(X_after=X_turned, end=(_index(p, on_object=(8.0, 0, 0)), THUMB)))
    assert v.functional_success and v.trigger_force_N == pytest.approx(8.0)
    spec = _spec(regions={"trigger": {**TRIGGER, "travel_O": [0, 0, 2.0]}})  # pressed upward (normalised)
    assert judge(spec, *_snaps(end=(_index(on_object=(0, 0, 6.0)), THUMB))).functional_success
    assert judge(spec, *_snaps()).failure_reason == "trigger_not_pressed"


def test_a_contact_without_force_vector_is_not_a_press():
    end = (_c("drill_00::body", "svh::svh_index_distal_link", P_TRIGGER_W, force=8.0), THUMB)
    v = judge(_spec(), *_snaps(end=end))
    assert v.failure_reason == "trigger_not_pressed" and math.isnan(v.trigger_force_N)


def test_force_sign_follows_the_body_when_the_record_is_swapped():
    c = _index(on_object=(0, -8.0, 0))
    s = c.swapped()
    assert s.body_a == "svh::svh_index_distal_link"
    assert np.allclose(s.force_on("drill_00"), [0, -8.0, 0]) and np.allclose(s.force_on("svh"), [0, 8.0, 0])
    v = judge(_spec(), *_snaps(end=(s, THUMB)))
    assert v.functional_success and v.trigger_force_N == pytest.approx(8.0)


def test_grown_by_override_is_respected():
    # a point 1.5 mm outside the annotated box: on the surface if the box is the part itself (grown_by 0),
    # not with the trigger's default (the box already grown by 4 mm: the part ends 4 mm inside it)
    p = P_TRIGGER_W - [0, TRIGGER["half_extents"][1] + 0.0015, 0]
    end = (_index(p), THUMB)
    assert judge(_spec(), *_snaps(end=end)).failure_reason == "trigger_missed"
    exact = _spec(regions={"trigger": {**TRIGGER, "grown_by": 0.0}})
    assert judge(exact, *_snaps(end=end)).functional_success
    # YCB boxes: grown by 3 mm, written in the annotation
    assert region_grown_by("trigger", {**TRIGGER, "grown_by": 0.003}) == 0.003
    assert region_grown_by("trigger", TRIGGER) == 0.004 and region_grown_by("handle", HANDLE) == 0.003
    assert region_grown_by("other", {}) == 0.0
    with pytest.raises(InputError):
        region_grown_by("trigger", {**TRIGGER, "grown_by": -0.001})


def test_other_finger_on_trigger_does_not_count():
    end = (_c("drill_00::body", "svh::svh_middle_distal_link", P_TRIGGER_W, on_a=(0, -8, 0)), THUMB)
    assert judge(_spec(), *_snaps(end=end)).failure_reason == "trigger_missed"


# ----------------------------------------------------------------------------- lift, hold, disturbance
def test_a_lift_of_8cm_is_not_a_grasp():
    X8 = _X((0.65, 0.0, 0.08))
    p = P_TRIGGER_W - [0, 0, 0.04]
    v = judge(_spec(), *_snaps(X_after=X8, end=(_index(p), THUMB)))
    assert not v.grasp_success and v.failure_reason == "lifted_short"
    assert "8.0 cm" in v.detail and "held off the table" in v.detail
    v = judge(_spec(), *_snaps(X_after=_X((0.65, 0.0, 0.10)), end=(_index(P_TRIGGER_W - [0, 0, 0.02]), THUMB)))
    assert v.grasp_success  # 10 cm is enough


def test_moved_3cm_in_the_hand_during_the_shake_is_shaken_loose():
    X_moved = _X((0.65, 0.0, 0.09))  # slid 3 cm down in the (fixed) hand
    end = (_index(P_TRIGGER_W - [0, 0, 0.03]), THUMB)
    v = judge(_spec(), *_snaps(shake=end, X_shake=X_moved, end=end, X_end=X_moved))
    assert not v.grasp_success and not v.functional_success and v.failure_reason == "shaken_loose"
    assert v.in_hand_shift_m == pytest.approx(0.03) and "3.0 cm" in v.detail


def test_moving_with_the_hand_is_not_motion_in_the_hand():
    """The hand up 1.27 cm at the end of the shake with the object: no in-hand motion."""
    up = _X((0.65, 0.0, 0.1327))
    s = list(_snaps())
    s[4] = Snapshot(7.0, up, HELD, up @ X_OH)
    assert in_hand_motion(s[2], s[4])[0] == pytest.approx(0.0, abs=1e-12)
    assert judge(_spec(), *s).functional_success


def test_turned_12deg_in_the_hand_is_shaken_loose():
    X_turned = X_LIFT @ _X((0, 0, 0), roll=np.radians(12))
    v = judge(_spec(), *_snaps(X_shake=X_turned, X_end=X_turned))
    assert v.failure_reason == "shaken_loose" and v.in_hand_turn_deg == pytest.approx(12.0)


def test_dropped_during_the_shake_is_shaken_loose():
    v = judge(_spec(), *_snaps(shake=(), X_shake=_X((0.65, 0, 0.05)), end=ON_TABLE, X_end=X0))
    assert v.failure_reason == "shaken_loose" and "dropped during the shake" in v.detail


def test_slipping_on_the_press_fails_the_grasp():
    X_moved = _X((0.65, 0.025, 0.12))  # pushed 2.5 cm forward in the hand by the index finger
    v = judge(_spec(), *_snaps(X_end=X_moved, end=(_index(P_TRIGGER_W + [0, 0.025, 0]), THUMB)))
    assert not v.grasp_success and v.failure_reason == "slipped_on_press"
    v = judge(_spec(), *_snaps(end=()))
    assert v.failure_reason == "slipped_on_press" and "dropped during the press" in v.detail


def test_slipping_during_the_hold():
    X_slid = _X((0.65, 0.0, 0.095))
    v = judge(_spec(), *_snaps(X_hold=X_slid, X_shake=X_slid, X_end=X_slid))
    assert v.failure_reason == "slipped" and "hold" in v.detail


def test_the_hand_pose_is_required():
    s = list(_snaps())
    s[4] = Snapshot(7.0, X_LIFT, HELD)
    with pytest.raises(InputError, match="X_WH"):
        judge(_spec(), *s)


# ----------------------------------------------------------------------------- rules kept from before
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


def test_an_object_that_began_to_move_untouched_fell_by_itself():
    initial, before, *later = _snaps(X_before=_X(roll=np.radians(80)))
    alone = replace(before, first_move=FirstMove(0.10, robot_contact=False))
    v = judge(_spec(), initial, alone, *later)
    assert v.failure_reason == "fell_by_itself" and "tipped 80 deg" in v.detail and "at 0.10 s" in v.detail
    assert decided_failure(_spec(), initial, alone).failure_reason == "fell_by_itself"
    pushed = replace(before, first_move=FirstMove(0.10, robot_contact=True))
    assert judge(_spec(), initial, pushed, *later).failure_reason == "collision_before_closing"
    # moved untouched but not knocked away (a small lean): the outcome decides, as for any nudge
    initial, before, *later = _snaps(X_before=_X(roll=np.radians(10)))
    v = judge(_spec(), initial, replace(before, first_move=FirstMove(0.10, robot_contact=False)), *later)
    assert v.functional_success


def test_dropped_and_not_lifted():
    v = judge(_spec(), *_snaps(hold=ON_TABLE, X_hold=X0, end=ON_TABLE, X_end=X0))
    assert v.failure_reason == "dropped" and not v.grasp_success
    v = judge(_spec(), *_snaps(X_after=X0, end=ON_TABLE))
    assert v.failure_reason == "not_lifted"
    X1 = _X((0.65, 0, 0.01))
    v = judge(_spec(), *_snaps(X_after=X1, end=ON_TABLE + HELD))
    assert v.failure_reason == "not_lifted"


def test_slipped():
    v = judge(_spec(), *_snaps(hold=ON_TABLE + HELD, X_hold=X0))
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
    # beside the handle's own surface by 5 mm (inside the old box grown by 5 mm): not on the handle
    p_beside = p_handle + [HANDLE["half_extents"][0] - 0.003 + 0.005, 0, 0]
    beside = (_c("drill_00::body", "svh::svh_middle_distal_link", p_beside),)
    assert judge(spec, *_snaps(end=beside)).failure_reason == "handle_missed"


def test_mug_tilted_20deg_after_the_shake_is_not_functional():
    """The mug turned 20 deg in the lift and stays so in the hand (no in-hand motion after the lift)."""
    spec = JudgeSpec(**{**_spec("mug", {"handle": HANDLE}).__dict__, "object_model": "drill_00"})
    X_tilt = _X((0.65, 0.0, 0.12), roll=np.radians(20))
    p_handle = X_tilt[:3, :3] @ np.array(HANDLE["center"]) + X_tilt[:3, 3]
    end = (_c("drill_00::body", "svh::svh_middle_distal_link", p_handle),)
    v = judge(spec, *_snaps(X_after=X_tilt, end=end))
    assert v.grasp_success and not v.functional_success and v.failure_reason == "tilted"
    assert v.tilt_deg == pytest.approx(20.0) and "20 deg" in v.detail
    X_small = _X((0.65, 0.0, 0.12), roll=np.radians(10))
    p_handle = X_small[:3, :3] @ np.array(HANDLE["center"]) + X_small[:3, 3]
    end = (_c("drill_00::body", "svh::svh_middle_distal_link", p_handle),)
    assert judge(spec, *_snaps(X_after=X_small, end=end)).functional_success


def test_primitive_object_has_no_functional_rule():
    spec = JudgeSpec(**{**_spec(None, {}).__dict__})
    v = judge(spec, *_snaps(end=(THUMB,)))
    assert v.functional_success and math.isnan(v.trigger_force_N)


def test_region_and_tilt_helpers():
    X = _X((1.0, 2.0, 3.0), yaw=np.pi / 2)
    p = X[:3, :3] @ np.array(TRIGGER["center"]) + X[:3, 3]
    assert points_in_region([p], X, TRIGGER, 0.0).tolist() == [True]
    assert points_in_region([p + [0.5, 0, 0]], X, TRIGGER, 0.0).tolist() == [False]
    assert tilt_deg(_X(), _X(roll=np.radians(20))) == pytest.approx(20.0)


def test_missing_functional_region_is_an_outcome_not_an_exception():
    v = judge(_spec(regions={}), *_snaps())
    assert v.grasp_success and not v.functional_success and v.failure_reason == "no_functional_region"


# ----------------------------------------------------------------------------- a trial stopped when decided
def _decided_at(spec, snaps):
    """(stage, verdict): the first prefix of the snapshots after which ``decided_failure`` gives a verdict,
    as a trial that stops when decided would see them (stage 1: before closing, 2: end of the lift,
    3: end of the hold, 4: end of the shake)."""
    initial, before_close, *later = snaps
    for stage, n_later in ((1, 0), (2, 1), (3, 2), (4, 3)):
        v = decided_failure(spec, initial, before_close, *later[:n_later])
        if v is not None:
            return stage, v
    return None, None


@pytest.mark.parametrize("snaps, stage", [
    (_snaps(X_before=_X((0.70, 0.0, 0.0))), 1),  # pushed 5 cm before closing
    (_snaps(X_after=X0, hold=ON_TABLE), 2),  # never left the table: decided at the end of the lift
    (_snaps(X_after=_X((0.65, 0.0, 0.08))), 2),  # held 8 cm up: lifted short
    (_snaps(X_hold=_X((0.65, 0.0, 0.095)), X_shake=_X((0.65, 0.0, 0.095)), X_end=_X((0.65, 0.0, 0.095))), 3),
    (_snaps(shake=(), X_shake=_X((0.65, 0, 0.05)), end=ON_TABLE, X_end=X0), 4),  # dropped in the shake
])
def test_a_decided_failure_is_the_full_judges_verdict(snaps, stage):
    """Stopped where the failure is decided, the verdict's flags, reason and detail are those of the whole run."""
    full = judge(_spec(), *snaps)
    at, early = _decided_at(_spec(), snaps)
    assert at == stage and not full.grasp_success
    assert (early.grasp_success, early.functional_success, early.failure_reason, early.detail) == (
        full.grasp_success, full.functional_success, full.failure_reason, full.detail)
    assert math.isnan(early.trigger_force_N)  # no press was simulated


@pytest.mark.parametrize("snaps", [_snaps(), _snaps(end=(_index(P_TRIGGER_W - [0, 0.03, 0]), THUMB)),
                                   _snaps(X_end=_X((0.65, 0.025, 0.12)))])
def test_nothing_is_decided_before_the_press_when_the_grasp_holds(snaps):
    """A functional grasp, a missed trigger and a slip on the press are all decided only at the end."""
    assert _decided_at(_spec(), snaps) == (None, None)
