"""Functional constraints on sampled grasps (paper, section III-D).

Sampled motions whose orientation would block or miss the tool's trigger, or
tilt a mug, are discarded before any simulation. The rules are code; their
parameters live in ``models/grasps/constraints.yaml``:

* ``trigger`` (drill, spray bottle): at the grasp pose, the grasp's
  functional point ``tip_H`` — a point fixed in the hand base frame H: the
  canonical trigger centre seen from the canonical grasp (training), or the
  index finger's pad — must lie within ``max_tip_distance`` metres of the
  instance's annotated trigger box,
  and the fingers' direction (H +z) must stay within ``max_finger_angle_deg``
  of the reference motion's (so the index finger reaches the trigger from the
  front rather than blocking it from the side).
* ``upright`` (mug): the grasp must not tilt the hand's vertical relation to
  the mug: the angle between the sampled and reference hand orientations'
  images of the object's z axis stays within ``max_tilt_deg``.

All poses are hand-base poses X_OH in the object frame O (metres).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from catgrasp_drake.errors import InputError, ModelFileError

CONSTRAINTS_FILE = Path(__file__).resolve().parents[2] / "models" / "grasps" / "constraints.yaml"


@dataclass(frozen=True)
class FunctionalConstraint:
    """One category's rule and its parameters."""

    category: str
    kind: str  # "trigger" or "upright"
    region: str
    max_tip_distance: float = 0.02
    max_finger_angle_deg: float = 15.0
    max_tilt_deg: float = 8.0

    def check(self, X_OH_grasp: np.ndarray, X_OH_reference: np.ndarray, regions: dict,
              tip_H: np.ndarray | None = None) -> tuple[bool, str]:
        """``(ok, reason)`` for a sampled grasp pose against the reference grasp pose."""
        if self.kind == "trigger":
            if tip_H is None:
                raise InputError("trigger constraint needs the index fingertip position tip_H")
            tip_O = X_OH_grasp[:3, :3] @ np.asarray(tip_H, float) + X_OH_grasp[:3, 3]
            d = box_distance(tip_O, regions[self.region])
            if d > self.max_tip_distance:
                return False, f"index tip {1000 * d:.0f} mm from the {self.region}"
            angle = _angle_deg(X_OH_grasp[:3, 2], X_OH_reference[:3, 2])
            if angle > self.max_finger_angle_deg:
                return False, f"fingers turned {angle:.0f} deg away from the reference"
            return True, ""
        if self.kind == "upright":
            # the object's z axis seen from the hand: R^T e_z, compared between sample and reference
            z_s = X_OH_grasp[:3, :3].T @ np.array([0.0, 0.0, 1.0])
            z_r = X_OH_reference[:3, :3].T @ np.array([0.0, 0.0, 1.0])
            angle = _angle_deg(z_s, z_r)
            if angle > self.max_tilt_deg:
                return False, f"hand tilted {angle:.0f} deg against the mug's vertical"
            return True, ""
        raise InputError(f"unknown constraint kind {self.kind!r}")


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    c = float(np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b)))
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def box_distance(point, region: dict) -> float:
    """Euclidean distance (m) from ``point`` to an axis-aligned box region (0 inside)."""
    c = np.asarray(region["center"], float)
    h = np.asarray(region["half_extents"], float)
    excess = np.maximum(np.abs(np.asarray(point, float) - c) - h, 0.0)
    return float(np.linalg.norm(excess))


def load_constraint(category: str, path: str | Path = CONSTRAINTS_FILE) -> FunctionalConstraint:
    """The functional constraint of ``category`` from the YAML file."""
    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as e:
        raise ModelFileError(f"{path}: unreadable constraints file ({e})") from None
    if not isinstance(data, dict) or category not in data:
        known = ", ".join(sorted(data)) if isinstance(data, dict) else "none"
        raise InputError(f"no functional constraint for category {category!r}; known: {known}")
    entry = dict(data[category])
    allowed = {"kind", "region", "max_tip_distance", "max_finger_angle_deg", "max_tilt_deg"}
    unknown = set(entry) - allowed
    if unknown:
        raise ModelFileError(f"{path}: {category}: unknown keys {sorted(unknown)}")
    if entry.get("kind") not in ("trigger", "upright"):
        raise ModelFileError(f"{path}: {category}: kind must be 'trigger' or 'upright'")
    return FunctionalConstraint(category=category, **entry)
