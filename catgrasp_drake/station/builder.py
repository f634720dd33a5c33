"""The grasping station: plant + scene graph, table, UR10 + SVH hand, object, cameras.

``add_station(builder, scenario)`` adds everything to a caller's
``DiagramBuilder`` and returns :class:`StationHandles`, so later code can add
its own systems (estimators, regressors, trajectory sources) to the same
builder. ``make_station(scenario)`` builds a closed ``Diagram`` that exports
its ports named ``<instance>.<port>`` (style of Drake's ``hardware_sim`` and
the manipulation course's ``MakeHardwareStation``):

====================================  ==========================================
``<arm>.desired_state`` (in)          arm [q; v] setpoints of the PD-gained actuators
``<hand>.desired_state`` (in)         hand [q; v] (9 actuated joints, actuator order)
``<arm>.actuation`` (in)              arm feed-forward torque (optional, default 0)
``<hand>.actuation`` (in)             hand feed-forward torque (optional, default 0)
``<arm>.state_estimated`` (out)       arm [q; v] (the plant's state, no noise)
``<hand>.state_estimated`` (out)      all hand joints [q; v] (actuated + mimic)
``<camera>.color_image`` (out)        RGBA8U image
``<camera>.depth_image`` (out)        ImageDepth32F, metres
``<camera>.label_image`` (out)        ImageLabel16I; the object's label is ``object_label``
``<camera>.X_WC`` (out)               RigidTransform of the camera in W
``<camera>.object_cloud_W`` (out)     segmented, cropped, voxelised object cloud (PointCloud, W)
``plant.contact_results`` (out)       ContactResults (hydroelastic + point pairs)
``plant.state`` (out)                 full plant state
``plant.body_poses`` (out)            poses of all bodies in W
``object.X_WO`` (out)                 true object pose (RigidTransform)
====================================  ==========================================

``<arm>``/``<hand>`` are the robot model's instance names (``ur10``, ``svh``).

Modelling choices:
- The robot's controller is taken to compensate gravity perfectly: gravity is
  disabled for the arm and hand model instances, so the PD-gained actuators
  only track the desired state (the object still feels gravity).
- The table is a compliant-hydroelastic box in its own model instance
  ``table`` (one body ``top`` welded to the world), so contacts with it are
  attributable; objects are rigid-hydroelastic meshes (data set) or
  compliant primitives (``cylinder_test``).
- Cameras are ``RgbdSensor``s fixed in the world rendering with
  ``RenderEngineVtk`` (headless).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    Box,
    ClippingRange,
    ColorRenderCamera,
    Cylinder,
    DepthRange,
    DepthRenderCamera,
    MakeRenderEngineVtk,
    Meshcat,
    MeshcatVisualizer,
    MeshcatVisualizerParams,
    ProximityProperties,
    RenderCameraCore,
    RenderEngineVtkParams,
    Role,
    RoleAssign,
    SceneGraph,
)
from pydrake.math import RigidTransform
from pydrake.multibody.meshcat import ContactVisualizer, ContactVisualizerParams
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    CoulombFriction,
    MultibodyPlant,
    MultibodyPlantConfig,
)
from pydrake.multibody.tree import JointActuatorIndex, ModelInstanceIndex, RigidBody, SpatialInertia, UnitInertia
from pydrake.systems.framework import Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.sensors import CameraInfo, RgbdSensor

from catgrasp_drake.data.dataset import instance_sdf_url
from catgrasp_drake.errors import InputError
from catgrasp_drake.perception.object_cloud import ObjectCloudSystem
from catgrasp_drake.robot.models import (
    add_arm_and_hand,
    hand_posture_categories,
    load_hand_postures,
    make_parser,
    set_hand_default_posture,
)
from catgrasp_drake.station.scenario import CameraSpec, Scenario

RENDERER_NAME = "catgrasp_vtk"
TABLE_INSTANCE = "table"
OBJECT_BODY = "body"


@dataclass
class StationHandles:
    """What ``add_station`` added (systems live in the caller's builder/diagram)."""

    scenario: Scenario
    plant: MultibodyPlant
    scene_graph: SceneGraph
    arm: ModelInstanceIndex
    hand: ModelInstanceIndex
    table: ModelInstanceIndex
    object_instance: ModelInstanceIndex
    object_body: RigidBody
    object_label: int
    arm_hand: object = None  # the robot module's ArmHand record
    cameras: dict = field(default_factory=dict)  # name -> RgbdSensor
    object_clouds: dict = field(default_factory=dict)  # name -> ObjectCloudSystem
    meshcat_visualizer: MeshcatVisualizer | None = None
    object_pose: LeafSystem | None = None

    @property
    def arm_name(self) -> str:
        return self.plant.GetModelInstanceName(self.arm)

    @property
    def hand_name(self) -> str:
        return self.plant.GetModelInstanceName(self.hand)


class BodyPoseSelector(LeafSystem):
    """Picks one body's pose out of the plant's ``body_poses`` output.

    .. pydrake_system::

        name: BodyPoseSelector
        input_ports:
        - body_poses
        output_ports:
        - X_WB

    Input ports:
        body_poses: list of RigidTransform X_WB (MultibodyPlant ``body_poses``).
    Output ports:
        X_WB: RigidTransform of the selected body in W.
    """

    def __init__(self, body_index: int):
        super().__init__()
        self._index = int(body_index)
        self._in = self.DeclareAbstractInputPort("body_poses", AbstractValue.Make([RigidTransform()]))
        self.DeclareAbstractOutputPort("X_WB", lambda: AbstractValue.Make(RigidTransform()), self._calc)

    def _calc(self, context, output):
        output.set_value(self._in.Eval(context)[self._index])


# ----------------------------------------------------------------------------- pieces
def plant_config(scenario: Scenario) -> MultibodyPlantConfig:
    p = scenario.plant
    return MultibodyPlantConfig(time_step=p.time_step,
                                discrete_contact_approximation=p.discrete_contact_approximation,
                                contact_model=p.contact_model,
                                penetration_allowance=p.penetration_allowance,
                                sap_near_rigid_threshold=p.sap_near_rigid_threshold)


def add_table(plant: MultibodyPlant, scenario: Scenario) -> ModelInstanceIndex:
    t = scenario.table
    instance = plant.AddModelInstance(TABLE_INSTANCE)
    body = plant.AddRigidBody("top", instance, SpatialInertia(10.0, np.zeros(3), UnitInertia.SolidBox(*t.size)))
    X_WT = RigidTransform(t.pose.matrix())
    plant.WeldFrames(plant.world_frame(), body.body_frame(), X_WT)
    box = Box(*t.size)
    X_TBox = RigidTransform([0.0, 0.0, -t.size[2] / 2])
    props = ProximityProperties()
    AddCompliantHydroelasticProperties(0.05, t.hydroelastic_modulus, props)
    AddContactMaterial(dissipation=5.0, point_stiffness=1e5, friction=CoulombFriction(t.friction, t.friction),
                       properties=props)
    plant.RegisterCollisionGeometry(body, X_TBox, box, "table_collision", props)
    plant.RegisterVisualGeometry(body, X_TBox, box, "table_visual", np.array([0.55, 0.45, 0.35, 1.0]))
    return instance


def _add_primitive_object(plant: MultibodyPlant, scenario: Scenario) -> ModelInstanceIndex:
    p = scenario.object.primitive
    instance = plant.AddModelInstance(p.shape)
    if p.shape == "cylinder":
        shape = Cylinder(p.radius, p.length)
        height = p.length
        unit = UnitInertia.SolidCylinder(p.radius, p.length, [0.0, 0.0, 1.0])
    else:
        shape = Box(*p.size)
        height = p.size[2]
        unit = UnitInertia.SolidBox(*p.size)
    X_OG = RigidTransform([0.0, 0.0, height / 2])  # base on z = 0
    inertia = SpatialInertia(p.mass_kg, [0.0, 0.0, height / 2], unit.ShiftFromCenterOfMass([0.0, 0.0, -height / 2]))
    body = plant.AddRigidBody(OBJECT_BODY, instance, inertia)
    props = ProximityProperties()
    AddCompliantHydroelasticProperties(0.01, 5e6, props)
    AddContactMaterial(dissipation=5.0, point_stiffness=1e5, friction=CoulombFriction(p.friction, p.friction),
                       properties=props)
    plant.RegisterCollisionGeometry(body, X_OG, shape, "collision", props)
    plant.RegisterVisualGeometry(body, X_OG, shape, "visual", np.array([0.2, 0.7, 0.3, 1.0]))
    return instance


def _add_object(plant: MultibodyPlant, parser, scenario: Scenario) -> ModelInstanceIndex:
    o = scenario.object
    if o.primitive is not None:
        return _add_primitive_object(plant, scenario)
    if o.model_dir is not None:
        (instance,) = parser.AddModels(o.sdf_file())
    else:
        (instance,) = parser.AddModels(url=instance_sdf_url(o.category, o.instance))
    return instance


def _apply_physics_knobs(plant: MultibodyPlant, scene_graph: SceneGraph, scenario: Scenario, hand, obj) -> None:
    """``PlantSpec.hand_effort_scale`` (hand effort limits scaled), ``object_friction`` and
    ``hand_resolution_hint`` (replaced)."""
    p = scenario.plant
    if p.hand_effort_scale != 1.0:
        for i in range(plant.num_actuators()):  # (GetJointActuatorIndices is empty before Finalize)
            actuator = plant.get_mutable_joint_actuator(JointActuatorIndex(i))
            if actuator.model_instance() == hand:
                actuator.set_effort_limit(actuator.effort_limit() * p.hand_effort_scale)
    if p.object_friction is not None:
        friction = CoulombFriction(p.object_friction, p.object_friction)
        _replace_proximity(plant, scene_graph, obj,
                           lambda props: props.UpdateProperty("material", "coulomb_friction", friction))
    if p.hand_resolution_hint is not None:
        def coarser(props):
            if props.HasProperty("hydroelastic", "resolution_hint"):
                props.UpdateProperty("hydroelastic", "resolution_hint", float(p.hand_resolution_hint))

        _replace_proximity(plant, scene_graph, hand, coarser)


def apply_context_knobs(h: "StationHandles", root_context) -> None:
    """Apply the scenario's context-level physics knobs to a root ``context`` of a diagram holding ``h``:
    ``PlantSpec.object_mass_scale`` (the object's mass times the factor; its unit inertia, hence its
    shape of inertia and centre of mass, unchanged). A no-op at the defaults."""
    k = h.scenario.plant.object_mass_scale
    if k != 1.0:
        plant_ctx = h.plant.GetMyMutableContextFromRoot(root_context)
        h.object_body.SetMass(plant_ctx, h.object_body.default_mass() * k)


def _replace_proximity(plant: MultibodyPlant, scene_graph: SceneGraph, instance, update) -> None:
    """Re-assign every collision geometry of ``instance`` with its proximity properties passed through
    ``update(props)`` (which edits the copy in place)."""
    inspector = scene_graph.model_inspector()
    for body_index in plant.GetBodyIndices(instance):
        for gid in plant.GetCollisionGeometriesForBody(plant.get_body(body_index)):
            props = ProximityProperties(inspector.GetProximityProperties(gid))
            update(props)
            scene_graph.AssignRole(plant.get_source_id(), gid, props, RoleAssign.kReplace)


def _camera_models(spec: CameraSpec) -> tuple[ColorRenderCamera, DepthRenderCamera]:
    info = CameraInfo(spec.width, spec.height, float(np.radians(spec.fov_y_deg)))
    near, far = spec.depth_range
    core = RenderCameraCore(RENDERER_NAME, info, ClippingRange(min(0.01, near / 2), far * 1.5), RigidTransform())
    return ColorRenderCamera(core, False), DepthRenderCamera(core, DepthRange(near, far))


def _object_render_label(plant: MultibodyPlant, scene_graph: SceneGraph, body: RigidBody) -> int:
    inspector = scene_graph.model_inspector()
    labels = set()
    for gid in plant.GetVisualGeometriesForBody(body):
        props = inspector.GetPerceptionProperties(gid)
        if props is not None and props.HasProperty("label", "id"):
            labels.add(int(props.GetProperty("label", "id")))
    if len(labels) != 1:
        raise InputError(f"object body {body.name()!r}: expected one render label, found {sorted(labels)}")
    return labels.pop()


def _add_camera(builder: DiagramBuilder, handles: StationHandles, spec: CameraSpec) -> None:
    scene_graph, scenario = handles.scene_graph, handles.scenario
    color, depth = _camera_models(spec)
    X_WC = RigidTransform(spec.X_WC_matrix())
    sensor = builder.AddNamedSystem(spec.name, RgbdSensor(scene_graph.world_frame_id(), X_WC, color, depth))
    builder.Connect(scene_graph.get_query_output_port(), sensor.query_object_input_port())
    c = scenario.object_cloud
    cloud = builder.AddNamedSystem(f"{spec.name}_object_cloud", ObjectCloudSystem(
        depth.core().intrinsics(), handles.object_label, crop_min=c.crop_min, crop_max=c.crop_max,
        voxel_size=c.voxel_size, noise_std=c.depth_noise_std, seed=c.seed, noise_model=c.depth_noise_model,
        edge_dropout=c.edge_dropout))
    builder.Connect(sensor.depth_image_32F_output_port(), cloud.GetInputPort("depth_image"))
    builder.Connect(sensor.label_image_output_port(), cloud.GetInputPort("label_image"))
    builder.Connect(sensor.body_pose_in_world_output_port(), cloud.GetInputPort("camera_pose"))
    handles.cameras[spec.name] = sensor
    handles.object_clouds[spec.name] = cloud


def posture_category(scenario: Scenario) -> str:
    """The hand-posture set of the scenario's object (``cylinder`` for primitives and categories without one)."""
    category = scenario.object.category
    return category if category in hand_posture_categories() else "cylinder"


# ----------------------------------------------------------------------------- builders
def add_station(builder: DiagramBuilder, scenario: Scenario, meshcat: Meshcat | None = None) -> StationHandles:
    """Add the station described by ``scenario`` to ``builder`` and return handles to its parts.

    The plant is finalized on return; the arm starts at ``scenario.arm_q_home``,
    the hand in its ``open`` posture, the object at ``scenario.X_WO()``.
    With ``meshcat`` (a ``pydrake.geometry.Meshcat`` the caller made, e.g.
    ``Meshcat(MeshcatParams(host="localhost", port=0))``) a MeshcatVisualizer
    and a ContactVisualizer are added.
    """
    if not isinstance(scenario, Scenario):
        raise InputError(f"scenario: expected a Scenario, got {type(scenario).__name__}")
    plant, scene_graph = AddMultibodyPlant(plant_config(scenario), builder)
    plant.set_name("plant")
    scene_graph.set_name("scene_graph")
    parser = make_parser(plant)
    table = add_table(plant, scenario)
    arm_hand = add_arm_and_hand(plant, parser, X_W_ArmBase=RigidTransform(scenario.arm_base.matrix()))
    arm, hand = arm_hand.arm, arm_hand.hand
    obj = _add_object(plant, parser, scenario)
    _apply_physics_knobs(plant, scene_graph, scenario, hand, obj)
    plant.set_gravity_enabled(arm, False)
    plant.set_gravity_enabled(hand, False)
    plant.Finalize()

    body = plant.GetBodyByName(OBJECT_BODY, obj)
    plant.SetDefaultFloatingBaseBodyPose(body, RigidTransform(scenario.X_WO()))
    arm_joints = [plant.get_joint(i) for i in plant.GetJointIndices(arm) if plant.get_joint(i).num_positions() == 1]
    if len(arm_joints) != len(scenario.arm_q_home):
        raise InputError(f"arm_q_home: {len(scenario.arm_q_home)} values for {len(arm_joints)} arm joints")
    for joint, q in zip(arm_joints, scenario.arm_q_home):
        joint.set_default_angle(float(q))
    set_hand_default_posture(plant, hand, load_hand_postures(posture_category(scenario))["open"])

    scene_graph.AddRenderer(RENDERER_NAME, MakeRenderEngineVtk(RenderEngineVtkParams()))
    label = _object_render_label(plant, scene_graph, body)
    handles = StationHandles(scenario=scenario, plant=plant, scene_graph=scene_graph, arm=arm, hand=hand,
                             table=table, object_instance=obj, object_body=body, object_label=label,
                             arm_hand=arm_hand)
    for spec in scenario.cameras:
        _add_camera(builder, handles, spec)

    pose = builder.AddNamedSystem("object_pose", BodyPoseSelector(int(body.index())))
    builder.Connect(plant.get_body_poses_output_port(), pose.get_input_port())
    handles.object_pose = pose

    if meshcat is not None:
        handles.meshcat_visualizer = MeshcatVisualizer.AddToBuilder(
            builder, scene_graph, meshcat, MeshcatVisualizerParams(role=Role.kIllustration, prefix="station"))
        ContactVisualizer.AddToBuilder(builder, plant, meshcat,
                                       ContactVisualizerParams(newtons_per_meter=200.0, prefix="contact"))
    return handles


def make_station(scenario: Scenario, meshcat: Meshcat | None = None) -> Diagram:
    """The station as a closed Diagram named ``station`` with ``<instance>.<port>`` ports (module docstring).

    Subsystems keep their names: ``plant``, ``scene_graph``, ``<camera>``,
    ``<camera>_object_cloud``, ``object_pose`` (and ``meshcat_visualizer(station)``
    when ``meshcat`` is given), so callers can reach them with
    ``GetSubsystemByName``.
    """
    builder = DiagramBuilder()
    h = add_station(builder, scenario, meshcat)
    plant = h.plant
    for instance in (h.arm, h.hand):
        name = plant.GetModelInstanceName(instance)
        builder.ExportInput(plant.get_desired_state_input_port(instance), f"{name}.desired_state")
        builder.ExportInput(plant.get_actuation_input_port(instance), f"{name}.actuation")
        builder.ExportOutput(plant.get_state_output_port(instance), f"{name}.state_estimated")
    for name, sensor in h.cameras.items():
        builder.ExportOutput(sensor.color_image_output_port(), f"{name}.color_image")
        builder.ExportOutput(sensor.depth_image_32F_output_port(), f"{name}.depth_image")
        builder.ExportOutput(sensor.label_image_output_port(), f"{name}.label_image")
        builder.ExportOutput(sensor.body_pose_in_world_output_port(), f"{name}.X_WC")
        builder.ExportOutput(h.object_clouds[name].GetOutputPort("object_cloud_W"), f"{name}.object_cloud_W")
    builder.ExportOutput(plant.get_contact_results_output_port(), "plant.contact_results")
    builder.ExportOutput(plant.get_state_output_port(), "plant.state")
    builder.ExportOutput(plant.get_body_poses_output_port(), "plant.body_poses")
    builder.ExportOutput(h.object_pose.get_output_port(), "object.X_WO")
    diagram = builder.Build()
    diagram.set_name("station")
    return diagram
