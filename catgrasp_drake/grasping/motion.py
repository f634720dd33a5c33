"""``GraspMotion``: the control poses and hand postures of one grasping motion.

A grasping motion (paper, section III-C) is a short sequence of control poses
of the hand -- here poses ``X_FH`` of the hand base link ``H`` (the robot
model's ``HAND_BASE_LINK``) in a frame ``F`` -- plus the hand postures of its
primitives. The station executes it as approach -> reach (pregrasp -> grasp
along the approach direction) -> close (preshape -> closed) -> lift -> hold.

``frame`` states which frame F the poses are in: ``"object"`` (the object's
canonical frame O: z up, base on z = 0, functional direction +y) or
``"world"`` (W). ``in_world(X_WO)`` / ``in_object(X_WO)`` convert.

Postures are (9,) joint-angle vectors (radians) in the order of the robot
model's ``HAND_ACTUATED_JOINTS``; ``open``, ``preshape`` and ``closed`` are
required.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

import numpy as np

from catgrasp_drake.errors import InputError

FRAMES = ("object", "world")
REQUIRED_POSES = ("pregrasp", "grasp")
REQUIRED_POSTURES = ("open", "preshape", "closed")
NUM_HAND_JOINTS = 9
MIN_LIFT_HEIGHT = 0.10
MIN_HOLD_TIME = 2.0
#: Tolerance on ``R^T R = I`` and ``det R = 1`` of control-pose rotations.
ROTATION_TOL = 1e-6
FORMAT = "catgrasp.grasp_motion"
FORMAT_VERSION = 1


def _check_poses(poses, name: str = "poses") -> np.ndarray:
    try:
        P = np.array(poses, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a (K, 4, 4) array of homogeneous transforms") from None
    if P.ndim != 3 or P.shape[1:] != (4, 4) or P.shape[0] < 1:
        raise InputError(f"{name}: expected shape (K, 4, 4) with K >= 1, got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise InputError(f"{name}: contains NaN or inf")
    for k, X in enumerate(P):
        if not np.allclose(X[3], [0, 0, 0, 1], atol=ROTATION_TOL):
            raise InputError(f"{name}[{k}]: last row must be [0, 0, 0, 1], got {X[3].tolist()}")
        R = X[:3, :3]
        err = float(np.abs(R.T @ R - np.eye(3)).max())
        if err > ROTATION_TOL or np.linalg.det(R) < 0:
            raise InputError(f"{name}[{k}]: rotation is not proper orthonormal "
                             f"(|R^T R - I| = {err:.2g}, det = {np.linalg.det(R):.3f}); orthonormalise it first")
    P[:, 3] = (0.0, 0.0, 0.0, 1.0)
    return P


def _check_posture(q, name: str) -> np.ndarray:
    try:
        a = np.array(q, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"posture {name!r}: expected {NUM_HAND_JOINTS} numbers") from None
    if a.shape != (NUM_HAND_JOINTS,):
        raise InputError(f"posture {name!r}: expected shape ({NUM_HAND_JOINTS},), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"posture {name!r}: contains NaN or inf")
    return a


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a


def invert(X: np.ndarray) -> np.ndarray:
    """Inverse of a 4x4 rigid transform."""
    Xi = np.eye(4)
    Xi[:3, :3] = X[:3, :3].T
    Xi[:3, 3] = -X[:3, :3].T @ X[:3, 3]
    return Xi


@dataclass(frozen=True, eq=False)
class GraspMotion:
    """Control poses (K, 4, 4) of the hand base link in ``frame`` + hand postures.

    Attributes:
        poses: (K, 4, 4) homogeneous transforms ``X_FH`` (read-only array).
        pose_names: K names; must contain ``"pregrasp"`` and ``"grasp"``.
        postures: name -> (9,) joint angles (rad); needs ``open``, ``preshape``, ``closed``.
        frame: ``"object"`` or ``"world"``.
        lift_height: straight-up lift after closing (m), >= 0.10.
        hold_time: hold after lifting (s), >= 2.
    """

    poses: np.ndarray
    pose_names: tuple[str, ...] = REQUIRED_POSES
    postures: Mapping[str, np.ndarray] = field(default_factory=dict)
    frame: str = "object"
    lift_height: float = 0.12
    hold_time: float = 2.0

    def __post_init__(self):
        poses = _check_poses(self.poses)
        names = tuple(str(n) for n in self.pose_names)
        if len(names) != len(poses):
            raise InputError(f"pose_names: {len(names)} names for {len(poses)} poses")
        if len(set(names)) != len(names):
            raise InputError(f"pose_names: duplicate names in {names}")
        missing = [n for n in REQUIRED_POSES if n not in names]
        if missing:
            raise InputError(f"pose_names: missing {missing}; a motion needs {list(REQUIRED_POSES)}")
        if not isinstance(self.postures, Mapping):
            raise InputError("postures: expected a mapping name -> (9,) joint angles")
        missing = [n for n in REQUIRED_POSTURES if n not in self.postures]
        if missing:
            raise InputError(f"postures: missing {missing}; a motion needs {list(REQUIRED_POSTURES)}")
        postures = {str(k): _frozen(_check_posture(v, str(k))) for k, v in self.postures.items()}
        if self.frame not in FRAMES:
            raise InputError(f"frame: expected one of {FRAMES}, got {self.frame!r}")
        for attr, lo in (("lift_height", MIN_LIFT_HEIGHT), ("hold_time", MIN_HOLD_TIME)):
            v = getattr(self, attr)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) or not math.isfinite(v) or v < lo:
                raise InputError(f"{attr}: expected a number >= {lo}, got {v!r}")
            object.__setattr__(self, attr, float(v))
        object.__setattr__(self, "poses", _frozen(poses))
        object.__setattr__(self, "pose_names", names)
        object.__setattr__(self, "postures", MappingProxyType(postures))

    # ------------------------------------------------------------------ access
    def pose(self, name: str) -> np.ndarray:
        """The control pose called ``name`` (4x4 copy)."""
        try:
            return self.poses[self.pose_names.index(name)].copy()
        except ValueError:
            raise InputError(f"no pose {name!r}; poses: {list(self.pose_names)}") from None

    def posture(self, name: str) -> np.ndarray:
        try:
            return np.array(self.postures[name])
        except KeyError:
            raise InputError(f"no posture {name!r}; postures: {list(self.postures)}") from None

    # ------------------------------------------------------------------ frames
    def _with_poses(self, poses: np.ndarray, frame: str) -> "GraspMotion":
        return GraspMotion(poses, self.pose_names, dict(self.postures), frame, self.lift_height, self.hold_time)

    def in_world(self, X_WO) -> "GraspMotion":
        """The same motion with poses in the world frame, for an object at ``X_WO`` (4x4)."""
        if self.frame == "world":
            return self
        X_WO = _check_poses(np.asarray(X_WO, float)[None], "X_WO")[0]
        return self._with_poses(X_WO @ self.poses, "world")

    def in_object(self, X_WO) -> "GraspMotion":
        """The same motion with poses in the object frame, for an object at ``X_WO`` (4x4)."""
        if self.frame == "object":
            return self
        X_WO = _check_poses(np.asarray(X_WO, float)[None], "X_WO")[0]
        return self._with_poses(invert(X_WO) @ self.poses, "object")

    # ------------------------------------------------------------------ I/O
    def to_dict(self) -> dict:
        """A JSON-able dict (plain lists and floats); inverse of :meth:`from_dict`."""
        return {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "frame": self.frame,
            "pose_names": list(self.pose_names),
            "poses": self.poses.tolist(),
            "postures": {k: v.tolist() for k, v in self.postures.items()},
            "lift_height": self.lift_height,
            "hold_time": self.hold_time,
        }

    @classmethod
    def from_dict(cls, data: Mapping) -> "GraspMotion":
        if not isinstance(data, Mapping):
            raise InputError(f"grasp motion: expected a mapping, got {type(data).__name__}")
        if data.get("format", FORMAT) != FORMAT or data.get("format_version", FORMAT_VERSION) != FORMAT_VERSION:
            raise InputError(f"grasp motion: not a {FORMAT} v{FORMAT_VERSION} record")
        known = {"format", "format_version", "frame", "pose_names", "poses", "postures", "lift_height", "hold_time"}
        unknown = sorted(set(data) - known)
        if unknown:
            raise InputError(f"grasp motion: unknown field(s) {unknown}")
        for k in ("poses", "postures", "frame"):
            if k not in data:
                raise InputError(f"grasp motion: missing field {k!r}")
        return cls(
            poses=data["poses"],
            pose_names=tuple(data.get("pose_names", REQUIRED_POSES)),
            postures=dict(data["postures"]),
            frame=data["frame"],
            lift_height=data.get("lift_height", 0.12),
            hold_time=data.get("hold_time", 2.0),
        )

    def __eq__(self, other) -> bool:
        if not isinstance(other, GraspMotion):
            return NotImplemented
        return self.to_dict() == other.to_dict()

    __hash__ = None

    # Immutable (read-only arrays, mapping proxy): Drake contexts that copy an
    # abstract value holding a motion may share it.
    def __deepcopy__(self, memo):
        return self

    def __copy__(self):
        return self
