"""A minimal grasp rig: the SVH hand on a vertical lift closes on a free cylinder, lifts it and holds it.

Used by the physics test of the hand model and handy for tuning gains and
contact parameters. The scene (world z up, gravity -z):

- a table (rigid box, top at z = 0);
- a free cylinder standing on it (rigid hydroelastic by default);
- the hand welded to a carriage on a PD-driven prismatic z joint ("lift"),
  oriented for a side power grasp: palm normal (+y hand) along -x world,
  fingers (+z hand) along +y world, little finger down (+x hand = -z world),
  so the cylinder axis is parallel to the finger joint axes and gravity acts
  along it: the cylinder is held by the squeeze and friction alone.

Timeline: preshape, close to the "closed" posture over ``close_time``, wait,
lift by ``lift_height`` over ``lift_time``, hold for ``hold_time``. The result
records the cylinder's drop relative to the hand during the hold, its height
above the table, the hand bodies touching it and the real-time rate.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    AddRigidHydroelasticProperties,
    Box,
    Cylinder,
    MakeRenderEngineVtk,
    ProximityProperties,
    RenderEngineVtkParams,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction, MultibodyPlantConfig
from pydrake.multibody.tree import PdControllerGains, PrismaticJoint, SpatialInertia, UnitInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from catgrasp_drake.errors import InputError
from catgrasp_drake.robot import models

#: Hand orientation of the rig (columns: hand x, y, z in world).
R_W_HAND = RotationMatrix(np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]]))


@dataclass(frozen=True)
class CylinderGraspParams:
    radius: float = 0.02
    length: float = 0.14
    mass: float = 0.3
    mu: float = 0.8
    compliant: bool = False
    hydroelastic_modulus: float = 1.0e7  # only for a compliant cylinder
    #: Cylinder axis position in the hand frame (x_h is along the cylinder axis, so only y, z matter).
    #: (0.042, 0.122): in front of the upper palm, under the proximal phalanges, ~4 mm clear of the preshaped hand.
    p_HandCylinder_yz: tuple[float, float] = (0.042, 0.122)
    posture_category: str = "cylinder"
    #: Posture closed to (e.g. "preshape" for a negative control that must not lift the cylinder).
    close_to: str = "closed"
    time_step: float = 5e-3
    close_time: float = 0.8
    settle_time: float = 0.7
    lift_height: float = 0.05
    lift_time: float = 1.0
    hold_time: float = 2.0
    hand_height: float = 0.075  # hand base origin above the table top


@dataclass
class CylinderGraspResult:
    drop_during_hold: float  # m, cylinder z relative to the hand, end of lift -> end of hold (positive = slipped down)
    drop_total: float  # m, same from closing to the end of hold
    height_above_table: float  # m, cylinder bottom above the table top at the end
    hand_links_in_contact: list[str] = field(default_factory=list)  # at the end of the hold
    initial_hand_contacts: list[str] = field(default_factory=list)  # hand links touching the cylinder at t = 0
    touches_thumb: bool = False
    touches_fingers: bool = False
    touches_table: bool = False
    couplers_max_error: float = 0.0  # rad, max |follower - (m*leader + offset)| at the end
    sim_time: float = 0.0
    wall_time: float = 0.0

    @property
    def realtime_rate(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else float("inf")


def _contact_body_pairs(plant, plant_context, inspector) -> set[tuple[str, str]]:
    results = plant.get_contact_results_output_port().Eval(plant_context)
    pairs = set()
    for i in range(results.num_hydroelastic_contacts()):
        surface = results.hydroelastic_contact_info(i).contact_surface()
        a = plant.GetBodyFromFrameId(inspector.GetFrameId(surface.id_M())).name()
        b = plant.GetBodyFromFrameId(inspector.GetFrameId(surface.id_N())).name()
        pairs.add((a, b))
    for i in range(results.num_point_pair_contacts()):
        info = results.point_pair_contact_info(i)
        pairs.add((plant.get_body(info.bodyA_index()).name(), plant.get_body(info.bodyB_index()).name()))
    return pairs


def simulate_cylinder_grasp(
    params: CylinderGraspParams = CylinderGraspParams(),
    *,
    renderer_name: str | None = None,
    on_event: Callable[[str, object, object, object], None] | None = None,
) -> CylinderGraspResult:
    """Build the rig, run close → lift → hold, and measure (deterministic; no randomness).

    ``renderer_name``: if given, a RenderEngineVtk of that name is added to the
    scene graph (for pictures). ``on_event(stage, diagram, context,
    scene_graph)`` is called at the stages "closed", "lifted" and "end".
    """
    if params.radius <= 0 or params.length <= 0 or params.mass <= 0:
        raise InputError("cylinder radius, length and mass must be positive")
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(
        MultibodyPlantConfig(
            time_step=params.time_step,
            discrete_contact_approximation="sap",
            contact_model="hydroelastic_with_fallback",
        ),
        builder,
    )
    # Table.
    table_props = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(0.8, 0.6), properties=table_props)
    AddRigidHydroelasticProperties(properties=table_props)
    X_WTable = RigidTransform([0.0, 0.0, -0.025])
    if renderer_name is not None:
        scene_graph.AddRenderer(renderer_name,
                                MakeRenderEngineVtk(RenderEngineVtkParams(default_clear_color=[1.0, 1.0, 1.0])))
    plant.RegisterCollisionGeometry(plant.world_body(), X_WTable, Box(0.6, 0.6, 0.05), "table", table_props)
    plant.RegisterVisualGeometry(plant.world_body(), X_WTable, Box(0.6, 0.6, 0.05), "table",
                                 np.array([0.6, 0.5, 0.4, 1]))

    # Free cylinder (axis along world z).
    cyl_instance = plant.AddModelInstance("cylinder")
    r, L, m = params.radius, params.length, params.mass
    cylinder = plant.AddRigidBody(
        "cylinder", cyl_instance, SpatialInertia(m, np.zeros(3), UnitInertia.SolidCylinder(r, L, [0, 0, 1]))
    )
    cyl_props = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(params.mu, params.mu), properties=cyl_props)
    if params.compliant:
        AddCompliantHydroelasticProperties(
            resolution_hint=0.005, hydroelastic_modulus=params.hydroelastic_modulus, properties=cyl_props
        )
    else:
        AddRigidHydroelasticProperties(resolution_hint=0.004, properties=cyl_props)
    plant.RegisterCollisionGeometry(cylinder, RigidTransform(), Cylinder(r, L), "cylinder", cyl_props)
    plant.RegisterVisualGeometry(cylinder, RigidTransform(), Cylinder(r, L), "cylinder", np.array([0.2, 0.5, 0.8, 1]))

    # Hand on a lift.
    lift_instance = plant.AddModelInstance("lift")
    carriage = plant.AddRigidBody("carriage", lift_instance, SpatialInertia.SolidBoxWithMass(0.5, 0.05, 0.05, 0.05))
    lift = plant.AddJoint(
        PrismaticJoint("lift_z", plant.world_frame(), carriage.body_frame(), [0.0, 0.0, 1.0])
    )
    lift_actuator = plant.AddJointActuator("lift_z_actuator", lift, 500.0)
    lift_actuator.set_controller_gains(PdControllerGains(p=2.0e4, d=1.0e3))
    hand = models.add_hand(plant)
    hand_base = plant.GetBodyByName(models.HAND_BASE_LINK, hand)
    plant.WeldFrames(carriage.body_frame(), hand_base.body_frame(), RigidTransform(R_W_HAND, [0.0, 0.0, 0.0]))
    plant.Finalize()

    # Where things are: hand base at height h; cylinder axis at the requested hand-frame (y, z).
    y_h, z_h = params.p_HandCylinder_yz
    p_W_axis = R_W_HAND.multiply(np.array([0.0, y_h, z_h]))  # relative to the hand origin
    h = params.hand_height

    postures = models.load_hand_postures(params.posture_category)
    if params.close_to not in postures:
        raise InputError(f"posture {params.close_to!r} not in {sorted(postures)}")
    t_close0 = 0.2
    t_close1 = t_close0 + params.close_time
    t_lift0 = t_close1 + params.settle_time
    t_lift1 = t_lift0 + params.lift_time
    t_end = t_lift1 + params.hold_time
    hand_traj = PiecewisePolynomial.FirstOrderHold(
        [0.0, t_close0, t_close1, t_end],
        np.column_stack([postures["preshape"], postures["preshape"], postures[params.close_to],
                         postures[params.close_to]]),
    )
    lift_traj = PiecewisePolynomial.FirstOrderHold(
        [0.0, t_lift0, t_lift1, t_end], np.array([[h, h, h + params.lift_height, h + params.lift_height]])
    )
    hand_src = builder.AddSystem(TrajectorySource(hand_traj, output_derivative_order=1))
    lift_src = builder.AddSystem(TrajectorySource(lift_traj, output_derivative_order=1))
    builder.Connect(hand_src.get_output_port(), plant.get_desired_state_input_port(hand))
    builder.Connect(lift_src.get_output_port(), plant.get_desired_state_input_port(lift_instance))
    diagram = builder.Build()

    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    lift.set_translation(plant_context, h)
    models.set_hand_angles(plant, plant_context, hand, postures["preshape"])
    plant.SetFreeBodyPose(
        plant_context, cylinder, RigidTransform([p_W_axis[0], p_W_axis[1], L / 2 + 1e-4])
    )

    inspector = scene_graph.model_inspector()

    def cylinder_z_in_hand() -> float:
        X_WH = hand_base.EvalPoseInWorld(plant_context)
        X_WC = cylinder.EvalPoseInWorld(plant_context)
        return float(X_WC.translation()[2] - X_WH.translation()[2])

    def hand_links_touching_cylinder() -> tuple[list[str], list[str]]:
        pairs = _contact_body_pairs(plant, plant_context, inspector)
        touching = sorted({a if b == "cylinder" else b for a, b in pairs if "cylinder" in (a, b)} - {"cylinder"})
        return touching, [name for name in touching if name in models.HAND_LINKS]

    _, initial_hand = hand_links_touching_cylinder()
    wall0 = time.perf_counter()
    simulator.AdvanceTo(t_close1 + params.settle_time)
    z_closed = cylinder_z_in_hand()
    if on_event is not None:
        on_event("closed", diagram, context, scene_graph)
    simulator.AdvanceTo(t_lift1)
    z_lifted = cylinder_z_in_hand()
    if on_event is not None:
        on_event("lifted", diagram, context, scene_graph)
    simulator.AdvanceTo(t_end)
    wall = time.perf_counter() - wall0
    z_end = cylinder_z_in_hand()
    if on_event is not None:
        on_event("end", diagram, context, scene_graph)

    touching, hand_touching = hand_links_touching_cylinder()
    errors = []
    for follower, (leader, mult, offset) in models.hand_mimic_joints().items():
        qf = plant.GetJointByName(follower, hand).get_angle(plant_context)
        ql = plant.GetJointByName(leader, hand).get_angle(plant_context)
        errors.append(abs(qf - (mult * ql + offset)))
    X_WC = cylinder.EvalPoseInWorld(plant_context)
    return CylinderGraspResult(
        drop_during_hold=z_lifted - z_end,
        drop_total=z_closed - z_end,
        height_above_table=float(X_WC.translation()[2] - L / 2),
        hand_links_in_contact=hand_touching,
        initial_hand_contacts=initial_hand,
        touches_thumb=any(n in models.THUMB_LINKS for n in hand_touching),
        touches_fingers=any(n not in models.THUMB_LINKS and n not in ("svh_base_link", "svh_palm_flex_link")
                            for n in hand_touching),
        touches_table=any(n in ("WorldBody", "world") for n in touching),
        couplers_max_error=float(max(errors)),
        sim_time=t_end,
        wall_time=wall,
    )
