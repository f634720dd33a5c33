"""The planning scene and its queries: IK, collisions, distances, table clearance.

A :class:`PlanningScene` is a plant with SCRATCH contexts (its positions and
collision filters are changed by every query), the indices of the arm's and
the hand's joints, the hand base frame H and the geometry sets of robot,
object and table. Everything but the arm stays at ``q_full`` (the hand in its
preshape); every query takes the arm's joint angles (``ARM_JOINTS`` order).

:func:`planning_scene` builds one and applies the planning-only collision
filters: robot vs itself and object vs table never count.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.geometry import Box, Capsule, CollisionFilterDeclaration, Cylinder, GeometrySet, Role, Sphere
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.inverse_kinematics import InverseKinematics
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex
from pydrake.solvers import SnoptSolver, Solve

from catgrasp_drake.planning.records import PlanParams
from catgrasp_drake.robot.models import ARM_JOINTS, HAND_ACTUATED_JOINTS, HAND_BASE_LINK, hand_joint_angles


@dataclass
class PlanningScene:
    """A plant with scratch contexts and what the planner's queries need of it (module docstring)."""

    plant: MultibodyPlant
    plant_context: object
    sg_context: object
    scene_graph: object
    arm_q_idx: np.ndarray  # indices into plant q of the arm joints (ARM_JOINTS order)
    hand_q_idx: np.ndarray  # indices of the hand's actuated joints (HAND_ACTUATED_JOINTS order)
    frame_H: object
    frame_wrist: object  # body frame of the arm's wrist-1 link
    q_full: np.ndarray  # the fixed configuration of everything but the arm
    robot_geoms: GeometrySet
    carried_ids: list  # proximity geometry ids rigid with H: the hand's (in q_full) and the arm's last link
    hand_ids: list  # the hand's proximity geometry ids
    object_geoms: GeometrySet
    table_geoms: GeometrySet
    table_ids: list
    shoulder_W: np.ndarray


def planning_scene(plant: MultibodyPlant, plant_context, scene_graph, sg_context, *, arm: ModelInstanceIndex,
                   hand: ModelInstanceIndex, object_instance: ModelInstanceIndex | None, table: ModelInstanceIndex,
                   q_arm_start: np.ndarray, q_hand: np.ndarray, object_geometry_ids=()) -> PlanningScene:
    """The scene of ``plant`` with the hand at posture ``q_hand`` (mimic followers consistent), filters applied.

    ``plant_context``/``sg_context``: a SCRATCH context of the diagram holding
    ``plant`` and ``scene_graph``. The object is the proximity geometry of
    ``object_instance`` and the ``object_geometry_ids`` (e.g. registered in
    ``sg_context`` only); neither: no object (robot vs table only).
    ``shoulder_W`` is the shoulder's position with the arm at ``q_arm_start``.
    """
    arm_q_idx = np.array([plant.GetJointByName(n, arm).position_start() for n in ARM_JOINTS])
    hand_q_idx = np.array([plant.GetJointByName(n, hand).position_start() for n in HAND_ACTUATED_JOINTS])
    q_full = np.asarray(plant.GetPositions(plant_context), float).copy()
    # the hand in preshape, mimic followers consistent (IK enforces the plant's coupler constraints)
    for name, angle in hand_joint_angles(q_hand).items():
        q_full[plant.GetJointByName(name, hand).position_start()] = angle
    frame_H = plant.GetFrameByName(HAND_BASE_LINK, hand)
    shoulder = plant.GetJointByName(ARM_JOINTS[1], arm).frame_on_child()
    q_tmp = q_full.copy()
    q_tmp[arm_q_idx] = q_arm_start
    plant.SetPositions(plant_context, q_tmp)
    shoulder_W = shoulder.CalcPoseInWorld(plant_context).translation()
    frame_wrist = plant.GetJointByName(ARM_JOINTS[3], arm).child_body().body_frame()
    object_instances = [object_instance] if object_instance is not None else []
    hand_ids = geometry_ids(plant, scene_graph, [hand])
    scene = PlanningScene(
        plant, plant_context, sg_context, scene_graph, arm_q_idx, hand_q_idx, frame_H, frame_wrist, q_full,
        robot_geoms=geometry_set(plant, scene_graph, [arm, hand]),
        carried_ids=hand_ids + body_geometry_ids(scene_graph, plant.GetJointByName(ARM_JOINTS[-1], arm).child_body()),
        hand_ids=hand_ids,
        object_geoms=GeometrySet(geometry_ids(plant, scene_graph, object_instances) + list(object_geometry_ids)),
        table_geoms=geometry_set(plant, scene_graph, [table]),
        table_ids=geometry_ids(plant, scene_graph, [table]), shoulder_W=shoulder_W)
    # Planning-only collision filters: robot vs itself and object vs table never count.
    collision_filters(scene).Apply(CollisionFilterDeclaration().ExcludeWithin(scene.robot_geoms)
                                   .ExcludeBetween(scene.object_geoms, scene.table_geoms))
    return scene


