"""Does the hand fit? The preshaped hand at a grasp against an object's true surface, without simulation.

A grasp whose preshaped hand already lies inside the object cannot be executed as written: the
planner's object clearance (:func:`catgrasp_drake.planning.planner.clear_object`) moves the whole
hand out, up to ``PlanParams.max_object_shift``, and with it the index finger off the trigger, or
refuses the grasp (``collision_before_closing``). On real objects and stretched instances the
category's tucked thumb and curled little finger are where it happens (docs/benchmark.md, sessions
20 and 22). :func:`hand_fit` says it before any trial: how deep the preshaped hand is, by link, and
the move the planner will make. :func:`closing_contacts` follows the hand on from there: the order in which
the fingers, thumb and palm meet the object as the hand closes, where, and whether on the functional region.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from catgrasp_drake.core.clearance import clearance_shift
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.planning.model import make_planning_model, object_mesh_path, true_object_field
from catgrasp_drake.planning.records import PlanParams
from catgrasp_drake.planning.scene import hand_surface_samples_H, planning_scene
from catgrasp_drake.station.scenario import Scenario


@dataclass(frozen=True)
class HandFit:
    """The preshaped hand at the grasp pose against the object's true surface (frame O, metres).

    ``link_depths_m``: per hand link, the depth of its deepest surface point inside the object
    (negative: clear of it by that much). ``shift_m`` (3,): the translation (frame O) the planner's
    object clearance moves the grasp by (zero when the hand is within ``tolerance_m``);
    ``plannable``: False when no move within ``max_shift_m`` clears it (the planner refuses the grasp).
    """

    link_depths_m: dict
    shift_m: np.ndarray
    plannable: bool
    tolerance_m: float
    max_shift_m: float

    @property
    def depth_m(self) -> float:
        """Depth of the hand's deepest point inside the object (m; negative: clear by that much)."""
        return max(self.link_depths_m.values())

    def deepest_links(self, k: int = 3) -> list[tuple[str, float]]:
        """The ``k`` deepest links as ``(name, depth_m)``, deepest first."""
        return sorted(self.link_depths_m.items(), key=lambda item: -item[1])[:k]

    def summary(self) -> str:
        """One line: depth, deepest links, and what the planner will do (mm)."""
        links = ", ".join(f"{name.removeprefix('svh_')} {1000 * d:.1f}" for name, d in self.deepest_links())
        head = f"preshaped hand {1000 * self.depth_m:.1f} mm {'inside' if self.depth_m > 0 else 'clear of'} the object"
        if not self.plannable:
            action = (f"no move within {1000 * self.max_shift_m:.0f} mm clears it: the planner refuses the grasp "
                      "(collision_before_closing)")
        elif np.any(self.shift_m):
            action = f"the planner moves the grasp {1000 * float(np.linalg.norm(self.shift_m)):.1f} mm out of it"
        else:
            action = f"within the planner's {1000 * self.tolerance_m:.0f} mm tolerance: executed as written"
        return f"{head} (deepest links, mm: {links}); {action}"


def _hand_against_object(scenario: Scenario, motion_O: GraspMotion, caller: str):
    """``(link_points_O, field)`` for ``motion_O``'s hand at its ``grasp`` pose on ``scenario``'s object:
    ``link_points_O(q_hand, spacing)`` lists ``(link name, surface points (n, 3) in O)`` of the hand in posture
    ``q_hand``; ``field`` is the object's signed-distance grid (positive inside, m; the planner's). InputError
    for a motion not in the object frame or an object without a mesh (a primitive)."""
    if not isinstance(motion_O, GraspMotion) or motion_O.frame != "object":
        raise InputError("motion_O: expected a GraspMotion in the object frame")
    mesh = object_mesh_path(scenario.object)
    if mesh is None:
        raise InputError(f"{caller}: scenario {scenario.name!r} has no object mesh (a primitive object)")
    pm = make_planning_model(scenario)
    context = pm.diagram.CreateDefaultContext()
    plant_context = pm.plant.GetMyMutableContextFromRoot(context)
    sg_context = pm.scene_graph.GetMyMutableContextFromRoot(context)
    X_OH = motion_O.pose("grasp")

    def link_points_O(q_hand, spacing):
        scene = planning_scene(pm.plant, plant_context, pm.scene_graph, sg_context, arm=pm.arm, hand=pm.hand,
                               object_instance=None, table=pm.table, q_arm_start=pm.q_arm_start, q_hand=q_hand)
        inspector = scene.scene_graph.model_inspector()
        return [(inspector.GetName(inspector.GetFrameId(geometry)).split("::")[-1], p_H @ X_OH[:3, :3].T + X_OH[:3, 3])
                for geometry, p_H in hand_surface_samples_H(scene, spacing)]

    return link_points_O, true_object_field(str(mesh))


