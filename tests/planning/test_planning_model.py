"""The planner's own model of the world (issue 17): its hand needs no hydroelastic pressure fields, and the
perceived object's hull is registered per plan in the plan's own context instead of a new model per shape."""

from __future__ import annotations

import numpy as np
from pydrake.geometry import AddContactMaterial, Convex, ProximityProperties
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction
from pydrake.multibody.tree import SpatialInertia, UnitInertia
from pydrake.systems.framework import DiagramBuilder

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.demo import default_model_path
from catgrasp_drake.planning.model import PlanningModel, make_planning_model
from catgrasp_drake.robot.models import add_arm_and_hand, load_hand_postures, make_parser, set_hand_default_posture
from catgrasp_drake.station.builder import add_table, plant_config, posture_category
from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
from catgrasp_drake.transfer import true_object_points_W


def _compliant_hand_geometries(pm) -> int:
    inspector = pm.scene_graph.model_inspector()
    n = 0
    for body in pm.plant.GetBodyIndices(pm.hand):
        for gid in pm.plant.GetCollisionGeometriesForBody(pm.plant.get_body(body)):
            props = inspector.GetProximityProperties(gid)
            n += props is not None and props.HasProperty("hydroelastic", "compliance_type")
    return n


def test_planning_without_the_hands_pressure_fields_makes_the_same_plan():
    """The planner asks only for signed distances: without the hand's compliant-hydroelastic declaration its
    plan is bit for bit the one made with it, on a drill placed off-centre with the object as an obstacle."""
    model = CategoryModel.load(default_model_path("drill"), category="drill")
    scenario = random_placement(with_instance(load_scenario("drill_default"), "drill_03"), 2)
    X = scenario.X_WO()
    motion = model.transfer(np.zeros(model.space.q), X[:3, :3], X[:3, 3], 1.0)
    obstacle = true_object_points_W(scenario)
    compliant = make_planning_model(scenario, obstacle, compliant_hand=True)
    default = make_planning_model(scenario, obstacle)
    assert _compliant_hand_geometries(compliant) > 10 and _compliant_hand_geometries(default) == 0
    a, b = compliant.plan(motion), default.plan(motion)
    assert a.ok and b.ok
    for field in ("times", "q_arm", "q_hand"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert a.knot_names == b.knot_names and a.object_shift == b.object_shift


def _hull_in_the_plant(scenario, points_W) -> PlanningModel:
    """The planning model as it was built before session 24: a new plant per perceived shape, the hull registered
    on a body welded to the world (what the context-side hull must reproduce)."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(plant_config(scenario), builder)
    table = add_table(plant, scenario)
    arm_hand = add_arm_and_hand(plant, make_parser(plant), X_W_ArmBase=RigidTransform(scenario.arm_base.matrix()),
                                compliant_hand=False)
    obstacle = plant.AddModelInstance("perceived_object")
    body = plant.AddRigidBody("body", obstacle, SpatialInertia(1.0, np.zeros(3), UnitInertia.SolidSphere(0.05)))
    plant.WeldFrames(plant.world_frame(), body.body_frame(), RigidTransform())
    props = ProximityProperties()
    AddContactMaterial(dissipation=5.0, point_stiffness=1e5, friction=CoulombFriction(0.5, 0.5), properties=props)
    plant.RegisterCollisionGeometry(body, RigidTransform(), Convex(points_W.T, "hull"), "hull", props)
    plant.Finalize()
    set_hand_default_posture(plant, arm_hand.hand, load_hand_postures(posture_category(scenario))["open"])
    return PlanningModel(builder.Build(), plant, scene_graph, arm_hand.arm, arm_hand.hand, table,
                         np.asarray(scenario.arm_q_home, float), obstacle)


def test_the_hull_registered_per_plan_plans_as_a_hull_in_the_plant():
    """One robot model serves every perceived shape: ``with_obstacle`` registers the hull in the plan's scratch
    context (filtered against the bodies welded to the world, as the plant filters its own). Its plans are bit for
    bit those of a new plant holding the hull (the model before session 24), on a spray bottle placed off-centre;
    the robot model itself is untouched (its own plan is the same before and after)."""
    model = CategoryModel.load(default_model_path("spray_bottle"), category="spray_bottle")
    scenario = random_placement(with_instance(load_scenario("spray_bottle_default"), "spray_bottle_05"), 4)
    X = scenario.X_WO()
    motion = model.transfer(np.zeros(model.space.q), X[:3, :3], X[:3, 3], 1.0)
    hull_W = true_object_points_W(scenario)
    robot = make_planning_model(scenario)
    alone = robot.plan(motion)
    perceived = robot.with_obstacle(hull_W)
    assert perceived.diagram is robot.diagram and perceived.obstacle_points_W.shape == hull_W.shape
    a, b = perceived.plan(motion), _hull_in_the_plant(scenario, hull_W).plan(motion)
    assert a.ok and b.ok
    for field in ("times", "q_arm", "q_hand"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert a.knot_names == b.knot_names
    # the hull is an obstacle: the plan around it is not the plan without it
    assert not np.array_equal(a.q_arm, alone.q_arm)
    again = robot.plan(motion)
    assert np.array_equal(again.q_arm, alone.q_arm) and np.array_equal(again.times, alone.times)
    assert robot.with_obstacle(hull_W[:3]) is robot  # fewer than 4 points: no object


def test_thumb_first_closes_the_thumb_half_way_and_changes_nothing_else():
    """``PlanParams(close_order="thumb_first")``: one more knot half-way through the closing, where the thumb's
    joints are at their closed values and every other joint at the preshape; every other knot is the default
    plan's, bit for bit. An unknown order is a one-line InputError."""
    import dataclasses

    import pytest

    from catgrasp_drake.errors import InputError
    from catgrasp_drake.planning.planner import THUMB_JOINT_INDICES
    from catgrasp_drake.planning.records import PlanParams

    model = CategoryModel.load(default_model_path("drill"), category="drill")
    scenario = random_placement(with_instance(load_scenario("drill_default"), "drill_03"), 2)
    X = scenario.X_WO()
    motion = model.transfer(np.zeros(model.space.q), X[:3, :3], X[:3, 3], 1.0)
    pm = make_planning_model(scenario, true_object_points_W(scenario))
    together = pm.plan(motion)
    thumb = pm.plan(motion, dataclasses.replace(PlanParams(), close_order="thumb_first"))
    assert together.ok and thumb.ok and "thumb_closed" not in together.knot_names
    k = thumb.knot_names.index("thumb_closed")
    assert thumb.knot_names[:k] + thumb.knot_names[k + 1:] == together.knot_names
    for field in ("times", "q_arm", "q_hand"):
        assert np.array_equal(np.delete(getattr(thumb, field), k, axis=0), getattr(together, field)), field
    c = together.knot_names.index("closed")
    assert thumb.times[k] == (together.times[c - 1] + together.times[c]) / 2  # half-way through close_time
    q_pre, q_closed, q_mid = together.q_hand[c - 1], together.q_hand[c], thumb.q_hand[k]
    others = [i for i in range(len(q_mid)) if i not in THUMB_JOINT_INDICES]
    assert np.array_equal(q_mid[THUMB_JOINT_INDICES], q_closed[THUMB_JOINT_INDICES])
    assert np.array_equal(q_mid[others], q_pre[others])
    assert not np.array_equal(q_pre[THUMB_JOINT_INDICES], q_closed[THUMB_JOINT_INDICES])  # the thumb does move
    with pytest.raises(InputError, match="close_order"):
        PlanParams(close_order="fingers_last")
