"""The grasp planner: joint knots executing a world-frame ``GraspMotion``, one function per phase.

:func:`plan_grasp` runs once per trial, before the simulation, with Drake's
``InverseKinematics`` (SNOPT when available) on a planning scene
(:mod:`catgrasp_drake.planning.scene`):

- object clearance (:func:`clear_object`), where the object's surface is
  known: a preshaped hand that would lie more than ``object_penetration_tol``
  inside the object at the grasp is moved out by the smallest translation
  (pregrasp and grasp together, at most ``max_object_shift``), so the reach
  does not knock the object over before the fingers close;
- table clearance (:func:`clear_table`): the pregrasp and grasp poses are
  raised (by at most ``max_table_raise``) until the preshaped hand's
  collision primitives and the wrist flange it is mounted on are
  ``table_clearance`` above the table top;
- ``home -> pregrasp`` (:func:`plan_approach`): joint-space cubic from the
  arm's start configuration to an IK solution of the pregrasp pose. IK seeds
  are tried in a fixed order (structured seeds, then ``pregrasp_restarts``
  seeded random ones); the first collision-free solution that some approach
  path reaches wins: direct, through a via pose ``via_heights`` above the
  pregrasp, or with the elbow raised first. Each path is checked densely in
  joint space (``approach_margin`` from table and object).
- ``reach`` (:func:`plan_reach`): pregrasp -> grasp on a straight line
  (position interpolated, orientation slerped), ``reach_knots`` IK knots,
  each seeded from the previous solution so the arm stays on one branch;
  robot vs table kept apart.
- ``close``: the arm holds; the hand goes preshape -> closed (the PD-gained,
  effort-limited hand actuators close compliantly on the object).
- ``lift`` (:func:`plan_lift`): straight up by ``lift_height`` in ``lift_knots`` IK knots.
- ``hold``: constant for ``hold_time`` (+ ``hold_margin``).
- ``shake`` (:func:`shake_knots`): the disturbance of the judge (DESIGN.md
  section 6): the hand base moved along world z sinusoidally for
  ``shake_time`` (1 s), peak acceleration ``shake_accel`` (2 m/s^2) at
  ``shake_frequency`` (2 Hz): ``dz(t) = A (1 - cos(2 pi f t))`` with
  ``A = a / (2 pi f)^2`` (1.27 cm), i.e. ±A about a mean A above the lifted
  height, orientation fixed. This is the one sinusoid that starts (and, after
  whole periods, ends) at rest: a plain ``A sin`` would start with a velocity
  step (an unbounded acceleration; interpolated, 11 m/s^2 instead of 2).
  Knots (``shake_knots_per_s``, 16/s: 8 per period) from the arm Jacobian at
  the lifted configuration, ``dq = lstsq(J, [0, 0, 0, 0, 0, dz])``, refined
  by a few Newton steps on the Jacobian so the hand keeps its orientation and
  horizontal position; they carry their exact velocities
  (``GraspPlan.v_arm``), so the executed cubic's peak acceleration is
  2.1 m/s^2 (a shape-preserving cubic through the same knots reaches 3.8).
- ``press`` (:func:`press_posture`): the arm holds; the index finger's
  actuated joints (``INDEX_ACTUATED_JOINTS``) are commanded to their upper
  joint limits over ``press_ramp`` and held there to the end of
  ``press_time`` (0.5 s), the rest of the hand holding its closed posture
  (the judge's trigger press; harmless for objects without one).
- ``end``: the last instant (end of the press).

The hand goes ``open -> preshape`` during the approach. :func:`timeline_and_knots`
lays the phases out in time.

A plan that cannot be made is REPORTED in ``GraspPlan.status``
(``"unreachable: pregrasp"``, ``"ik_failed: grasp"``,
``"collision: pregrasp"``, ``"branch_flip: reach"`` ...): a phase raises
:class:`PlanFailure`, :func:`plan_grasp` turns it into a plan that holds the
start configuration with the hand open. Nothing raises into the simulation.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from pydrake.geometry import CollisionFilterDeclaration
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable, ModelInstanceIndex

from catgrasp_drake.core.clearance import SignedDistanceGrid, clearance_shift
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.planning.records import GraspPlan, PlanParams, Timeline, hold_plan
from catgrasp_drake.planning.scene import (
    PlanningScene,
    collision_filters,
    collisions,
    hand_surface_points_H,
    min_distance,
    path_collides,
    planning_scene,
    robot_collides,
    solve_ik,
    solve_ik_continuous,
    table_raise,
)
from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS, INDEX_ACTUATED_JOINTS, THUMB_ACTUATED_JOINTS

#: Joint offset (rad, ARM_JOINTS order) from the start that lifts the shoulder and bends the elbow:
#: a pregrasp IK seed, and the first knot of approaches that must clear the table.
ELBOW_RAISED = np.array([0.0, -0.4, 0.6, -0.2, 0.0, 0.0])
#: Positions of ``THUMB_ACTUATED_JOINTS`` in a hand posture (``HAND_ACTUATED_JOINTS`` order).
THUMB_JOINT_INDICES = [HAND_ACTUATED_JOINTS.index(j) for j in THUMB_ACTUATED_JOINTS]


class PlanFailure(Exception):
    """A phase cannot be planned; ``status`` is the plan's status (``"ik_failed: reach"`` ...)."""

    def __init__(self, status: str):
        super().__init__(status)
        self.status = status