def collision_filters(scene: PlanningScene):
    """The scene's ``CollisionFilterManager`` (on its scratch scene-graph context)."""
    return scene.scene_graph.collision_filter_manager(scene.sg_context)


# ----------------------------------------------------------------------------- geometry
def geometry_ids(plant: MultibodyPlant, scene_graph, instances) -> list:
    """Proximity geometry ids of every body of the model ``instances``."""
    return [g for inst in instances for bi in plant.GetBodyIndices(inst)
            for g in body_geometry_ids(scene_graph, plant.get_body(bi))]


def body_geometry_ids(scene_graph, body) -> list:
    """Proximity geometry ids of one body (its frame may carry none)."""
    fid = body.GetParentPlant().GetBodyFrameIdIfExists(body.index())
    return [] if fid is None else list(scene_graph.model_inspector().GetGeometries(fid, Role.kProximity))


def geometry_set(plant: MultibodyPlant, scene_graph, instances) -> GeometrySet:
    return GeometrySet(geometry_ids(plant, scene_graph, instances))


# ----------------------------------------------------------------------------- IK
def solve_ik(c: PlanningScene, X_WH: RigidTransform, q_seed_arm: np.ndarray, params: PlanParams,
             min_distance: float | None = None, wrist_up: bool = False) -> tuple[bool, np.ndarray]:
    """Arm joint angles putting frame H at ``X_WH``; everything else fixed at ``c.q_full``.

    ``wrist_up`` keeps the wrist-1 body's origin ``wrist_clearance`` above H
    (forearm and wrist stay above a hand working low over the table).
    """
    plant = c.plant
    ik = InverseKinematics(plant, c.plant_context, with_joint_limits=True)
    q = ik.q()
    prog = ik.get_mutable_prog()
    others = np.setdiff1d(np.arange(plant.num_positions()), c.arm_q_idx)
    prog.AddBoundingBoxConstraint(c.q_full[others], c.q_full[others], q[others])
    p = X_WH.translation()
    tol = params.position_tol
    ik.AddPositionConstraint(c.frame_H, np.zeros(3), plant.world_frame(), p - tol, p + tol)
    ik.AddOrientationConstraint(plant.world_frame(), X_WH.rotation(), c.frame_H, RotationMatrix(),
                                params.orientation_tol)
    if wrist_up:
        ik.AddPositionConstraint(c.frame_wrist, np.zeros(3), plant.world_frame(),
                                 [-np.inf, -np.inf, p[2] + params.wrist_clearance], [np.inf] * 3)
    if min_distance is not None:
        ik.AddMinimumDistanceLowerBoundConstraint(min_distance, 0.05)
    q_guess = c.q_full.copy()
    q_guess[c.arm_q_idx] = q_seed_arm
    prog.SetInitialGuess(q, q_guess)
    solver = SnoptSolver()
    result = solver.Solve(prog) if solver.available() and solver.enabled() else Solve(prog)
    if not result.is_success():
        return False, q_seed_arm
    return True, np.asarray(result.GetSolution(q))[c.arm_q_idx]


def solve_ik_continuous(c: PlanningScene, X_WH: RigidTransform, q_prev: np.ndarray, params: PlanParams,
                        min_distance: float | None = None) -> tuple[bool, np.ndarray]:
    """IK seeded from the previous knot; the first solution (wrist up, then free) that stays on its branch.

    With ``min_distance``, solutions keeping every unfiltered pair that far apart come first.
    """
    best = (False, q_prev)
    attempts = [(True, min_distance), (False, min_distance)] if min_distance is not None else []
    for wrist_up, distance in attempts + [(True, None), (False, None)]:
        ok, q = solve_ik(c, X_WH, q_prev, params, min_distance=distance, wrist_up=wrist_up)
        if ok and np.abs(q - q_prev).max() <= params.max_knot_jump:
            return True, q
        if ok and not best[0]:
            best = (True, q)
    return best


