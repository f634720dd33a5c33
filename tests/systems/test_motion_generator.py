"""MotionPlanner through its ports: the plan is the planner's, computed once, refused when unsure."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.planning.model import make_planning_model
from catgrasp_drake.robot.models import ARM_JOINTS
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.station.scenario import load_scenario
from catgrasp_drake.systems.grasp_execution import MotionPlanner


@pytest.fixture(scope="module")
def setup():
    scenario = load_scenario("drill_default")
    planning = make_planning_model(scenario)
    motion_W = load_handwritten_motion("drill", "drill_00").in_world(scenario.X_WO())
    gen = MotionPlanner(planning.plant, planning.arm, planning.hand, planning, min_confidence=0.3)
    return planning, motion_W, gen


def _context(gen, motion_W, confidence):
    ctx = gen.CreateDefaultContext()
    gen.GetInputPort("grasp_motion_W").FixValue(ctx, motion_W)
    gen.GetInputPort("confidence").FixValue(ctx, [confidence])
    return ctx


def test_plan_port_equals_the_planner_and_is_computed_once(setup):
    planning, motion_W, gen = setup
    ctx = _context(gen, motion_W, 0.9)
    plan = gen.GetOutputPort("plan").Eval(ctx)
    assert plan.ok and gen.GetOutputPort("plan_status").Eval(ctx) == "ok"
    ref = planning.plan(motion_W)
    assert np.allclose(plan.times, ref.times) and np.allclose(plan.q_arm, ref.q_arm, atol=1e-6)
    # desired states follow the plan in time (actuator order = ARM_JOINTS order for the UR10 model)
    t = 0.5 * (plan.timeline.reach + plan.timeline.close)
    ctx.SetTime(t)
    x_arm = gen.GetOutputPort("arm_desired_state").Eval(ctx)
    q_ref = plan.arm_trajectory().value(t).ravel()
    assert len(x_arm) == 2 * len(ARM_JOINTS)
    assert np.allclose(x_arm[:6], q_ref, atol=1e-9)
    assert gen.GetOutputPort("plan").Eval(ctx) is plan  # time changed, plan not recomputed


def test_low_confidence_is_refused_with_a_clear_status(setup):
    planning, motion_W, gen = setup
    ctx = _context(gen, motion_W, 0.2)
    plan = gen.GetOutputPort("plan").Eval(ctx)
    assert not plan.ok and plan.failure_kind == "refused"
    assert "low confidence (0.20 < 0.30): take another view" in plan.status
    ctx.SetTime(2.0)  # the arm holds its start configuration
    assert np.allclose(gen.GetOutputPort("arm_desired_state").Eval(ctx)[:6], planning.q_arm_start)


def _lowered(motion, dz):
    from catgrasp_drake.grasping.motion import GraspMotion

    poses = np.array(motion.poses, float)
    poses[:, 2, 3] -= dz
    return GraspMotion(poses, motion.pose_names, dict(motion.postures), motion.frame, motion.lift_height,
                       motion.hold_time)


def test_candidates_fall_back_to_the_first_feasible_grasp(setup):
    """A first candidate 8 cm below the table is refused by the planner; the second is planned and executed."""
    from catgrasp_drake.prediction import GraspCandidate

    planning, motion_W, gen = setup
    low = _lowered(motion_W, 0.08)
    assert not planning.plan(low).ok
    candidate = {"object_points_W": np.zeros((0, 3)), "hypothesis": 0, "weight": 0.5, "support": 0.5,
                 "functional_point_W": np.zeros(3)}
    ctx = _context(gen, motion_W, 0.9)
    gen.GetInputPort("grasp_candidates_W").FixValue(ctx, (GraspCandidate(low, **candidate),
                                                          GraspCandidate(motion_W, **candidate)))
    plan = gen.GetOutputPort("plan").Eval(ctx)
    assert plan.ok and (plan.candidate, plan.tried) == (1, 2)
    np.testing.assert_allclose(plan.q_arm, planning.plan(motion_W).q_arm, atol=1e-9)
    ctx = _context(gen, motion_W, 0.9)  # none feasible: the first's failure, every candidate tried
    gen.GetInputPort("grasp_candidates_W").FixValue(ctx, (GraspCandidate(low, **candidate),
                                                          GraspCandidate(_lowered(motion_W, 0.1), **candidate)))
    plan = gen.GetOutputPort("plan").Eval(ctx)
    assert not plan.ok and plan.status == planning.plan(low).status and plan.tried == 2
