"""Grasp and functional-grasp success from contacts and poses (DESIGN.md section 6).

Pure functions over small records (numpy only), so the rules are unit-testable
without a simulation. ``catgrasp_drake.trial`` fills the records from
the simulation (``ContactResults``, the object's pose X_WO and the hand base
pose X_WH) at the phase boundaries of the plan
(:class:`catgrasp_drake.planning.records.Timeline`):

- ``initial``: start of the simulation;
- ``before_close``: the hand at the grasp pose, fingers still in preshape
  (start of the close phase);
- ``after_lift``: end of the lift = start of the hold (the REFERENCE of the
  in-hand rule);
- ``after_hold``: end of the hold (``hold_time``, 2 s), before the disturbance;
- ``after_shake``: end of the shake: the wrist moved vertically (world z)
  sinusoidally for 1 s, peak acceleration 2 m/s^2 at 2 Hz (±1.27 cm),
  orientation fixed;
- ``end``: end of the press: the index finger's actuated joints commanded
  to their upper limits for 0.5 s, the rest of the hand holding its closed
  posture.

In-hand motion: X_HO = X_WH^-1 X_WO; the *shift* (m) and *turn* (deg) of a
snapshot are the translation and rotation angle between its X_HO and the
reference's (``after_lift``). Tolerances: ``in_hand_shift_tol`` (2 cm) and
``in_hand_turn_tol_deg`` (10°).

Rules (first failing rule names ``failure_reason``):

1. ``collision_before_closing``: before closing, a robot body (arm or hand)
   touches the table, or the object has been knocked away: pushed by more
   than ``push_tolerance`` (4 cm, the sampling's largest offset) or tipped
   (its z axis turned) by more than ``push_tilt_deg`` (30°) from its initial
   pose. Smaller nudges and turns about the vertical (fingers brushing a
   light bottle on the reach) are not failures by themselves: the outcome
   after the lift, hold and disturbance decides. ``fell_by_itself`` instead
   when the object was knocked away so but began to move with no robot body
   touching it (the closing snapshot's :class:`FirstMove`, watched during the
   simulation): an object that does not stand, not a grasp that hit it.
2. Lift and hold, at ``after_hold`` (``partners`` = the model instances
   touching the object; ``lifted`` = the object's rise at the end of the
   lift (``after_lift``) is at least ``min_rise``, 10 cm, not a fraction of
   the commanded lift):
   - no hand contact: ``dropped`` if lifted, else ``not_lifted``;
   - hand and table contact: ``slipped`` if lifted, else ``not_lifted``;
   - anything else but the hand (e.g. the arm): ``touched_other``;
   - held, off the table, risen by 2-10 cm (it turned or slid in the hand
     during the lift): ``lifted_short``; less: ``not_lifted``;
   - moved in the hand beyond the tolerances during the hold: ``slipped``.
3. Disturbance, at ``after_shake``: no hand contact (dropped during the
   shake), back on the table, or moved in the hand beyond the tolerances:
   ``shaken_loose``; anything else but the hand: ``touched_other``.
4. Press, at ``end``: no hand contact, on the table, or moved in the hand
   beyond the tolerances: ``slipped_on_press``; anything else but the hand:
   ``touched_other``. Otherwise GRASP SUCCESS: lifted >= 10 cm, held 2 s,
   shaken and pressed, still in the hand within 2 cm / 10° of where it was
   at the start of the hold, touched only by the hand.
5. Functional success (needs grasp success), at ``end``:
   - drill, spray bottle: some contact point between ``index_distal_body``
     and the object lies on the trigger's OWN surface: inside the annotated
     ``trigger`` box grown by ``surface_margin - grown_by`` (2 mm minus
     what the annotation already added around the trigger, see
     :func:`region_grown_by`), else ``trigger_missed``; AND the force of
     those contacts ON THE OBJECT, projected on the trigger's travel
     direction (region key ``travel_O``, object frame; default −y_O: a
     drill's trigger is pushed back into the handle, a spray bottle's lever
     pulled back toward the neck), is at least ``min_trigger_force`` (5 N),
     else ``trigger_not_pressed`` (the measured force in ``detail``);
   - mug: tilt of the object's z axis from its initial direction <= 15°
     after the shake and at the end (else ``tilted``), and some hand
     contact point within ``surface_margin`` (2 mm) of the handle (the
     ``handle`` box grown by ``surface_margin - grown_by``; else
     ``handle_missed``);
   - other categories (e.g. a primitive test object): functional success =
     grasp success;
   - an object of a functional category without its region annotated (a
     scanned bottle without a trigger): ``no_functional_region`` (grasped,
     functional success undefined, counted as not functional).

A trial need not run past a decided failure: :func:`decided_failure` gives the
verdict that the snapshots taken so far already decide (rules 1-3, and an object
not lifted ``min_rise`` by the end of the lift), and ``catgrasp_drake.trial``
stops there unless something watches the run (a film, a recording).

The :class:`Verdict` records what was measured: ``object_rise_m`` and
``tilt_deg`` at the end, ``in_hand_shift_m``/``in_hand_turn_deg`` (the
largest over the hold, shake and press), ``trigger_force_N`` (along the
travel, at the end; nan without index-distal contact on the trigger or
without a trigger region).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from catgrasp_drake.data.categories import REGION_MARGIN_M
from catgrasp_drake.errors import InputError

#: How much the annotated boxes were grown around the part itself (m), per region name, when the
#: region has no ``"grown_by"`` key: the generated instances' trigger box is the trigger's bounding
#: box grown by 4 mm and the mug handle's by 3 mm (``catgrasp_drake.data.categories._box_region``).
#: Other region names: 0 (the box is the part's own bounding box).
DEFAULT_GROWN_BY: dict[str, float] = dict(REGION_MARGIN_M)
#: Direction (object frame) in which the trigger is pressed, when the region has no ``"travel_O"`` key.
DEFAULT_TRAVEL_O = (0.0, -1.0, 0.0)


@dataclass(frozen=True)
class ContactRecord:
    """One contact between two bodies, named ``<model instance>::<body>``.

    ``points_W`` are points of the contact (point pair: the contact point;
    hydroelastic: the patch centroid and its faces' centroids), world frame.
    ``force_N`` is the magnitude of the contact force. ``force_on_a_W`` (N,
    world frame, optional) is the contact force vector applied ON ``body_a``
    BY ``body_b`` (the force on ``body_b`` is its negative): use
    :meth:`force_on` to get it for either side.
    """

    body_a: str
    body_b: str
    points_W: tuple[tuple[float, float, float], ...]
    force_N: float = 0.0
    kind: str = "hydroelastic"  # or "point"
    force_on_a_W: tuple[float, float, float] | None = None

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

    def force_on(self, body_or_model: str) -> np.ndarray | None:
        """Contact force (N, W) applied on ``body_or_model``'s side of the contact, or None if unknown."""
        if self.force_on_a_W is None:
            return None
        f = np.asarray(self.force_on_a_W, float)
        if body_or_model in (self.body_a, self.model_a()):
            return f
        if body_or_model in (self.body_b, self.model_b()):
            return -f
        raise InputError(f"{body_or_model!r} is not a side of the contact {self.body_a} / {self.body_b}")

    def swapped(self) -> "ContactRecord":
        """The same contact with the sides exchanged (the force vector follows: it stays on the same body)."""
        f = None if self.force_on_a_W is None else tuple(-float(v) for v in self.force_on_a_W)
        return ContactRecord(self.body_b, self.body_a, self.points_W, self.force_N, self.kind, f)

    def to_dict(self) -> dict:
        d = {"body_a": self.body_a, "body_b": self.body_b, "force_N": round(float(self.force_N), 6),
             "kind": self.kind, "num_points": len(self.points_W)}
        if self.force_on_a_W is not None:
            d["force_on_a_W"] = [round(float(v), 6) for v in self.force_on_a_W]
        return d


@dataclass(frozen=True)
class JudgeSpec:
    """What the judge needs to know about the scene (names, regions, thresholds; m, deg, N)."""

    object_model: str
    hand_model: str
    arm_model: str
    table_model: str
    index_distal_body: str  # full name "<hand model>::<link>"
    category: str | None = None
    # name -> {"center": [3], "half_extents": [3], optional "grown_by": m, optional "travel_O": [3]} in O
    regions: dict = field(default_factory=dict)
    lift_height: float = 0.12  # the commanded lift (for reference; the rule is min_rise)
    min_rise: float = 0.10
    surface_margin: float = 0.002
    min_trigger_force: float = 5.0
    in_hand_shift_tol: float = 0.02
    in_hand_turn_tol_deg: float = 10.0
    push_tolerance: float = 0.04
    push_tilt_deg: float = 30.0
    max_tilt_deg: float = 15.0


@dataclass(frozen=True)
class FirstMove:
    """When the object first moved before the closing, and whether a robot body touched it then.

    "Moved": turned (its z axis) by more than :data:`FIRST_MOVE_TILT_DEG` or shifted by more than
    :data:`FIRST_MOVE_SHIFT_M` from its pose at the start of the trial. ``time`` in s.
    """

    time: float
    robot_contact: bool


#: The object has "moved" (:class:`FirstMove`) once it turned by this much (deg) or shifted by this much (m).
FIRST_MOVE_TILT_DEG = 1.0
FIRST_MOVE_SHIFT_M = 0.002


def has_moved(X_WO_start: np.ndarray, X_WO: np.ndarray) -> bool:
    """Whether the object at ``X_WO`` has moved from ``X_WO_start`` in the sense of :class:`FirstMove`."""
    shift = float(np.linalg.norm(X_WO[:3, 3] - X_WO_start[:3, 3]))
    return shift > FIRST_MOVE_SHIFT_M or tilt_deg(X_WO_start, X_WO) > FIRST_MOVE_TILT_DEG


@dataclass(frozen=True)
class Snapshot:
    """The object's pose, the hand base pose (``X_WH``, optional) and the contacts at one instant.

    ``first_move`` (the snapshot at the closing only; None: not watched, or it did not move) says whether the
    object began to move with a robot body touching it or by itself.
    """

    time: float
    X_WO: np.ndarray
    contacts: tuple[ContactRecord, ...] = ()
    X_WH: np.ndarray | None = None
    first_move: FirstMove | None = None


@dataclass(frozen=True)
class Verdict:
    grasp_success: bool
    functional_success: bool
    failure_reason: str | None
    detail: str = ""
    object_rise_m: float = 0.0
    tilt_deg: float = 0.0
    trigger_force_N: float = math.nan  # along the trigger's travel, on the object, at the end
    in_hand_shift_m: float = math.nan  # largest over hold, shake, press (vs the start of the hold)
    in_hand_turn_deg: float = math.nan


# ----------------------------------------------------------------------------- helpers
def tilt_deg(X_WO_a: np.ndarray, X_WO_b: np.ndarray) -> float:
    """Angle (degrees) between the object's z axis in pose a and in pose b."""
    za, zb = np.asarray(X_WO_a)[:3, 2], np.asarray(X_WO_b)[:3, 2]
    return float(np.degrees(np.arccos(np.clip(za @ zb, -1.0, 1.0))))


def rotation_deg(X_a: np.ndarray, X_b: np.ndarray) -> float:
    """Rotation angle (degrees) between two poses' orientations."""
    R = np.asarray(X_a)[:3, :3].T @ np.asarray(X_b)[:3, :3]
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0))))


