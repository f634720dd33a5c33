"""UR10 + hand: parsing, DH forward kinematics, flange adapter, collisions at home."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from catgrasp_drake.errors import InputError
from catgrasp_drake.robot import models
from tools import ur10_model


@pytest.fixture(scope="module")
def station():
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(
        MultibodyPlantConfig(time_step=5e-3, discrete_contact_approximation="sap",
                             contact_model="hydroelastic_with_fallback"),
        builder,
    )
    X_W_ArmBase = RigidTransform(RollPitchYaw(0, 0, 0.3), [0.1, -0.2, 0.05])
    parts = models.add_arm_and_hand(plant, X_W_ArmBase=X_W_ArmBase)
    plant.Finalize()
    diagram = builder.Build()
    return diagram, plant, scene_graph, parts, X_W_ArmBase


def test_arm_and_hand_parse_together(station):
    _, plant, _, parts, _ = station
    assert plant.num_positions(parts.arm) == 6
    assert plant.num_positions(parts.hand) == 20  # welded to the flange: no floating base
    assert plant.num_actuators() == 15
    assert plant.num_constraints() == 11
    names = [plant.get_joint_actuator(i).joint().name() for i in plant.GetJointActuatorIndices(parts.arm)]
    assert tuple(names) == models.ARM_JOINTS
    masses = [plant.GetBodyByName(n, parts.arm).default_mass() for n in models.ARM_LINKS[1:]]
    assert masses == pytest.approx([7.1, 12.7, 4.27, 2.0, 2.0, 0.365])
    for i in plant.GetJointActuatorIndices(parts.arm):
        actuator = plant.get_joint_actuator(i)
        assert actuator.has_controller()
        assert actuator.effort_limit() == models.ARM_PD_GAINS[actuator.joint().name()][2]
    assert parts.hand_base_body.name() == models.HAND_BASE_LINK
    assert parts.flange_frame.name() == models.ARM_FLANGE_FRAME


@pytest.mark.parametrize(
    "q",
    [np.zeros(6), models.ARM_HOME_POSITIONS, np.array([0.3, -1.1, 1.4, -0.7, 0.9, -2.2]),
     np.array([-2.5, 0.4, -2.9, 3.5, -5.0, 6.0])],
)
def test_forward_kinematics_matches_dh(station, q):
    _, plant, _, parts, X_W_ArmBase = station
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, parts.arm, q)
    X_WF = plant.CalcRelativeTransform(context, plant.world_frame(), parts.flange_frame)
    expected = X_W_ArmBase.GetAsMatrix4() @ ur10_model.dh_forward_kinematics(q)
    assert np.allclose(X_WF.GetAsMatrix4(), expected, atol=1e-9)
    # The hand base sits at X_FLANGE_HAND on the flange.
    X_WH = plant.CalcRelativeTransform(context, plant.world_frame(), parts.hand_base_frame)
    assert np.allclose(X_WH.GetAsMatrix4(), (X_WF @ models.X_FLANGE_HAND).GetAsMatrix4(), atol=1e-9)


def test_zero_configuration_tool0_published_value():
    # UR10 at q = 0: the arm stretched along -x; tool0 at (a2 + a3, -(d4 + d6), d1 - d5).
    X = ur10_model.dh_forward_kinematics(np.zeros(6))
    assert np.allclose(X[:3, 3], [-1.1843, -0.256141, 0.0116], atol=1e-9)


def test_no_penetrations_at_home(station):
    diagram, plant, scene_graph, parts, _ = station
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    plant.SetPositions(plant_context, parts.arm, models.ARM_HOME_POSITIONS)
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
    assert query.ComputePointPairPenetration() == []


def test_add_after_finalize_is_an_input_error(station):
    _, plant, _, _, _ = station
    with pytest.raises(InputError, match="finalized"):
        models.add_hand(plant)


def test_make_parser_knows_the_package():
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)
    parser = models.make_parser(plant)
    assert parser.package_map().GetPath(models.PACKAGE_NAME) == str(models.MODELS_DIR)
    parser.AddModels(url=models.ARM_URDF_URL)
    assert plant.HasBodyNamed(models.ARM_BASE_LINK)


def test_generator_reproduces_committed_arm_urdf():
    assert ur10_model.build_urdf() == models.ARM_URDF_PATH.read_text(), \
        "models/ur10/ur10.urdf is stale: rerun python -m tools.ur10_model"


def test_arm_tracks_a_slow_trajectory_carrying_1_5_kg():
    from pydrake.multibody.tree import SpatialInertia
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.primitives import ConstantVectorSource, TrajectorySource
    from pydrake.trajectories import PiecewisePolynomial

    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlant(
        MultibodyPlantConfig(time_step=5e-3, discrete_contact_approximation="sap",
                             contact_model="hydroelastic_with_fallback"),
        builder,
    )
    parts = models.add_arm_and_hand(plant)
    payload = plant.AddRigidBody("payload", parts.hand, SpatialInertia.SolidSphereWithMass(1.5, 0.04))
    plant.WeldFrames(parts.hand_base_frame, payload.body_frame(), RigidTransform([0.0, 0.06, 0.12]))
    plant.Finalize()
    q0 = models.ARM_HOME_POSITIONS
    q1 = q0 + np.array([0.8, 0.3, -0.4, 0.3, 0.5, 0.5])
    traj = PiecewisePolynomial.CubicWithContinuousSecondDerivatives([0.0, 4.0], np.column_stack([q0, q1]),
                                                                    np.zeros(6), np.zeros(6))
    source = builder.AddSystem(TrajectorySource(traj, output_derivative_order=1))
    builder.Connect(source.get_output_port(), plant.get_desired_state_input_port(parts.arm))
    hand_q = models.load_hand_postures("cylinder")["open"]
    hand_source = builder.AddSystem(ConstantVectorSource(np.concatenate([hand_q, np.zeros(9)])))
    builder.Connect(hand_source.get_output_port(), plant.get_desired_state_input_port(parts.hand))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    plant_context = plant.GetMyMutableContextFromRoot(simulator.get_mutable_context())
    plant.SetPositions(plant_context, parts.arm, q0)
    worst = 0.0
    for t in np.arange(0.5, 4.51, 0.5):
        simulator.AdvanceTo(t)
        worst = max(worst, np.abs(plant.GetPositions(plant_context, parts.arm) - traj.value(min(t, 4.0)).ravel()).max())
    assert worst < 5e-3  # rad; ~6 mm at the hand for the outstretched arm