def hand_fit(scenario: Scenario, motion_O: GraspMotion, params: PlanParams = PlanParams(),
             posture: str = "preshape", spacing: float = 0.003) -> HandFit:
    """The fit of ``motion_O``'s hand (in posture ``posture``, at its ``grasp`` pose, OBJECT frame) on the
    object of ``scenario`` (its true mesh, as the planner's object clearance sees it); hand surface points
    every ``spacing`` m. InputError for a primitive object (no mesh) or a motion not in the object frame."""
    link_points_O, field = _hand_against_object(scenario, motion_O, "hand_fit")
    depths: dict[str, float] = {}
    points = []
    for link, p_O in link_points_O(motion_O.posture(posture), spacing):
        depths[link] = max(depths.get(link, -np.inf), float(field(p_O).max()))
        points.append(p_O)
    tolerance = params.object_penetration_tol
    if tolerance is None:
        return HandFit(depths, np.zeros(3), True, float("inf"), params.max_object_shift)
    r = clearance_shift(np.vstack(points), field, tolerance, params.max_object_shift)
    return HandFit(depths, np.asarray(r.shift, float), bool(r.ok), float(tolerance), float(params.max_object_shift))


#: The hand's links by finger, as :func:`closing_contacts` names them (the palm: the base and the palm's flex link).
FINGER_LINKS = {
    "thumb": ("svh_thumb_base_link", "svh_thumb_proximal_link", "svh_thumb_middle_link", "svh_thumb_distal_link"),
    "index": ("svh_index_knuckle_link", "svh_index_proximal_link", "svh_index_middle_link", "svh_index_distal_link"),
    "middle": ("svh_middle_proximal_link", "svh_middle_middle_link", "svh_middle_distal_link"),
    "ring": ("svh_ring_knuckle_link", "svh_ring_proximal_link", "svh_ring_middle_link", "svh_ring_distal_link"),
    "pinky": ("svh_pinky_knuckle_link", "svh_pinky_proximal_link", "svh_pinky_middle_link", "svh_pinky_distal_link"),
    "palm": ("svh_base_link", "svh_palm_flex_link"),
}


@dataclass(frozen=True)
class FirstContact:
    """Where one finger (or the palm) first meets the object as the hand closes (frame O, metres).

    ``fraction``: how far along the closing (0 the preshape, 1 the closed posture) its surface first lies
    inside the object (None: it never does); ``link``: its link that does; ``point_O``: that link's deepest
    point then; ``in_region``: that point lies within ``region_margin_m`` of the functional region's box
    (None when no region was given)."""

    finger: str
    fraction: float | None
    link: str | None = None
    point_O: np.ndarray | None = None
    in_region: bool | None = None

    def summary(self) -> str:
        if self.fraction is None:
            return f"{self.finger}: never meets the object"
        where = {None: "", True: ", on the functional region", False: ", off the functional region"}[self.in_region]
        p = " ".join(f"{1000 * v:.0f}" for v in self.point_O)
        return (f"{self.finger}: at {100 * self.fraction:.0f} % of the closing, "
                f"{self.link.removeprefix('svh_')} at ({p}) mm{where}")


def closing_contacts(scenario: Scenario, motion_O: GraspMotion, *, region: dict | None = None, steps: int = 20,
                     spacing: float = 0.003, region_margin_m: float = 0.002) -> list[FirstContact]:
    """The order in which the fingers, thumb and palm meet the object of ``scenario`` as ``motion_O``'s hand
    closes at its ``grasp`` pose, without simulation: the posture goes ``preshape -> closed`` in ``steps``
    equal steps (as the planner interpolates it) with the hand held still, and each finger's first step
    with a surface point inside the object's true mesh (the planner's signed-distance grid) is kept.

    A kinematic answer: the object does not move and a finger does not stop where it first touches, so it
    says which finger arrives first and where -- e.g. the index on the trigger's side rather than its front,
    or the thumb before the fingers -- not what the contact then does. ``region`` (``{"center",
    "half_extents"}``, m, O; e.g. the annotated trigger) marks each first contact on or off it. Returns one
    :class:`FirstContact` per entry of :data:`FINGER_LINKS`, earliest first (never-touching fingers last)."""
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise InputError(f"steps: expected a positive integer, got {steps!r}")
    box = None
    if region is not None:
        try:
            box = (np.asarray(region["center"], float).reshape(3), np.asarray(region["half_extents"], float).reshape(3))
        except (KeyError, TypeError, ValueError):
            raise InputError("region: expected {'center': (3,), 'half_extents': (3,)} in metres") from None
    link_points_O, field = _hand_against_object(scenario, motion_O, "closing_contacts")
    finger_of = {link: finger for finger, links in FINGER_LINKS.items() for link in links}
    q_pre, q_closed = motion_O.posture("preshape"), motion_O.posture("closed")
    found: dict[str, FirstContact] = {}
    for k in range(steps + 1):
        f = k / steps
        deepest: dict[str, tuple[float, str, np.ndarray]] = {}  # finger -> its deepest point inside, this step
        for link, p_O in link_points_O(q_pre + f * (q_closed - q_pre), spacing):
            finger = finger_of.get(link)
            if finger is None or finger in found:
                continue
            depth = field(p_O)
            i = int(np.argmax(depth))
            if depth[i] > deepest.get(finger, (0.0,))[0]:
                deepest[finger] = (float(depth[i]), link, p_O[i])
        for finger, (_, link, p) in deepest.items():
            in_region = None if box is None else bool(np.all(np.abs(p - box[0]) <= box[1] + region_margin_m))
            found[finger] = FirstContact(finger, f, link, p, in_region)
    never = [FirstContact(finger, None) for finger in FINGER_LINKS if finger not in found]
    return sorted(found.values(), key=lambda c: c.fraction) + never