def in_hand_pose(snapshot: Snapshot) -> np.ndarray:
    """X_HO = X_WH^-1 X_WO of a snapshot (needs its hand pose)."""
    if snapshot.X_WH is None:
        raise InputError(f"snapshot at t = {snapshot.time:.3f} s has no hand pose X_WH (the in-hand rule needs it)")
    X_WH = np.asarray(snapshot.X_WH, float)
    R, p = X_WH[:3, :3], X_WH[:3, 3]
    X_HW = np.eye(4)
    X_HW[:3, :3] = R.T
    X_HW[:3, 3] = -R.T @ p
    return X_HW @ np.asarray(snapshot.X_WO, float)


def in_hand_motion(reference: Snapshot, snapshot: Snapshot) -> tuple[float, float]:
    """(shift m, turn deg) of the object relative to the hand from ``reference`` to ``snapshot``."""
    A, B = in_hand_pose(reference), in_hand_pose(snapshot)
    return float(np.linalg.norm(B[:3, 3] - A[:3, 3])), rotation_deg(A, B)


def region_grown_by(name: str, region: dict) -> float:
    """How much the annotated box ``region`` was grown around the part (m): its ``"grown_by"`` key, else
    ``DEFAULT_GROWN_BY[name]`` (trigger 4 mm, handle 3 mm), else 0."""
    value = region.get("grown_by", DEFAULT_GROWN_BY.get(name, 0.0))
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InputError(f"region {name!r}: grown_by must be a number (m), got {value!r}") from None
    if not np.isfinite(value) or value < 0:
        raise InputError(f"region {name!r}: grown_by must be >= 0 (m), got {value}")
    return value