def interpolate_poses(X_A: RigidTransform, X_B: RigidTransform, n: int) -> list[RigidTransform]:
    """``n`` poses from A (exclusive) to B (inclusive): linear position, slerped rotation."""
    qa, qb = X_A.rotation().ToQuaternion(), X_B.rotation().ToQuaternion()
    out = []
    for s in np.linspace(0.0, 1.0, n + 1)[1:]:
        R = RotationMatrix(qa.slerp(s, qb))
        out.append(RigidTransform(R, (1 - s) * X_A.translation() + s * X_B.translation()))
    return out


# ----------------------------------------------------------------------------- table clearance
def clear_table(c: PlanningScene, X: dict[str, RigidTransform], params: PlanParams) -> dict[str, RigidTransform]:
    """The pregrasp and grasp poses ``X`` raised until the hand clears the table, checked against the arm's reach."""
    raise_m = table_raise(c, list(X.values()), params.table_clearance)
    if raise_m > params.max_table_raise:
        raise PlanFailure(f"collision: hand {1000 * (raise_m - params.table_clearance):.0f} mm into the table")
    X = {name: RigidTransform(X_WH.rotation(), X_WH.translation() + [0.0, 0.0, raise_m]) for name, X_WH in X.items()}
    for name, X_WH in X.items():
        if np.linalg.norm(X_WH.translation() - c.shoulder_W) > params.max_reach:
            raise PlanFailure(f"unreachable: {name}")
    return X


# ----------------------------------------------------------------------------- object clearance
@dataclass(frozen=True)
class ObjectSurface:
    """The object as the planner knows its surface: ``field`` (signed distance, positive inside) in the
    object's frame O, and ``X_WO`` (4x4) its pose in the world."""

    field: SignedDistanceGrid
    X_WO: np.ndarray


def clear_object(c: PlanningScene, X: dict[str, RigidTransform], surface: ObjectSurface | None,
                 params: PlanParams) -> tuple[dict[str, RigidTransform], np.ndarray]:
    """``(poses, shift_W)``: the pregrasp and grasp moved together by the smallest translation (m, W) that
    brings the preshaped hand at the grasp to at most ``params.object_penetration_tol`` inside the object.

    A grasp whose preshaped hand would already lie inside the object sweeps into it on the reach and
    knocks it before the fingers close (a real drill's handle thicker than the generator's meets the
    thumb). Unchanged when ``surface`` is None, the check is off or the hand is clear; a hand that needs
    more than ``params.max_object_shift`` is refused (``collision: grasp``).
    """
    if surface is None or params.object_penetration_tol is None:
        return X, np.zeros(3)
    X_OW = np.linalg.inv(surface.X_WO)
    M = X_OW @ X["grasp"].GetAsMatrix4()
    p_O = hand_surface_points_H(c) @ M[:3, :3].T + M[:3, 3]
    r = clearance_shift(p_O, surface.field, params.object_penetration_tol, params.max_object_shift)
    if not r.ok:
        raise PlanFailure(f"collision: grasp (the preshaped hand {1000 * r.depth_before:.0f} mm inside the object; "
                          f"no move within {1000 * params.max_object_shift:.0f} mm clears it)")
    shift_W = surface.X_WO[:3, :3] @ r.shift
    if not shift_W.any():
        return X, shift_W
    return {name: RigidTransform(X_WH.rotation(), X_WH.translation() + shift_W) for name, X_WH in X.items()}, shift_W


