"""The robot's planning model: arm, hand, table and the object as perceived, in a diagram of their own.

:func:`make_planning_model` builds it from a scenario (no cameras; the object
as the convex hull of perceived points, or absent);
:meth:`PlanningModel.of_station` views a built station as one (the trial
plans on the station's own plant, true object included). Either way
:meth:`PlanningModel.plan` runs :func:`~catgrasp_drake.planning.planner.plan_grasp`
on a fresh scratch context.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from pydrake.geometry import (
    AddContactMaterial,
    CollisionFilterDeclaration,
    Convex,
    GeometryInstance,
    GeometrySet,
    ProximityProperties,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia, UnitInertia
from pydrake.systems.framework import DiagramBuilder

from catgrasp_drake.core.clearance import SignedDistanceGrid
from catgrasp_drake.core.validation import as_points
from catgrasp_drake.data.dataset import instance_mesh_path
from catgrasp_drake.data.meshes import read_mesh
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.planning.planner import ObjectSurface, plan_grasp
from catgrasp_drake.planning.records import GraspPlan, PlanParams
from catgrasp_drake.planning.scene import body_geometry_ids
from catgrasp_drake.robot.models import add_arm_and_hand, load_hand_postures, make_parser, set_hand_default_posture
from catgrasp_drake.station.builder import StationHandles, add_table, plant_config, posture_category
from catgrasp_drake.station.scenario import ObjectSpec, Scenario


@dataclass
class PlanningModel:
    """The robot's own model of the world for planning: arm, hand, table and the object as perceived.

    The robot knows the table and sees the object only through its cloud, so
    the object is the convex hull of the completed shape (``obstacle_points_W``,
    world frame, m), or absent. The way to the pregrasp keeps clear of it; the
    reach may touch it. The hull is not part of the plant: :meth:`plan`
    registers it in its own scratch context (SceneGraph's context-side
    geometry), so one robot model serves every perceived shape
    (:meth:`with_obstacle`) without parsing the robot again. ``obstacle``: a
    model instance of the plant that is the object (a station's true object).
    """

    diagram: object
    plant: MultibodyPlant
    scene_graph: object
    arm: ModelInstanceIndex
    hand: ModelInstanceIndex
    table: ModelInstanceIndex
    q_arm_start: np.ndarray
    obstacle: ModelInstanceIndex | None = None
    object_surface: ObjectSurface | None = None
    obstacle_points_W: np.ndarray | None = None
    obstacle_frame: object = None  # FrameId the hull is fixed to (a body welded to the world); None: the world's

    @classmethod
    def of_station(cls, diagram, station: StationHandles) -> "PlanningModel":
        """The built ``diagram`` holding ``station`` as a planning model; its obstacle is the station's true object,
        whose surface (its mesh) the object clearance checks the grasp against."""
        scenario = station.scenario
        surface = None
        mesh_path = object_mesh_path(scenario.object)
        if mesh_path is not None:
            surface = ObjectSurface(true_object_field(str(mesh_path)), scenario.X_WO())
        return cls(diagram, station.plant, station.scene_graph, station.arm, station.hand, station.table,
                   np.asarray(scenario.arm_q_home, float), station.object_instance, surface)

    def with_obstacle(self, points_W) -> "PlanningModel":
        """This model (the same diagram) with the convex hull of ``points_W`` (N >= 4, world frame, m) as the
        object; fewer than 4 points: this model unchanged."""
        points_W = as_points(points_W, "obstacle points", min_points=0)
        if len(points_W) < 4:
            return self
        return dataclasses.replace(self, obstacle_points_W=points_W.copy())

    def plan(self, motion_W: GraspMotion, params: PlanParams = PlanParams()) -> GraspPlan:
        """:func:`~catgrasp_drake.planning.planner.plan_grasp` of ``motion_W`` on a fresh scratch context."""
        ctx = self.diagram.CreateDefaultContext()
        sg_context = self.scene_graph.GetMyMutableContextFromRoot(ctx)
        hull_ids = ()
        if self.obstacle_points_W is not None:
            hull_ids = (_register_hull(self.plant, self.scene_graph, sg_context, self.obstacle_points_W,
                                       self.obstacle_frame),)
        return plan_grasp(self.plant, self.plant.GetMyMutableContextFromRoot(ctx), self.scene_graph,
                          sg_context, arm=self.arm, hand=self.hand,
                          object_instance=self.obstacle, table=self.table, motion_W=motion_W,
                          q_arm_start=self.q_arm_start, params=params, object_surface=self.object_surface,
                          object_geometry_ids=hull_ids)


def _register_hull(plant: MultibodyPlant, scene_graph, sg_context, points_W: np.ndarray, frame_id=None):
    """Register the convex hull of ``points_W`` as a proximity geometry on ``frame_id`` (a frame at the world's
    pose; None: the world frame) in ``sg_context`` only (the plant and the diagram's model are untouched); returns
    its GeometryId."""
    props = ProximityProperties()
    AddContactMaterial(dissipation=5.0, point_stiffness=1e5, friction=CoulombFriction(0.5, 0.5), properties=props)
    hull = GeometryInstance(RigidTransform(), Convex(points_W.T, "hull"), "perceived_object_hull")
    hull.set_proximity_properties(props)
    frame_id = scene_graph.world_frame_id() if frame_id is None else frame_id
    hull_id = scene_graph.RegisterGeometry(sg_context, plant.get_source_id(), frame_id, hull)
    # the plant filters collisions among the bodies welded to the world (table, arm base, the hull's holder);
    # the hull, registered after that, gets the same filter
    welded = [g for body in plant.GetBodiesWeldedTo(plant.world_body()) for g in body_geometry_ids(scene_graph, body)]
    scene_graph.collision_filter_manager(sg_context).Apply(
        CollisionFilterDeclaration().ExcludeBetween(GeometrySet([hull_id]), GeometrySet(welded)))
    return hull_id


#: Surface samples of a true object's mesh for its signed-distance field: ~1.3 mm apart on a drill, dense
#: enough that the field's closing keeps a mug handle's loop open; grid voxel (m).
SURFACE_SAMPLES = 30000
SURFACE_VOXEL = 0.002


def object_mesh_path(spec: ObjectSpec) -> Path | None:
    """The mesh file (canonical frame O) of a data-set or imported object; None for primitives."""
    if spec.primitive is not None or spec.instance is None:
        return None
    if spec.model_dir is not None:
        path = Path(spec.model_dir) / f"{spec.instance}.obj"
        return path if path.is_file() else None
    return instance_mesh_path(spec.category, spec.instance)


@functools.lru_cache(maxsize=16)
def true_object_field(mesh_path: str) -> SignedDistanceGrid:
    """The signed-distance field (frame O) of the object mesh at ``mesh_path`` (cached per process:
    every trial on an object plans against the same field)."""
    mesh = read_mesh(mesh_path)
    points, _ = trimesh.sample.sample_surface(mesh, SURFACE_SAMPLES, seed=0)
    return SignedDistanceGrid.from_surface_points(points, SURFACE_VOXEL)


def make_planning_model(scenario: Scenario, obstacle_W=None, *, compliant_hand: bool = False) -> PlanningModel:
    """The robot's planning model of ``scenario``: table + arm + hand, no cameras, and the object as perceived.

    ``obstacle_W`` (N, 3) world points of the object as the robot knows it
    (e.g. the estimator's completed shape): their convex hull is the object
    (:meth:`PlanningModel.with_obstacle`); the planner keeps the arm clear of
    it on the way to the pregrasp (the reach itself is allowed to touch it).
    None (or fewer than 4 points): no object in the model. The arm starts at ``scenario.arm_q_home``, the hand open.
    The hand's capsules carry no hydroelastic pressure fields unless
    ``compliant_hand`` (the planner asks only for signed distances, which do
    not use them; their meshing was ~85 ms of every plan).
    """
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(plant_config(scenario), builder)
    parser = make_parser(plant)
    table = add_table(plant, scenario)
    arm_hand = add_arm_and_hand(plant, parser, X_W_ArmBase=RigidTransform(scenario.arm_base.matrix()),
                                compliant_hand=compliant_hand)
    # the perceived object's frame: a body welded to the world, its geometry (the hull) registered per plan
    holder = plant.AddRigidBody("body", plant.AddModelInstance("perceived_object"),
                                SpatialInertia(1.0, np.zeros(3), UnitInertia.SolidSphere(0.05)))
    plant.WeldFrames(plant.world_frame(), holder.body_frame(), RigidTransform())
    plant.Finalize()
    set_hand_default_posture(plant, arm_hand.hand, load_hand_postures(posture_category(scenario))["open"])
    diagram = builder.Build()
    diagram.set_name("planning_model")
    robot = PlanningModel(diagram, plant, scene_graph, arm_hand.arm, arm_hand.hand, table,
                          np.asarray(scenario.arm_q_home, float),
                          obstacle_frame=plant.GetBodyFrameIdOrThrow(holder.index()))
    return robot if obstacle_W is None else robot.with_obstacle(obstacle_W)