def travel_direction_O(region: dict) -> np.ndarray:
    """Unit travel direction (object frame) of a trigger region: its ``"travel_O"`` key, else −y."""
    d = np.asarray(region.get("travel_O", DEFAULT_TRAVEL_O), float)
    if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) < 1e-9:
        raise InputError(f"travel_O: expected a non-zero 3-vector, got {region.get('travel_O')!r}")
    return d / np.linalg.norm(d)


def points_in_region(points_W, X_WO: np.ndarray, region: dict, margin: float) -> np.ndarray:
    """Boolean mask of world points inside an object-frame axis-aligned box grown by ``margin`` (may be < 0)."""
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


def region_offsets(points_W, X_WO: np.ndarray, region: dict, margin: float) -> np.ndarray:
    """Per point (N, 3): how far (m) each world point lies outside the object-frame box grown by ``margin``,
    along each object axis, signed (+ beyond the box's upper face on that axis, - below its lower; 0 within)."""
    P = np.asarray(points_W, float).reshape(-1, 3)
    c = np.asarray(region["center"], float)
    h = np.maximum(np.asarray(region["half_extents"], float) + margin, 0.0)
    X = np.asarray(X_WO, float)
    d = (P - X[:3, 3]) @ X[:3, :3] - c
    return np.sign(d) * np.maximum(np.abs(d) - h, 0.0)