# ----------------------------------------------------------------------------- pregrasp and approach
def pregrasp_seeds(q_start: np.ndarray, params: PlanParams):
    """(min_distance, wrist_up, seed) of the pregrasp IK attempts, in order.

    Wrist up, wrist up with minimum distance, free, free with minimum distance; each from the start,
    from the start with the elbow raised and from that with the wrist turned over (SNOPT is local: one
    seed can be stuck on the branch that lays the forearm on the table, or twists the wrist under a
    hand working low); then random restarts about the start (fixed seed: deterministic).
    """
    flip = np.array([0.0, 0.0, 0.0, 0.0, 0.85 * np.pi, 1.5 * np.pi])
    for wrist_up, distance in ((True, None), (True, params.min_distance), (False, None),
                               (False, params.min_distance)):
        for seed in (q_start, q_start + ELBOW_RAISED, q_start + ELBOW_RAISED + flip):
            yield distance, wrist_up, seed
    rng = np.random.default_rng(20181)
    for _ in range(params.pregrasp_restarts):
        spread = np.array([1.2, 1.0, 1.5, 1.5, np.pi, np.pi])
        yield params.min_distance, False, q_start + rng.uniform(-1.0, 1.0, 6) * spread


def approach_candidates(c: PlanningScene, X_WPre: RigidTransform, q_start: np.ndarray, q_pre: np.ndarray,
                        params: PlanParams):
    """Knot lists (after the start) ending at ``q_pre``, simplest first (a generator: IK runs on demand)."""
    yield [q_pre]
    vias = []
    for height in params.via_heights:
        X_via = RigidTransform(X_WPre.rotation(), X_WPre.translation() + [0.0, 0.0, height])
        ok, q_via = solve_ik(c, X_via, q_pre, params, min_distance=params.min_distance)
        if ok:
            vias.append(q_via)
            yield [q_via, q_pre]
    q_raised = q_start + ELBOW_RAISED
    yield [q_raised, q_pre]
    for q_via in vias:
        yield [q_raised, q_via, q_pre]


def plan_approach(c: PlanningScene, X_WPre: RigidTransform, q_arm_start: np.ndarray,
                  params: PlanParams) -> tuple[np.ndarray, list[np.ndarray]]:
    """``(q_pre_arm, approach_knots)``: the pregrasp configuration and the knots leading to it from the start.

    The first collision-free pregrasp IK solution (in the order of :func:`pregrasp_seeds`) that an
    approach path from the start reaches without meeting the table or object.
    """
    attempts = []  # (collision-free, q_pre) of every distinct IK solution
    for distance, wrist_up, seed in pregrasp_seeds(q_arm_start, params):
        ok, q = solve_ik(c, X_WPre, seed, params, min_distance=distance, wrist_up=wrist_up)
        if not ok or any(np.abs(q - q_seen).max() < 1e-3 for _, q_seen in attempts):
            continue
        free = not robot_collides(c, q)
        attempts.append((free, q))
        if not free:
            continue
        # the margin shrinks to what the pregrasp itself leaves (a hand working low over the table)
        margin = min(params.approach_margin, 0.5 * min_distance(c, q, params.approach_margin))
        for candidate in approach_candidates(c, X_WPre, q_arm_start, q, params):
            if not path_collides(c, [q_arm_start] + candidate, margin):
                return q, candidate
    if not attempts:
        raise PlanFailure("ik_failed: pregrasp")
    if not any(free for free, _ in attempts):
        raise PlanFailure(f"collision: pregrasp ({'; '.join(collisions(c, attempts[0][1])[:3])})")
    raise PlanFailure("collision: approach (every path from the start to the pregrasp meets the table or object)")


