"""Grasp and functional-grasp success from contacts and object poses (DESIGN.md section 6).

Pure functions over small records (numpy only), so the rules are unit-testable
without a simulation. ``catgrasp_drake.station.trial`` fills the records from
the simulation (``ContactResults`` and body poses) at three instants:

- ``before_close``: the hand at the grasp pose, fingers still in preshape
  (start of the close phase);
- ``after_lift``: end of the lift (start of the hold);
- ``end``: end of the hold.

Rules (first failing rule names ``failure_reason``):

1. ``collision_before_closing``: before closing, a robot body (arm or hand)
   touches the table, or the object has been knocked away: pushed by more
   than ``push_tolerance`` (4 cm, the sampling's largest offset) or tipped
   (its z axis turned) by more than ``push_tilt_deg`` (30°) from its initial
   pose. Smaller nudges and turns about the vertical (fingers brushing a
   light bottle on the reach) are not failures by themselves: DESIGN.md's
   success definition judges the outcome at the end of the hold.
2. At the end of the hold, with ``partners`` = the model instances touching
   the object:
   - no hand contact: ``dropped`` if the object had risen by at least half
     the lift height after the lift, else ``not_lifted``;
   - hand and table contact: ``slipped`` if it had been lifted, else ``not_lifted``;
   - anything else but the hand (e.g. the arm): ``touched_other``;
   - rise at the end below half the lift height: ``slipped``;
   - otherwise GRASP SUCCESS (off the table, touched only by the hand).
3. Functional success (needs grasp success):
   - drill, spray bottle: some contact point between ``index_distal_body``
     and the object lies inside the annotated ``trigger`` box grown by
     ``region_margin`` (5 mm, for the finger's compliant surface and the
     contact patch's discretisation) at the end of the hold; else
     ``trigger_missed``;
   - mug: tilt of the object's z axis from its initial direction <= 15°
     (else ``tilted``) and some hand contact point inside the ``handle``
     box grown by the margin (else ``handle_missed``);
   - other categories (e.g. a primitive test object): functional success =
     grasp success;
   - an object of a functional category without its region annotated (a
     scanned bottle without a trigger): ``no_functional_region`` (grasped,
     functional success undefined, counted as not functional).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from catgrasp_drake.errors import InputError


@dataclass(frozen=True)
class ContactRecord:
    """One contact between two bodies, named ``<model instance>::<body>``.

    ``points_W`` are points of the contact (point pair: the contact point;
    hydroelastic: the patch centroid and its faces' centroids), world frame.
    """

    body_a: str
    body_b: str
    points_W: tuple[tuple[float, float, float], ...]
    force_N: float = 0.0
    kind: str = "hydroelastic"  # or "point"

    def model_a(self) -> str:
        return self.body_a.split("::")[0]

    def model_b(self) -> str:
        return self.body_b.split("::")[0]

    def involves(self, body_or_model: str) -> bool:
        return body_or_model in (self.body_a, self.body_b, self.model_a(), self.model_b())

    def other(self, body_or_model: str) -> str:
        """The other side's full body name."""
        if body_or_model in (self.body_a, self.model_a()):
            return self.body_b
        return self.body_a

    def to_dict(self) -> dict:
        return {"body_a": self.body_a, "body_b": self.body_b, "force_N": round(float(self.force_N), 6),
                "kind": self.kind, "num_points": len(self.points_W)}


@dataclass(frozen=True)
class JudgeSpec:
    """What the judge needs to know about the scene (names, regions, thresholds)."""

    object_model: str
    hand_model: str
    arm_model: str
    table_model: str
    index_distal_body: str  # full name "<hand model>::<link>"
    category: str | None = None
    regions: dict = field(default_factory=dict)  # name -> {"center": [3], "half_extents": [3]} in O
    lift_height: float = 0.12
    region_margin: float = 0.005
    push_tolerance: float = 0.04
    push_tilt_deg: float = 30.0
    max_tilt_deg: float = 15.0


@dataclass(frozen=True)
class Snapshot:
    """The object's pose and the contacts at one instant."""

    time: float
    X_WO: np.ndarray
    contacts: tuple[ContactRecord, ...] = ()


@dataclass(frozen=True)
class Verdict:
    grasp_success: bool
    functional_success: bool
    failure_reason: str | None
    detail: str = ""
    object_rise_m: float = 0.0
    tilt_deg: float = 0.0


# ----------------------------------------------------------------------------- helpers
def tilt_deg(X_WO_a: np.ndarray, X_WO_b: np.ndarray) -> float:
    """Angle (degrees) between the object's z axis in pose a and in pose b."""
    za, zb = np.asarray(X_WO_a)[:3, 2], np.asarray(X_WO_b)[:3, 2]
    return float(np.degrees(np.arccos(np.clip(za @ zb, -1.0, 1.0))))


def rotation_deg(X_a: np.ndarray, X_b: np.ndarray) -> float:
    """Rotation angle (degrees) between two poses' orientations."""
    R = np.asarray(X_a)[:3, :3].T @ np.asarray(X_b)[:3, :3]
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0))))