# ----------------------------------------------------------------------------- collisions and distances
def query_at(c: PlanningScene, q_arm: np.ndarray):
    """SceneGraph's query object with the arm at ``q_arm`` and everything else at ``c.q_full``."""
    q = c.q_full.copy()
    q[c.arm_q_idx] = q_arm
    c.plant.SetPositions(c.plant_context, q)
    return c.scene_graph.get_query_output_port().Eval(c.sg_context)


def collisions(c: PlanningScene, q_arm: np.ndarray, margin: float = 0.0) -> list[str]:
    """Pairs "A vs B" (frame names) of unfiltered geometries closer than ``margin`` at ``q_arm``."""
    query = query_at(c, q_arm)
    inspector = query.inspector()
    out = []
    for pair in query.ComputeSignedDistancePairwiseClosestPoints(max(margin, 0.0) + 1e-4):
        if pair.distance < margin:
            a, b = (inspector.GetName(inspector.GetFrameId(g)) for g in (pair.id_A, pair.id_B))
            out.append(f"{a} vs {b}")
    return sorted(out)


def min_distance(c: PlanningScene, q_arm: np.ndarray, cap: float) -> float:
    """Smallest distance (m) between unfiltered geometries at ``q_arm``, or ``cap`` if all are farther."""
    query = query_at(c, q_arm)
    return min([cap] + [pair.distance for pair in query.ComputeSignedDistancePairwiseClosestPoints(cap)])


def robot_collides(c: PlanningScene, q_arm: np.ndarray, margin: float = 0.0) -> bool:
    """Any robot geometry closer than ``margin`` to the table or object at ``q_arm``."""
    return bool(collisions(c, q_arm, margin))


def path_collides(c: PlanningScene, knots: list[np.ndarray], margin: float, step: float = 0.05) -> bool:
    """Whether the piecewise-linear joint path through ``knots`` comes closer than ``margin`` to anything.

    Checked every ``step`` rad of the largest joint motion (the executed shape-preserving cubic stays
    between consecutive knots; ``margin`` covers the difference and the tracking error).
    """
    for q_a, q_b in zip(knots[:-1], knots[1:]):
        n = max(1, int(np.ceil(np.abs(q_b - q_a).max() / step)))
        for s in np.linspace(0.0, 1.0, n + 1)[1:]:
            if robot_collides(c, q_a + s * (q_b - q_a), margin):
                return True
    return False


# ----------------------------------------------------------------------------- table clearance
def lowest_point_z(shape, X_WG: np.ndarray) -> float | None:
    """World z of the lowest point of a primitive ``shape`` at pose ``X_WG`` (None: not a primitive)."""
    R, p = X_WG[:3, :3], X_WG[:3, 3]
    if isinstance(shape, Sphere):
        return p[2] - shape.radius()
    if isinstance(shape, Capsule):
        return p[2] - abs(R[2, 2]) * shape.length() / 2 - shape.radius()
    if isinstance(shape, Cylinder):
        return p[2] - abs(R[2, 2]) * shape.length() / 2 - shape.radius() * np.sqrt(max(0.0, 1 - R[2, 2] ** 2))
    if isinstance(shape, Box):
        return p[2] - 0.5 * float(np.abs(R[2, :]) @ np.array([shape.width(), shape.depth(), shape.height()]))
    return None


def table_raise(c: PlanningScene, poses_WH: list[RigidTransform], clearance: float) -> float:
    """Height (m, >= 0) to raise the hand poses by so that the hand (in ``c.q_full``'s posture) clears the table.

    The hand's collision primitives and the arm's last link (the wrist
    flange the hand is mounted on) are carried rigidly with frame H; the
    table top is the highest point of the table's geometry.
    """
    inspector = c.scene_graph.model_inspector()
    query = query_at(c, c.q_full[c.arm_q_idx])
    X_HW = c.frame_H.CalcPoseInWorld(c.plant_context).inverse().GetAsMatrix4()
    table_top = -np.inf
    for g in c.table_ids:
        X_WG = query.GetPoseInWorld(g).GetAsMatrix4()
        z_low = lowest_point_z(inspector.GetShape(g), X_WG)
        if z_low is not None:  # highest point of a primitive = mirror of its lowest about its centre
            table_top = max(table_top, 2 * X_WG[2, 3] - z_low)
    if not np.isfinite(table_top):
        return 0.0
    hand = [(inspector.GetShape(g), X_HW @ query.GetPoseInWorld(g).GetAsMatrix4())
            for g in c.carried_ids]
    lowest = np.inf
    for X_WH in poses_WH:
        M = X_WH.GetAsMatrix4()
        for shape, X_HG in hand:
            z = lowest_point_z(shape, M @ X_HG)
            if z is not None:
                lowest = min(lowest, z)
    return max(0.0, table_top + clearance - lowest) if np.isfinite(lowest) else 0.0