# ----------------------------------------------------------------------------- reach and lift
def plan_reach(c: PlanningScene, X_WPre: RigidTransform, X_WGrasp: RigidTransform, q_pre_arm: np.ndarray,
               params: PlanParams) -> list[np.ndarray]:
    """Arm knots along the straight line pregrasp -> grasp (the last one at the grasp); robot vs table only."""
    manager = collision_filters(c)
    id_obj = manager.ApplyTransient(CollisionFilterDeclaration().ExcludeBetween(c.robot_geoms, c.object_geoms))
    try:
        reach = []
        q_prev = q_pre_arm
        for k, X_WH in enumerate(interpolate_poses(X_WPre, X_WGrasp, params.reach_knots)):
            # robot vs table kept apart where possible: an arm grazing the table at the grasp lies on it once
            # the controller tracks the plan under load
            ok, q_k = solve_ik_continuous(c, X_WH, q_prev, params, min_distance=params.reach_min_distance)
            last = k == params.reach_knots - 1
            if not ok:
                raise PlanFailure("ik_failed: grasp" if last else "ik_failed: reach")
            if np.abs(q_k - q_prev).max() > params.max_knot_jump:
                raise PlanFailure("branch_flip: reach")
            reach.append(q_k)
            q_prev = q_k
        in_table = collisions(c, reach[-1], margin=-0.003)  # > 3 mm into the table
    finally:
        manager.RemoveDeclaration(id_obj)
    if in_table:
        raise PlanFailure(f"collision: grasp ({'; '.join(in_table[:3])})")
    return reach


def plan_lift(c: PlanningScene, X_WGrasp: RigidTransform, q_grasp: np.ndarray, lift_height: float,
              params: PlanParams) -> list[np.ndarray]:
    """Arm knots lifting the hand straight up by ``lift_height`` (object attached; no collision constraints)."""
    X_lift = RigidTransform(X_WGrasp.rotation(), X_WGrasp.translation() + [0, 0, lift_height])
    lift = []
    q_prev = q_grasp
    for X_WH in interpolate_poses(X_WGrasp, X_lift, params.lift_knots):
        ok, q_k = solve_ik_continuous(c, X_WH, q_prev, params)
        if not ok:
            raise PlanFailure("ik_failed: lift")
        if np.abs(q_k - q_prev).max() > params.max_knot_jump:
            raise PlanFailure("branch_flip: lift")
        lift.append(q_k)
        q_prev = q_k
    return lift


# ----------------------------------------------------------------------------- shake and press
def shake_amplitude(params: PlanParams) -> float:
    """Amplitude (m) of the shake: peak acceleration / (2 pi f)^2."""
    return params.shake_accel / (2.0 * np.pi * params.shake_frequency) ** 2


def shake_knots(c: PlanningScene, q_lift: np.ndarray, params: PlanParams) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """(time after the shake's start, arm q, arm v) knots moving frame H by ``A (1 - cos(2 pi f t))`` along z.

    Each knot starts from the linear step ``dq = lstsq(J_arm, [0, 0, 0, 0, 0, dz])`` (``J_arm``: the
    arm's columns of H's spatial-velocity Jacobian, angular then translational, in W, at ``q_lift``)
    and is refined by a few Newton steps on the same Jacobian at the knot, so that H keeps its lifted
    orientation and horizontal position (the linear step alone is 0.4 mm off at the top, 2.5 cm up).
    The velocity is ``lstsq(J_arm(q), [0, 0, 0, 0, 0, dz/dt])``. Starts at rest at ``q_lift``; the
    last knot, at ``shake_time``, is back there at rest when the shake spans whole periods (1 s at 2 Hz).
    """
    plant = c.plant
    q_full = c.q_full.copy()
    ez = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0])

    def pose_and_jacobian(q_arm):
        q_full[c.arm_q_idx] = q_arm
        plant.SetPositions(c.plant_context, q_full)
        J = plant.CalcJacobianSpatialVelocity(c.plant_context, JacobianWrtVariable.kQDot, c.frame_H, np.zeros(3),
                                              plant.world_frame(), plant.world_frame())
        return c.frame_H.CalcPoseInWorld(c.plant_context), J[:, c.arm_q_idx]

    q_lift = np.asarray(q_lift, float)
    X_lift, J_lift = pose_and_jacobian(q_lift)
    dq_dz = np.linalg.lstsq(J_lift, ez, rcond=None)[0]
    amplitude = shake_amplitude(params)
    omega = 2.0 * np.pi * params.shake_frequency
    n = max(1, int(round(params.shake_knots_per_s * params.shake_time)))
    out = []
    for k in range(1, n + 1):
        dt = params.shake_time * k / n
        dz, vz = amplitude * (1.0 - np.cos(omega * dt)), amplitude * omega * np.sin(omega * dt)
        p_target = X_lift.translation() + [0.0, 0.0, dz]
        q = q_lift + dq_dz * dz
        for _ in range(3):
            X, J = pose_and_jacobian(q)
            rot = (X_lift.rotation() @ X.rotation().inverse()).ToAngleAxis()
            error = np.concatenate([rot.angle() * rot.axis(), p_target - X.translation()])
            if np.abs(error).max() < 1e-9:
                break
            q = q + np.linalg.lstsq(J, error, rcond=None)[0]
        _, J = pose_and_jacobian(q)
        out.append((dt, q, np.linalg.lstsq(J, ez * vz, rcond=None)[0]))
    return out