def object_partners(contacts, object_model: str) -> set[str]:
    """Model instances (other than the object) in contact with the object."""
    out = set()
    for c in contacts:
        if c.model_a() == object_model and c.model_b() != object_model:
            out.add(c.model_b())
        elif c.model_b() == object_model and c.model_a() != object_model:
            out.add(c.model_a())
    return out


def _region(spec: JudgeSpec, region_name: str) -> dict:
    region = spec.regions.get(region_name)
    if region is None:
        raise InputError(f"no {region_name!r} region annotated; regions: {sorted(spec.regions)}")
    return region


def surface_contacts(contacts, spec: JudgeSpec, X_WO: np.ndarray, region_name: str, *, by: str) -> list:
    """Contacts of body/model ``by`` with the object having a point within ``spec.surface_margin`` of the
    part itself: inside the annotated box grown by ``surface_margin - grown_by``."""
    region = _region(spec, region_name)
    margin = spec.surface_margin - region_grown_by(region_name, region)
    return [c for c in contacts if c.involves(spec.object_model) and c.involves(by)
            and points_in_region(c.points_W, X_WO, region, margin).any()]


def region_miss_detail(contacts, spec: JudgeSpec, X_WO: np.ndarray, region_name: str, *, by: str) -> str:
    """How far ``by``'s nearest contact point on the object is from the part ``region_name`` itself."""
    region = _region(spec, region_name)
    own = -region_grown_by(region_name, region)  # the part's own bounding box
    points = [p for c in contacts if c.involves(spec.object_model) and c.involves(by) for p in c.points_W]
    who = by.split("::")[-1]
    if not points:
        return f"{who} does not touch the object"
    off = region_offsets(points, X_WO, region, own)
    nearest = off[int(np.argmin(np.linalg.norm(off, axis=1)))] * 1000.0
    where = " ".join(f"{axis} {v:+.1f}" for axis, v in zip("xyz", nearest) if abs(v) >= 0.05) or "0"
    return f"{who}'s nearest contact point is {np.linalg.norm(nearest):.1f} mm from the {region_name} (needs <= " \
           f"{spec.surface_margin * 1000:.0f} mm; outside its box by {where} mm, object frame)"


def region_touched(contacts, spec: JudgeSpec, X_WO: np.ndarray, region_name: str, *, by: str) -> bool:
    """Whether body/model ``by`` touches the part ``region_name`` (within ``spec.surface_margin`` of it)."""
    return bool(surface_contacts(contacts, spec, X_WO, region_name, by=by))