def points_in_region(points_W, X_WO: np.ndarray, region: dict, margin: float) -> np.ndarray:
    """Boolean mask of world points inside an object-frame axis-aligned box grown by ``margin``."""
    P = np.asarray(points_W, float).reshape(-1, 3)
    if len(P) == 0:
        return np.zeros(0, bool)
    try:
        c = np.asarray(region["center"], float)
        h = np.asarray(region["half_extents"], float)
    except (KeyError, TypeError):
        raise InputError(f"region: expected center and half_extents, got {region!r}") from None
    X = np.asarray(X_WO, float)
    p_O = (P - X[:3, 3]) @ X[:3, :3]
    return np.all(np.abs(p_O - c) <= h + margin, axis=1)


def object_partners(contacts, object_model: str) -> set[str]:
    """Model instances (other than the object) in contact with the object."""
    out = set()
    for c in contacts:
        if c.model_a() == object_model and c.model_b() != object_model:
            out.add(c.model_b())
        elif c.model_b() == object_model and c.model_a() != object_model:
            out.add(c.model_a())
    return out


def region_touched(contacts, spec: JudgeSpec, X_WO: np.ndarray, region_name: str, *, by: str) -> bool:
    """Whether body/model ``by`` touches the object inside region ``region_name`` (grown by the margin)."""
    region = spec.regions.get(region_name)
    if region is None:
        raise InputError(f"no {region_name!r} region annotated; regions: {sorted(spec.regions)}")
    for c in contacts:
        if c.involves(spec.object_model) and c.involves(by):
            if points_in_region(c.points_W, X_WO, region, spec.region_margin).any():
                return True
    return False


# ----------------------------------------------------------------------------- the judge
def judge(spec: JudgeSpec, initial: Snapshot, before_close: Snapshot, after_lift: Snapshot,
          end: Snapshot) -> Verdict:
    """Grasp and functional success of one executed grasp (rules in the module docstring)."""
    z0 = float(np.asarray(initial.X_WO)[2, 3])
    rise_lift = float(np.asarray(after_lift.X_WO)[2, 3]) - z0
    rise_end = float(np.asarray(end.X_WO)[2, 3]) - z0
    tilt = tilt_deg(initial.X_WO, end.X_WO)

    def verdict(grasp, functional, reason, detail=""):
        return Verdict(grasp, functional, reason, detail, rise_end, tilt)

    # 1. before closing
    for c in before_close.contacts:
        robot = c.involves(spec.hand_model) or c.involves(spec.arm_model)
        if robot and c.involves(spec.table_model):
            robot_body = c.other(spec.table_model)
            return verdict(False, False, "collision_before_closing", f"{robot_body} touches the table")
    push = float(np.linalg.norm(np.asarray(before_close.X_WO)[:3, 3] - np.asarray(initial.X_WO)[:3, 3]))
    tipped = tilt_deg(initial.X_WO, before_close.X_WO)
    if push > spec.push_tolerance or tipped > spec.push_tilt_deg:
        turn = rotation_deg(initial.X_WO, before_close.X_WO)
        return verdict(False, False, "collision_before_closing",
                       f"object pushed {push * 100:.1f} cm, tipped {tipped:.0f} deg "
                       f"(turned {turn:.0f} deg) before closing")

    # 2. grasp success at the end of the hold
    partners = object_partners(end.contacts, spec.object_model)
    lifted = rise_lift >= 0.5 * spec.lift_height
    if spec.hand_model not in partners:
        if lifted:
            return verdict(False, False, "dropped", f"rise {rise_lift * 100:.1f} cm after lift, no hand contact at end")
        return verdict(False, False, "not_lifted", f"rise {rise_lift * 100:.1f} cm after lift")
    if spec.table_model in partners:
        if lifted:
            return verdict(False, False, "slipped", "object back on the table at the end of the hold")
        return verdict(False, False, "not_lifted", f"rise {rise_lift * 100:.1f} cm after lift, still on the table")
    others = sorted(partners - {spec.hand_model})
    if others:
        return verdict(False, False, "touched_other", f"object touches {', '.join(others)}")
    if rise_end < 0.5 * spec.lift_height:
        return verdict(False, False, "slipped", f"rise {rise_end * 100:.1f} cm at the end of the hold")

    # 3. functional success
    needed = {"drill": "trigger", "spray_bottle": "trigger", "mug": "handle"}.get(spec.category)
    if needed is not None and needed not in spec.regions:  # e.g. a scanned bottle without a trigger
        return verdict(True, False, "no_functional_region", f"object has no {needed!r} region annotated")
    if spec.category in ("drill", "spray_bottle"):
        if not region_touched(end.contacts, spec, end.X_WO, "trigger", by=spec.index_distal_body):
            return verdict(True, False, "trigger_missed", "index distal link not on the trigger")
    elif spec.category == "mug":
        if tilt > spec.max_tilt_deg:
            return verdict(True, False, "tilted", f"mug tilted {tilt:.0f} deg")
        if not region_touched(end.contacts, spec, end.X_WO, "handle", by=spec.hand_model):
            return verdict(True, False, "handle_missed", "hand not on the handle")
    return verdict(True, True, None)
