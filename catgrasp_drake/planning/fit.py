"""Does the hand fit? The preshaped hand at a grasp against an object's true surface, without simulation.

A grasp whose preshaped hand already lies inside the object cannot be executed as written: the
planner's object clearance (:func:`catgrasp_drake.planning.planner.clear_object`) moves the whole
hand out, up to ``PlanParams.max_object_shift``, and with it the index finger off the trigger, or
refuses the grasp (``collision_before_closing``). On real objects and stretched instances the
category's tucked thumb and curled little finger are where it happens (docs/benchmark.md, sessions
20 and 22). :func:`hand_fit` says it before any trial: how deep the preshaped hand is, by link, and
the move the planner will make.
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


def hand_fit(scenario: Scenario, motion_O: GraspMotion, params: PlanParams = PlanParams(),
             posture: str = "preshape", spacing: float = 0.003) -> HandFit:
    """The fit of ``motion_O``'s hand (in posture ``posture``, at its ``grasp`` pose, OBJECT frame) on the
    object of ``scenario`` (its true mesh, as the planner's object clearance sees it); hand surface points
    every ``spacing`` m. InputError for a primitive object (no mesh) or a motion not in the object frame."""
    if not isinstance(motion_O, GraspMotion) or motion_O.frame != "object":
        raise InputError("motion_O: expected a GraspMotion in the object frame")
    mesh = object_mesh_path(scenario.object)
    if mesh is None:
        raise InputError(f"hand_fit: scenario {scenario.name!r} has no object mesh (a primitive object)")
    pm = make_planning_model(scenario)
    context = pm.diagram.CreateDefaultContext()
    scene = planning_scene(pm.plant, pm.plant.GetMyMutableContextFromRoot(context), pm.scene_graph,
                           pm.scene_graph.GetMyMutableContextFromRoot(context), arm=pm.arm, hand=pm.hand,
                           object_instance=None, table=pm.table, q_arm_start=pm.q_arm_start,
                           q_hand=motion_O.posture(posture))
    inspector = scene.scene_graph.model_inspector()
    X_OH = motion_O.pose("grasp")
    field = true_object_field(str(mesh))
    depths: dict[str, float] = {}
    points = []
    for geometry, p_H in hand_surface_samples_H(scene, spacing):
        p_O = p_H @ X_OH[:3, :3].T + X_OH[:3, 3]
        link = inspector.GetName(inspector.GetFrameId(geometry)).split("::")[-1]
        depths[link] = max(depths.get(link, -np.inf), float(field(p_O).max()))
        points.append(p_O)
    tolerance = params.object_penetration_tol
    if tolerance is None:
        return HandFit(depths, np.zeros(3), True, float("inf"), params.max_object_shift)
    r = clearance_shift(np.vstack(points), field, tolerance, params.max_object_shift)
    return HandFit(depths, np.asarray(r.shift, float), bool(r.ok), float(tolerance), float(params.max_object_shift))