def press_posture(plant: MultibodyPlant, hand: ModelInstanceIndex, q_closed: np.ndarray) -> np.ndarray:
    """``q_closed`` with the index finger's actuated joints at (at least) their upper limits."""
    q_press = np.asarray(q_closed, float).copy()
    for name in INDEX_ACTUATED_JOINTS:
        j = HAND_ACTUATED_JOINTS.index(name)
        q_press[j] = max(q_press[j], float(plant.GetJointByName(name, hand).position_upper_limits()[0]))
    return q_press


# ----------------------------------------------------------------------------- timeline
def timeline_and_knots(q_arm_start: np.ndarray, postures: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
                       approach_knots: list[np.ndarray], reach: list[np.ndarray], lift: list[np.ndarray],
                       shake: list[tuple[float, np.ndarray, np.ndarray]], hold_time: float,
                       params: PlanParams) -> tuple[Timeline, np.ndarray, np.ndarray, np.ndarray, tuple, np.ndarray]:
    """The phases laid out in time: ``(timeline, times, q_arm, q_hand, knot_names, v_arm)``.

    ``postures``: the hand's (open, preshape, closed, press) postures. The approach lasts
    ``max(min_approach_time, largest summed joint motion / max_joint_speed)``; its knots are spread
    by the largest joint motion of each segment.
    """
    q_open, q_pre, q_closed, q_press = postures
    q_grasp = reach[-1]
    path = np.vstack([q_arm_start] + approach_knots)
    t_approach_dur = max(params.min_approach_time,
                         float(np.abs(np.diff(path, axis=0)).sum(axis=0).max()) / params.max_joint_speed)
    tl = {}
    times, qa, qh, names, va = [], [], [], [], []

    def knot(t, q_arm, q_hand, name, v_arm=None):
        times.append(t)
        qa.append(np.asarray(q_arm, float))
        qh.append(np.asarray(q_hand, float))
        names.append(name)
        va.append(np.full(len(qa[-1]), np.nan) if v_arm is None else np.asarray(v_arm, float))

    t = 0.0
    tl["settle"] = t
    knot(t, q_arm_start, q_open, "start")
    t += params.settle_time
    tl["approach"] = t
    knot(t, q_arm_start, q_open, "approach")
    n_app = len(approach_knots)
    segment = np.abs(np.diff(path, axis=0)).max(axis=1)  # time along the approach ~ largest joint motion
    share = np.cumsum(segment) / segment.sum() if segment.sum() > 0 else np.arange(1, n_app + 1) / n_app
    for i, q in enumerate(approach_knots):
        knot(t + t_approach_dur * share[i], q, q_open + (q_pre - q_open) * (i + 1) / n_app,
             "via" if i < n_app - 1 else "pregrasp")
    t += t_approach_dur
    tl["reach"] = t
    for i, q in enumerate(reach):
        knot(t + params.reach_time * (i + 1) / len(reach), q, q_pre, "grasp" if i == len(reach) - 1 else "reach")
    t += params.reach_time
    tl["close"] = t
    if params.close_order == "thumb_first":  # the thumb closed half-way, the other fingers still preshaped
        q_thumb = q_pre.copy()
        q_thumb[THUMB_JOINT_INDICES] = q_closed[THUMB_JOINT_INDICES]
        knot(t + 0.5 * params.close_time, q_grasp, q_thumb, "thumb_closed")
    knot(t + params.close_time, q_grasp, q_closed, "closed")
    t += params.close_time + params.close_dwell
    knot(t, q_grasp, q_closed, "closed_dwell")
    tl["lift"] = t
    for i, q in enumerate(lift):
        knot(t + params.lift_time * (i + 1) / len(lift), q, q_closed, "lifted" if i == len(lift) - 1 else "lift")
    t += params.lift_time
    tl["hold"] = t
    t += hold_time + params.hold_margin
    knot(t, lift[-1], q_closed, "hold_end", np.zeros(len(lift[-1])))
    tl["shake"] = t
    for i, (dt, q, v) in enumerate(shake):
        knot(t + dt, q, q_closed, "shaken" if i == len(shake) - 1 else "shake", v)
    t += params.shake_time
    tl["press"] = t
    q_shaken = shake[-1][1]
    ramp = min(params.press_ramp, params.press_time)
    if 0.0 < ramp < params.press_time:
        knot(t + ramp, q_shaken, q_press, "pressed")
    t += params.press_time
    knot(t, q_shaken, q_press, "end")
    tl["end"] = t
    return Timeline(**tl), np.array(times), np.array(qa), np.array(qh), tuple(names), np.array(va)


