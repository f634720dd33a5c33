"""The grasp planner's guarantees, checked on the planned (executed) trajectories with Drake's distance queries.

- a grasp predicted a little too low is raised until the preshaped hand
  clears the table by ``table_clearance``; one far too low is refused;
- the executed home -> pregrasp trajectory (the shape-preserving cubic, not
  just its knots) keeps the robot off the table and the object.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.grasping.sampling import perturb_poses
from catgrasp_drake.planning.model import make_planning_model
from catgrasp_drake.planning.planner import shake_amplitude
from catgrasp_drake.planning.records import PHASES, PlanParams
from catgrasp_drake.robot.models import ARM_JOINTS, hand_joint_angles
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.station.scenario import load_scenario


@pytest.fixture(scope="module")
def drill():
    scenario = load_scenario("drill_default")
    planning = make_planning_model(scenario)
    motion_W = load_handwritten_motion("drill", "drill_00").in_world(scenario.X_WO())
    return planning, motion_W


def _shifted(motion: GraspMotion, dz: float) -> GraspMotion:
    poses = motion.poses.copy()
    poses[:, 2, 3] += dz
    return dataclasses.replace(motion, poses=poses)


def _distances_to_table(planning, q_arm, q_hand) -> dict[str, float]:
    """Smallest distance (m) from each robot body (arm or hand) to the table at ``q_arm`` / ``q_hand``."""
    plant, sg = planning.plant, planning.scene_graph
    ctx = planning.diagram.CreateDefaultContext()
    pc = plant.GetMyMutableContextFromRoot(ctx)
    for name, q in zip(ARM_JOINTS, q_arm):
        plant.GetJointByName(name, planning.arm).set_angle(pc, q)
    for name, q in hand_joint_angles(q_hand).items():
        plant.GetJointByName(name, planning.hand).set_angle(pc, q)
    query = sg.get_query_output_port().Eval(sg.GetMyContextFromRoot(ctx))
    inspector = query.inspector()
    out = {}
    for pair in query.ComputeSignedDistancePairwiseClosestPoints(0.2):
        names = [inspector.GetName(inspector.GetFrameId(g)) for g in (pair.id_A, pair.id_B)]
        table = [n for n in names if n.startswith("table::")]
        robot = [n for n in names if n.startswith(("ur10::", "svh::"))]
        if table and robot:
            out[robot[0]] = min(out.get(robot[0], np.inf), pair.distance)
    return out


#: what the hand carries rigidly: its own links and the arm's last link (the wrist flange)
CARRIED = ("svh::", "ur10::ur10_wrist_3_link")


def _hand_clearance(planning, plan, knot: str) -> float:
    i = plan.knot_names.index(knot)
    d = _distances_to_table(planning, plan.q_arm[i], plan.q_hand[i])
    return min(v for k, v in d.items() if k.startswith(CARRIED))


def test_a_grasp_slightly_too_low_is_raised_to_the_table_clearance(drill):
    planning, motion_W = drill
    params = PlanParams()
    reference = planning.plan(motion_W, params)
    assert reference.ok
    clearance_ref = _hand_clearance(planning, reference, "grasp")
    # lower the whole motion until the hand would sit 6 mm INTO the table
    low = _shifted(motion_W, -(clearance_ref + 0.006))
    plan = planning.plan(low, params)
    assert plan.ok, plan.status
    clearance = _hand_clearance(planning, plan, "grasp")
    # raised to the clearance (the primitives' lowest point vs Drake's distance: within 1 mm)
    assert clearance == pytest.approx(params.table_clearance, abs=1e-3)


def _pitched_up(motion: GraspMotion, angle: float) -> GraspMotion:
    """``motion`` turned by ``angle`` (rad) about the grasp point so the fingers point up and the wrist down."""
    X_g = motion.pose("grasp")
    axis = np.cross(X_g[:3, 2], [0.0, 0.0, 1.0])
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()
    return dataclasses.replace(motion, poses=perturb_poses(motion.poses, T, X_g[:3, 3]))


def test_the_wrist_flange_is_raised_over_the_table_with_the_hand(drill):
    """Fingers pointing up put the wrist's last link lowest: it, not the hand, sets the raise."""
    planning, motion_W = drill
    params = PlanParams()
    tilted = _shifted(_pitched_up(motion_W, np.radians(35.0)), 0.08)
    reference = planning.plan(tilted, params)
    assert reference.ok, reference.status
    i = reference.knot_names.index("grasp")
    d = _distances_to_table(planning, reference.q_arm[i], reference.q_hand[i])
    assert d["ur10::ur10_wrist_3_link"] < min(v for k, v in d.items() if k.startswith("svh::"))
    low = _shifted(tilted, -(d["ur10::ur10_wrist_3_link"] + 0.006))  # wrist 6 mm INTO the table
    plan = planning.plan(low, params)
    assert plan.ok, plan.status
    d = _distances_to_table(planning, plan.q_arm[i], plan.q_hand[i])
    # within the IK's tolerances: 1 mm in position, 0.01 rad in orientation (~1 mm at the flange)
    assert d["ur10::ur10_wrist_3_link"] == pytest.approx(params.table_clearance,
                                                         abs=params.position_tol + 0.1 * params.orientation_tol)