def trigger_force(contacts, spec: JudgeSpec, X_WO: np.ndarray, region_name: str = "trigger") -> float:
    """Force (N) of the index distal link's contacts on the trigger surface ON THE OBJECT, along the
    trigger's travel direction (summed over those contacts; a contact counts whole when any of its
    points is on the trigger). nan: no such contact, or a contact without a force vector."""
    on = surface_contacts(contacts, spec, X_WO, region_name, by=spec.index_distal_body)
    if not on:
        return math.nan
    forces = [c.force_on(spec.object_model) for c in on]
    if any(f is None for f in forces):
        return math.nan
    d_W = np.asarray(X_WO, float)[:3, :3] @ travel_direction_O(_region(spec, region_name))
    return float(np.sum(forces, axis=0) @ d_W)


# ----------------------------------------------------------------------------- the judge
def judge(spec: JudgeSpec, initial: Snapshot, before_close: Snapshot, after_lift: Snapshot,
          after_hold: Snapshot, after_shake: Snapshot, end: Snapshot) -> Verdict:
    """Grasp and functional success of one executed grasp (rules in the module docstring).

    ``after_lift``, ``after_hold``, ``after_shake`` and ``end`` need the hand pose ``X_WH``.
    """
    return _rules(spec, initial, before_close, after_lift, after_hold, after_shake, end)


def decided_failure(spec: JudgeSpec, initial: Snapshot, before_close: Snapshot, after_lift: Snapshot | None = None,
                    after_hold: Snapshot | None = None, after_shake: Snapshot | None = None) -> Verdict | None:
    """The failure verdict that the snapshots taken so far already decide, or None (not decided yet).

    A trial may stop there: rules 1-3 look at no later snapshot, so the full run's
    :func:`judge` would give the same success flags, reason and detail. Rule 2 needs
    ``after_hold`` too, except for an object not lifted ``min_rise`` by the end of the
    lift: every branch of rule 2 fails it, so it is decided then, with the contacts at
    the end of the lift standing for those at the end of the hold (the flags are the
    full run's; the reason can differ only among ``not_lifted``, ``lifted_short`` and
    ``touched_other``). What the verdict measures (rise, tilt, in-hand motion) is
    measured at the last snapshot given, and there is no trigger force.
    """
    if after_lift is not None and after_hold is None:
        rise = float(np.asarray(after_lift.X_WO)[2, 3]) - float(np.asarray(initial.X_WO)[2, 3])
        if rise < spec.min_rise:
            after_hold = after_lift
    return _rules(spec, initial, before_close, after_lift, after_hold, after_shake, None)


