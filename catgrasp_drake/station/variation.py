"""Grasp variations: a hand-written grasp moved, turned and re-postured by a parameter vector.

A variation ``v`` holds the values of :data:`VARIATION_NAMES`, in the object
frame O of the grasp's instance:

- ``dx, dy, dz`` (m): the hand's control poses moved (after the turn);
- ``roll, pitch, yaw`` (deg): turned by x-y-z Euler angles about the centre of
  the category's functional region (trigger or handle) -- as
  :func:`catgrasp_drake.station.handwritten.shifted_motion`;
- the ``closed`` posture's joints changed per finger group (rad): thumb
  flexion, thumb opposition, index proximal, index distal, middle (proximal
  and distal), ring and little finger, finger spread -- clipped to the
  joint limits. The ``preshape`` is left as it is.

``scale`` gives each parameter's natural step (1 cm, 8 deg, 0.25 rad): the
initial spread of a search. ``v = 0`` is the grasp itself.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS, hand_joint_limits
from catgrasp_drake.station.handwritten import moved_about, shifted_motion

#: (name, scale, joints of HAND_ACTUATED_JOINTS it moves (postures only)).
VARIATION: tuple[tuple[str, float, tuple[str, ...]], ...] = (
    ("dx", 0.01, ()), ("dy", 0.01, ()), ("dz", 0.01, ()),
    ("roll", 8.0, ()), ("pitch", 8.0, ()), ("yaw", 8.0, ()),
    ("thumb_flexion", 0.25, ("svh_thumb_flexion",)),
    ("thumb_opposition", 0.25, ("svh_thumb_opposition",)),
    ("index_proximal", 0.25, ("svh_index_proximal",)),
    ("index_distal", 0.25, ("svh_index_distal",)),
    ("middle", 0.25, ("svh_middle_proximal", "svh_middle_distal")),
    ("ring_pinky", 0.25, ("svh_ring", "svh_pinky")),
    ("spread", 0.25, ("svh_finger_spread",)),
)
VARIATION_NAMES: tuple[str, ...] = tuple(name for name, _, _ in VARIATION)
VARIATION_SCALE = np.array([scale for _, scale, _ in VARIATION])
NUM_POSE_PARAMS = 6


def variation_vector(values: dict | None = None) -> np.ndarray:
    """A variation from ``{name: value}`` (missing names 0); unknown names are an error."""
    values = dict(values or {})
    unknown = sorted(set(values) - set(VARIATION_NAMES))
    if unknown:
        raise InputError(f"variation: unknown parameters {unknown}; known: {', '.join(VARIATION_NAMES)}")
    return np.array([float(values.get(name, 0.0)) for name in VARIATION_NAMES])


def variation_dict(v) -> dict:
    """``{name: value}`` of a variation vector (rounded: metres to 0.1 mm, degrees and radians to 1e-4)."""
    v = _check(v)
    return {name: round(float(x), 4) for name, x in zip(VARIATION_NAMES, v)}


def _check(v) -> np.ndarray:
    try:
        a = np.array(v, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InputError("variation: expected numbers") from None
    if a.shape != (len(VARIATION_NAMES),) or not np.all(np.isfinite(a)):
        raise InputError(f"variation: expected {len(VARIATION_NAMES)} finite values ({', '.join(VARIATION_NAMES)})")
    return a


def varied_posture(q, v) -> np.ndarray:
    """The posture ``q`` (HAND_ACTUATED_JOINTS order, rad) with the variation's finger-group changes,
    clipped to the joint limits."""
    v = _check(v)
    q = np.array(q, dtype=np.float64)
    index = {name: i for i, name in enumerate(HAND_ACTUATED_JOINTS)}
    for (_, _, joints), dv in zip(VARIATION[NUM_POSE_PARAMS:], v[NUM_POSE_PARAMS:]):
        for joint in joints:
            q[index[joint]] += dv
    limits = hand_joint_limits()
    lower, upper = (np.array([limits[j][k] for j in HAND_ACTUATED_JOINTS]) for k in (0, 1))
    return np.clip(q, lower, upper)


def vary_motion(motion: GraspMotion, category: str, instance: str, v, *,
                annotations_dir: str | Path | None = None) -> GraspMotion:
    """``motion`` (object frame, on ``instance``) with the variation ``v`` applied (module docstring)."""
    v = _check(v)
    out = shifted_motion(motion, category, instance, v[:3], v[3:6], annotations_dir=annotations_dir)
    return _varied_closing(out, v)


def vary_motion_about(motion: GraspMotion, pivot_O, v) -> GraspMotion:
    """``motion`` (object frame) with the variation ``v`` applied, turned about ``pivot_O`` (m, object frame)
    instead of an annotated region's centre -- e.g. about the warped functional point of a grasp
    transferred onto an instance (``catgrasp_drake.training``)."""
    v = _check(v)
    return _varied_closing(moved_about(motion, pivot_O, v[:3], v[3:6]), v)


def _varied_closing(motion: GraspMotion, v: np.ndarray) -> GraspMotion:
    postures = dict(motion.postures)
    postures["closed"] = varied_posture(postures["closed"], v)
    return replace(motion, postures=postures)