# ----------------------------------------------------------------------------- planner
def plan_grasp(plant: MultibodyPlant, plant_context, scene_graph, sg_context, *, arm: ModelInstanceIndex,
               hand: ModelInstanceIndex, object_instance: ModelInstanceIndex | None, table: ModelInstanceIndex,
               motion_W: GraspMotion, q_arm_start, params: PlanParams = PlanParams(),
               object_surface: ObjectSurface | None = None, object_geometry_ids=()) -> GraspPlan:
    """Plan the joint trajectories executing ``motion_W`` (poses in the WORLD frame).

    ``plant_context``/``sg_context`` must be a SCRATCH context of the diagram
    holding ``plant`` and ``scene_graph`` (its positions and collision
    filters are modified). The object is ``object_instance``'s geometry and the
    ``object_geometry_ids`` (e.g. registered in ``sg_context`` only); neither:
    a planning model without the object (robot vs table only). ``object_surface``: the object's surface,
    for :func:`clear_object` (None: not checked). Never raises for unreachable
    or colliding poses: the returned plan's ``status`` says what failed.
    """
    if not isinstance(motion_W, GraspMotion) or motion_W.frame != "world":
        raise InputError("plan_grasp: needs a GraspMotion in the world frame (motion.in_world(X_WO))")
    t_start = time.perf_counter()
    q_arm_start = np.asarray(q_arm_start, float)
    postures = motion_W.postures
    q_open, q_pre, q_closed = (np.asarray(postures[k]) for k in ("open", "preshape", "closed"))
    c = planning_scene(plant, plant_context, scene_graph, sg_context, arm=arm, hand=hand,
                       object_instance=object_instance, table=table, q_arm_start=q_arm_start, q_hand=q_pre,
                       object_geometry_ids=object_geometry_ids)
    try:
        X, shift_W = clear_object(c, {name: RigidTransform(motion_W.pose(name)) for name in ("pregrasp", "grasp")},
                                  object_surface, params)
        X = clear_table(c, X, params)
        q_pre_arm, approach_knots = plan_approach(c, X["pregrasp"], q_arm_start, params)
        reach = plan_reach(c, X["pregrasp"], X["grasp"], q_pre_arm, params)
        lift = plan_lift(c, X["grasp"], reach[-1], motion_W.lift_height, params)
    except PlanFailure as failure:
        p = hold_plan(q_arm_start, q_open, failure.status)
        return GraspPlan(p.status, p.timeline, p.times, p.q_arm, p.q_hand, p.knot_names,
                         time.perf_counter() - t_start)
    shake = shake_knots(c, lift[-1], params)
    q_press = press_posture(plant, hand, q_closed)
    timeline, times, qa, qh, names, va = timeline_and_knots(
        q_arm_start, (q_open, q_pre, q_closed, q_press), approach_knots, reach, lift, shake, motion_W.hold_time,
        params)
    return GraspPlan("ok", timeline, times, qa, qh, names, time.perf_counter() - t_start, va,
                     object_shift=tuple(float(v) for v in shift_W))