def _rules(spec, initial, before_close, after_lift, after_hold, after_shake, end) -> Verdict | None:
    """:func:`judge` on the snapshots given; a missing one (None) ends the rules there with None."""
    last = next(s for s in (end, after_shake, after_hold, after_lift, before_close) if s is not None)
    z0 = float(np.asarray(initial.X_WO)[2, 3])
    rise_lift = float(np.asarray(after_lift.X_WO)[2, 3]) - z0 if after_lift is not None else math.nan
    rise_end = float(np.asarray(last.X_WO)[2, 3]) - z0
    tilt = tilt_deg(initial.X_WO, last.X_WO)
    motion = {name: in_hand_motion(after_lift, s)
              for name, s in (("hold", after_hold), ("shake", after_shake), ("press", end))
              if s is not None and after_lift is not None and s is not after_lift}
    shift = max((m[0] for m in motion.values()), default=math.nan)
    turn = max((m[1] for m in motion.values()), default=math.nan)
    force = math.nan
    trigger_region = spec.regions.get("trigger") if spec.category in ("drill", "spray_bottle") else None
    if trigger_region is not None and end is not None:
        force = trigger_force(end.contacts, spec, end.X_WO)

    def verdict(grasp, functional, reason, detail=""):
        return Verdict(grasp, functional, reason, detail, rise_end, tilt, force, shift, turn)

    def loose(phase: str) -> str | None:
        """Why the in-hand motion at the end of ``phase`` fails the tolerances (None: within)."""
        s, t = motion[phase]
        if s > spec.in_hand_shift_tol or t > spec.in_hand_turn_tol_deg:
            return f"moved {s * 100:.1f} cm / {t:.0f} deg in the hand by the end of the {phase}"
        return None

    # 1. before closing
    for c in before_close.contacts:
        robot = c.involves(spec.hand_model) or c.involves(spec.arm_model)
        if robot and c.involves(spec.table_model):
            robot_body = c.other(spec.table_model)
            return verdict(False, False, "collision_before_closing", f"{robot_body} touches the table")
    push = float(np.linalg.norm(np.asarray(before_close.X_WO)[:3, 3] - np.asarray(initial.X_WO)[:3, 3]))
    tipped = tilt_deg(initial.X_WO, before_close.X_WO)
    if push > spec.push_tolerance or tipped > spec.push_tilt_deg:
        turned = rotation_deg(initial.X_WO, before_close.X_WO)
        moved = (f"object pushed {push * 100:.1f} cm, tipped {tipped:.0f} deg "
                 f"(turned {turned:.0f} deg) before closing")
        first = before_close.first_move
        if first is not None and not first.robot_contact:
            return verdict(False, False, "fell_by_itself",
                           f"{moved}; it began to move at {first.time:.2f} s with no robot body touching it: "
                           "it does not stand by itself")
        return verdict(False, False, "collision_before_closing", moved)

    # 2. lift and hold
    if after_lift is None or after_hold is None:
        return None
    partners = object_partners(after_hold.contacts, spec.object_model)
    lifted = rise_lift >= spec.min_rise
    rise_text = f"rise {rise_lift * 100:.1f} cm at the end of the lift (needs {spec.min_rise * 100:.0f} cm)"
    if spec.hand_model not in partners:
        if lifted:
            return verdict(False, False, "dropped", f"{rise_text}, no hand contact at the end of the hold")
        return verdict(False, False, "not_lifted", rise_text)
    if spec.table_model in partners:
        if lifted:
            return verdict(False, False, "slipped", "object back on the table at the end of the hold")
        return verdict(False, False, "not_lifted", f"{rise_text}, still on the table")
    others = sorted(partners - {spec.hand_model})
    if others:
        return verdict(False, False, "touched_other", f"object touches {', '.join(others)} during the hold")
    if not lifted and rise_lift <= 0.02:
        return verdict(False, False, "not_lifted", rise_text)
    if not lifted:
        return verdict(False, False, "lifted_short", f"{rise_text}; held off the table, tilted "
                       f"{tilt_deg(initial.X_WO, after_lift.X_WO):.0f} deg during the lift")
    why = loose("hold")
    if why:
        return verdict(False, False, "slipped", why)

    # 3. the disturbance (shake), 4. the press
    for phase, snapshot, reason in (("shake", after_shake, "shaken_loose"), ("press", end, "slipped_on_press")):
        if snapshot is None:
            return None
        partners = object_partners(snapshot.contacts, spec.object_model)
        if spec.hand_model not in partners:
            return verdict(False, False, reason, f"dropped during the {phase}")
        if spec.table_model in partners:
            return verdict(False, False, reason, f"object on the table at the end of the {phase}")
        others = sorted(partners - {spec.hand_model})
        if others:
            return verdict(False, False, "touched_other", f"object touches {', '.join(others)} after the {phase}")
        why = loose(phase)
        if why:
            return verdict(False, False, reason, why)

    # 5. functional success
    needed = {"drill": "trigger", "spray_bottle": "trigger", "mug": "handle"}.get(spec.category)
    if needed is not None and needed not in spec.regions:  # e.g. a scanned bottle without a trigger
        return verdict(True, False, "no_functional_region", f"object has no {needed!r} region annotated")
    if spec.category in ("drill", "spray_bottle"):
        if not region_touched(end.contacts, spec, end.X_WO, "trigger", by=spec.index_distal_body):
            return verdict(True, False, "trigger_missed", "at the end of the press, " + region_miss_detail(
                end.contacts, spec, end.X_WO, "trigger", by=spec.index_distal_body))
        if not force >= spec.min_trigger_force:  # nan (no force vector recorded) fails too
            return verdict(True, False, "trigger_not_pressed",
                           f"index distal force on the trigger along its travel {force:.2f} N "
                           f"(needs {spec.min_trigger_force:.1f} N) at the end of the press")
    elif spec.category == "mug":
        mug_tilt = max(tilt_deg(initial.X_WO, after_shake.X_WO), tilt)
        if mug_tilt > spec.max_tilt_deg:
            return verdict(True, False, "tilted", f"mug tilted {mug_tilt:.0f} deg after the shake")
        if not region_touched(end.contacts, spec, end.X_WO, "handle", by=spec.hand_model):
            return verdict(True, False, "handle_missed", "hand not on the handle: " + region_miss_detail(
                end.contacts, spec, end.X_WO, "handle", by=spec.hand_model))
    return verdict(True, True, None)