# ----------------------------------------------------------------------------- object clearance
def shape_surface_points(shape, spacing: float) -> np.ndarray | None:
    """Points (K, 3) about ``spacing`` (m) apart on the surface of a primitive ``shape``, in its own frame
    (Drake's conventions: capsules and cylinders along z, boxes centred); None for other shapes."""
    def along(length):  # sample positions over [-length/2, length/2]
        return np.linspace(-length / 2, length / 2, max(2, int(np.ceil(length / spacing)) + 1))

    def ring(radius, z, count):
        a = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)
        return np.stack([radius * np.cos(a), radius * np.sin(a), np.full(count, z)], axis=1)

    def sphere(radius, centre_z=0.0, sign=0):
        n = max(8, int(np.ceil(4.0 * np.pi * radius ** 2 / spacing ** 2)))
        k = np.arange(n) + 0.5
        z = 1.0 - 2.0 * k / n
        phi = np.pi * (1.0 + 5.0 ** 0.5) * k
        u = np.stack([np.sqrt(1 - z ** 2) * np.cos(phi), np.sqrt(1 - z ** 2) * np.sin(phi), z], axis=1)
        if sign:
            u = u[sign * u[:, 2] >= 0]
        return radius * u + [0.0, 0.0, centre_z]

    if isinstance(shape, Sphere):
        return sphere(shape.radius())
    if isinstance(shape, (Capsule, Cylinder)):
        r, half = shape.radius(), shape.length() / 2
        count = max(8, int(np.ceil(2.0 * np.pi * r / spacing)))
        side = np.vstack([ring(r, z, count) for z in along(2 * half)])
        if isinstance(shape, Capsule):
            return np.vstack([side, sphere(r, half, 1), sphere(r, -half, -1)])
        caps = [ring(rr, z, max(4, int(np.ceil(2.0 * np.pi * rr / spacing))))
                for z in (-half, half) for rr in np.linspace(0.0, r, max(2, int(np.ceil(r / spacing)) + 1))[1:]]
        return np.vstack([side] + caps)
    if isinstance(shape, Box):
        size = np.array([shape.width(), shape.depth(), shape.height()])
        out = []
        for axis in range(3):
            a, b = [i for i in range(3) if i != axis]
            A, B = (m.ravel() for m in np.meshgrid(along(size[a]), along(size[b])))
            for sign in (-1.0, 1.0):
                face = np.zeros((len(A), 3))
                face[:, a], face[:, b], face[:, axis] = A, B, sign * size[axis] / 2
                out.append(face)
        return np.vstack(out)
    return None


def hand_surface_samples_H(c: PlanningScene, spacing: float = 0.003) -> list[tuple[object, np.ndarray]]:
    """``[(geometry id, points (n, 3))]``: points every ``spacing`` (m) on each of the hand's collision geometries
    (those :func:`shape_surface_points` can sample) in its planning posture (``c.q_full``), in frame H (m)."""
    inspector = c.scene_graph.model_inspector()
    query = query_at(c, c.q_full[c.arm_q_idx])
    X_HW = c.frame_H.CalcPoseInWorld(c.plant_context).inverse().GetAsMatrix4()
    out = []
    for g in c.hand_ids:
        p_G = shape_surface_points(inspector.GetShape(g), spacing)
        if p_G is not None:
            X_HG = X_HW @ query.GetPoseInWorld(g).GetAsMatrix4()
            out.append((g, p_G @ X_HG[:3, :3].T + X_HG[:3, 3]))
    return out


def hand_surface_points_H(c: PlanningScene, spacing: float = 0.003) -> np.ndarray:
    """Points (N, 3) on the hand's collision geometry in its planning posture (``c.q_full``), in frame H (m)."""
    samples = hand_surface_samples_H(c, spacing)
    return np.vstack([p for _, p in samples]) if samples else np.zeros((0, 3))