def test_a_grasp_far_below_the_table_is_refused(drill):
    planning, motion_W = drill
    plan = planning.plan(_shifted(motion_W, -0.08), PlanParams())
    assert not plan.ok
    assert plan.status.startswith("collision: hand") and "into the table" in plan.status


def test_the_executed_approach_keeps_the_robot_off_the_table(drill):
    planning, motion_W = drill
    plan = planning.plan(motion_W, PlanParams())
    assert plan.ok
    trajectory = plan.arm_trajectory()
    t0, t1 = plan.timeline.approach, plan.timeline.reach
    i_pre = plan.knot_names.index("pregrasp")
    worst = np.inf
    for t in np.linspace(t0, t1, 60):
        # hand posture: as the generator interpolates it (open -> preshape, linear in time)
        q_hand = np.array([np.interp(t, plan.times, plan.q_hand[:, j]) for j in range(plan.q_hand.shape[1])])
        d = _distances_to_table(planning, trajectory.value(t).ravel(), q_hand)
        worst = min([worst] + list(d.values()))
    assert worst > 0.0
    assert i_pre > 0


def _hand_pose(planning, q_arm) -> np.ndarray:
    """X_WH (4x4) of the hand base at arm configuration ``q_arm`` (forward kinematics)."""
    from catgrasp_drake.robot.models import HAND_BASE_LINK

    plant = planning.plant
    pc = plant.GetMyMutableContextFromRoot(planning.diagram.CreateDefaultContext())
    for name, q in zip(ARM_JOINTS, q_arm):
        plant.GetJointByName(name, planning.arm).set_angle(pc, q)
    return plant.EvalBodyPoseInWorld(pc, plant.GetBodyByName(HAND_BASE_LINK, planning.hand)).GetAsMatrix4()


