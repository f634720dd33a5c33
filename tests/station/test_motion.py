"""GraspMotion validation, frames and serialisation."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion, invert


def _rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def _pose(R=np.eye(3), p=(0, 0, 0)):
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = p
    return X


POSTURES = {"open": np.zeros(9), "preshape": np.full(9, 0.1), "closed": np.full(9, 0.8)}


def _motion(**kw):
    args = dict(poses=np.stack([_pose(p=(0, -0.1, 0.1)), _pose(p=(0, -0.05, 0.1))]),
                pose_names=("pregrasp", "grasp"), postures=POSTURES, frame="object")
    args.update(kw)
    return GraspMotion(**args)


def test_valid_motion_is_frozen():
    m = _motion()
    assert m.poses.shape == (2, 4, 4)
    with pytest.raises(ValueError):
        m.poses[0, 0, 3] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.lift_height = 0.2
    assert m.lift_height >= 0.10 and m.hold_time >= 2.0
    np.testing.assert_allclose(m.pose("grasp")[:3, 3], [0, -0.05, 0.1])


@pytest.mark.parametrize("kw, fragment", [
    (dict(poses=np.zeros((2, 4, 4))), "last row"),
    (dict(poses=np.stack([_pose(np.diag([1, 1, -1.0])), _pose()])), "rotation"),
    (dict(poses=np.stack([_pose(2 * np.eye(3)), _pose()])), "rotation"),
    (dict(poses=np.stack([_pose(p=(np.nan, 0, 0)), _pose()])), "NaN"),
    (dict(poses=np.eye(4)), "shape"),
    (dict(pose_names=("a", "b")), "missing"),
    (dict(pose_names=("pregrasp",)), "names"),
    (dict(postures={"open": np.zeros(9), "preshape": np.zeros(9)}), "closed"),
    (dict(postures={**POSTURES, "closed": np.zeros(8)}), "closed"),
    (dict(postures={**POSTURES, "open": [0] * 8 + [np.inf]}), "open"),
    (dict(frame="camera"), "frame"),
    (dict(lift_height=0.05), "lift_height"),
    (dict(hold_time=1.0), "hold_time"),
    (dict(lift_height=float("nan")), "lift_height"),
])
def test_validation_errors(kw, fragment):
    with pytest.raises(InputError, match=fragment):
        _motion(**kw)


def test_world_object_round_trip():
    m = _motion()
    X_WO = _pose(_rot_z(0.7), (0.6, 0.1, 0.02))
    w = m.in_world(X_WO)
    assert w.frame == "world"
    np.testing.assert_allclose(w.poses, X_WO @ m.poses)
    back = w.in_object(X_WO)
    assert back.frame == "object"
    np.testing.assert_allclose(back.poses, m.poses, atol=1e-12)
    assert m.in_object(X_WO) is m and w.in_world(X_WO) is w
    np.testing.assert_allclose(invert(X_WO) @ X_WO, np.eye(4), atol=1e-12)


def test_dict_round_trip_is_json():
    m = _motion(lift_height=0.15, hold_time=2.5)
    d = json.loads(json.dumps(m.to_dict()))
    m2 = GraspMotion.from_dict(d)
    assert m2 == m
    assert m2.lift_height == 0.15 and m2.hold_time == 2.5
    with pytest.raises(InputError, match="unknown"):
        GraspMotion.from_dict({**d, "extra": 1})
    with pytest.raises(InputError, match="missing"):
        GraspMotion.from_dict({k: v for k, v in d.items() if k != "poses"})