def test_the_shake_moves_the_hand_base_vertically_with_its_orientation_fixed(drill):
    """The disturbance after the hold: the hand base goes up and down sinusoidally, ±a / (2 pi f)^2 =
    ±1.27 cm about its mean along world z, from rest to rest, peak acceleration ~2 m/s^2 (forward
    kinematics on the plan's knots and on the executed cubic); no turning, no sideways motion."""
    from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS
    from catgrasp_drake.station.judge import rotation_deg

    planning, motion_W = drill
    params = PlanParams()
    plan = planning.plan(motion_W, params)
    assert plan.ok, plan.status
    tl = plan.timeline
    assert PHASES[-1] == "end" and tl.hold < tl.shake < tl.press < tl.end
    assert tl.shake - tl.hold == pytest.approx(motion_W.hold_time + params.hold_margin)
    assert tl.press - tl.shake == pytest.approx(1.0) and tl.end - tl.press == pytest.approx(0.5)
    amplitude = shake_amplitude(params)
    assert amplitude == pytest.approx(2.0 / (2 * np.pi * 2.0) ** 2) and amplitude == pytest.approx(0.0127, abs=1e-4)
    X_ref = _hand_pose(planning, plan.q_arm[plan.knot_names.index("hold_end")])
    shake = [i for i, t in enumerate(plan.times) if tl.shake < t <= tl.press]
    assert len(shake) == 16
    dz, horizontal, turn = [], [], []
    for i in shake:
        X = _hand_pose(planning, plan.q_arm[i])
        dz.append(X[2, 3] - X_ref[2, 3])
        horizontal.append(np.linalg.norm(X[:2, 3] - X_ref[:2, 3]))
        turn.append(rotation_deg(X_ref, X))
        phase = 2 * np.pi * params.shake_frequency * (plan.times[i] - tl.shake)
        assert dz[-1] == pytest.approx(amplitude * (1 - np.cos(phase)), abs=3e-4)
    mean = 0.5 * (max(dz) + min(dz))
    assert max(dz) - mean == pytest.approx(amplitude, abs=3e-4) and mean - min(dz) == pytest.approx(amplitude, abs=3e-4)
    assert abs(dz[-1]) < 1e-4  # back at the lifted height
    assert max(horizontal) < 1e-3 and max(turn) < 1.0
    # the executed cubic: within the knots' envelope, orientation fixed, peak acceleration ~ 2 m/s^2
    traj = plan.arm_trajectory()
    ts = np.linspace(tl.shake - 0.1, tl.press + 0.1, 241)
    z = []
    for t in ts:
        X = _hand_pose(planning, traj.value(t).ravel())
        z.append(X[2, 3] - X_ref[2, 3])
        assert -1e-4 <= z[-1] <= 2 * amplitude + 1e-3
        assert rotation_deg(X_ref, X) < 1.0
    acceleration = np.diff(z, 2) / (ts[1] - ts[0]) ** 2
    assert 1.8 < np.abs(acceleration).max() < 2.4
    # the press: the arm holds, the index finger's joints go to their upper limits, the rest stays closed
    i_end, i_hold = plan.knot_names.index("end"), plan.knot_names.index("hold_end")
    assert np.allclose(plan.q_arm[i_end], plan.q_arm[i_hold], atol=1e-9)
    limits = {"svh_index_proximal": 0.79849, "svh_index_distal": 1.334}
    for j, name in enumerate(HAND_ACTUATED_JOINTS):
        want = limits.get(name, plan.q_hand[i_hold][j])
        assert plan.q_hand[i_end][j] == pytest.approx(want)


# ----------------------------------------------------------------------------- object clearance
@pytest.fixture(scope="module")
def drill_station():
    from catgrasp_drake.trial import trial_diagram

    scenario = load_scenario("drill_default")
    return scenario, trial_diagram(scenario)


def _pushed_in(motion_W: GraspMotion, depth: float) -> GraspMotion:
    """``motion_W`` moved ``depth`` (m) along its grasp's approach direction (H's +y: out of the palm)."""
    poses = motion_W.poses.copy()
    poses[:, :3, 3] += depth * motion_W.pose("grasp")[:3, 1]
    return dataclasses.replace(motion_W, poses=poses)


def test_the_true_object_planner_moves_a_hand_pushed_into_the_handle_back_out(drill_station):
    from catgrasp_drake.trial import plan_for

    scenario, td = drill_station
    motion_W = load_handwritten_motion("drill", "drill_00").in_world(scenario.X_WO())
    as_written = plan_for(td, motion_W)
    assert as_written.ok and not any(as_written.object_shift)  # the hand-written grasp is clear of drill_00
    pushed = _pushed_in(motion_W, 0.02)  # the preshaped hand stands a few mm off the handle as written
    plan = plan_for(td, pushed)
    assert plan.ok
    shift = np.asarray(plan.object_shift)
    palm_W = pushed.pose("grasp")[:3, 1]
    # out of the handle, against the push, by most of it (the tolerance lets the hand stay 4 mm in)
    assert 0.006 < np.linalg.norm(shift) < 0.02
    assert shift @ palm_W < -0.6 * np.linalg.norm(shift)
    off = plan_for(td, pushed, PlanParams(object_penetration_tol=None))
    assert off.ok and not any(off.object_shift)


def test_a_hand_deep_inside_the_object_is_refused(drill_station):
    from catgrasp_drake.trial import plan_for

    scenario, td = drill_station
    motion_W = load_handwritten_motion("drill", "drill_00").in_world(scenario.X_WO())
    plan = plan_for(td, _pushed_in(motion_W, 0.03), PlanParams(max_object_shift=0.003))
    assert plan.status.startswith("collision: grasp (the preshaped hand")
    assert plan.failure_reason == "collision_before_closing"
