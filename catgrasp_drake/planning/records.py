"""Plan records: the parameters, phase times and joint knots of one grasp execution.

A plan that cannot be made is REPORTED in ``GraspPlan.status``
(``"unreachable: pregrasp"``, ``"ik_failed: grasp"``, ``"collision: pregrasp"``,
``"branch_flip: reach"`` ...; ``"refused: ..."`` when the transfer refuses a
motion); ``GraspPlan.failure_reason`` maps it to the trial's failure reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.trajectories import PiecewisePolynomial

from catgrasp_drake.errors import InputError

PHASES = ("settle", "approach", "reach", "close", "lift", "hold", "shake", "press", "end")
#: Failure kind of a plan (its status up to the colon) -> the trial's failure reason.
FAILURE_REASONS = {"collision": "collision_before_closing", "unreachable": "unreachable",
                   "ik_failed": "unreachable", "branch_flip": "unreachable"}
#: How the hand closes (``PlanParams.close_order``).
CLOSE_ORDERS = ("together", "thumb_first")


@dataclass(frozen=True)
class PlanParams:
    """Timing (s), tolerances (m, rad) and knot counts of the grasp execution."""

    settle_time: float = 0.1
    min_approach_time: float = 1.2
    max_joint_speed: float = 1.2  # rad/s, sets the approach duration
    reach_time: float = 0.8
    close_time: float = 0.8
    close_dwell: float = 0.3
    #: "together": every hand joint goes preshape -> closed over ``close_time``; "thumb_first": the thumb's
    #: joints reach their closed values half-way through it while the others hold the preshape, then the others
    #: close (:data:`CLOSE_ORDERS`).
    close_order: str = "together"
    lift_time: float = 1.0
    hold_margin: float = 0.1
    shake_time: float = 1.0  # s, the disturbance after the hold
    shake_accel: float = 2.0  # m/s^2, peak vertical acceleration of the hand base
    shake_frequency: float = 2.0  # Hz
    shake_knots_per_s: int = 16
    press_time: float = 0.5  # s, index finger closed further (trigger press)
    press_ramp: float = 0.2  # s, of press_time, to go from the closed posture to the press posture
    reach_knots: int = 5
    lift_knots: int = 5
    position_tol: float = 1e-3
    orientation_tol: float = 0.01
    min_distance: float = 0.005  # robot vs environment at home->pregrasp
    reach_min_distance: float = 0.003  # robot vs table during the reach (preferred, not required)
    via_heights: tuple[float, ...] = (0.15, 0.30)  # m above the pregrasp, for approaches that need a via
    approach_margin: float = 0.01  # m, robot vs table/object along the home -> pregrasp path
    max_reach: float = 1.35  # m, shoulder to hand base; beyond -> "unreachable"
    max_knot_jump: float = 0.6  # rad between consecutive knots; above -> "branch_flip"
    wrist_clearance: float = 0.08  # m, wrist-1 origin above the hand base at pregrasp/grasp (if feasible)
    pregrasp_restarts: int = 12  # random IK restarts after the structured pregrasp seeds
    # The hand (preshape) at pregrasp and grasp is raised until its lowest point is this far above the
    # table top; a perceived grasp a few mm too low would otherwise put the palm into the table.
    table_clearance: float = 0.004  # m
    max_table_raise: float = 0.03  # m; a hand lower than this under the clearance is refused
    # Object clearance (planner.clear_object), where the planning model knows the object's surface: the
    # preshaped hand at the grasp pose may lie this deep inside the object (m; the deepest any hand-written
    # grasp goes on the committed instances is 3.5 mm); deeper, the pregrasp and grasp are moved by the
    # smallest translation that brings it back, at most max_object_shift, else the plan is refused.
    # None: no check.
    object_penetration_tol: float | None = 0.004
    max_object_shift: float = 0.02  # m

    def __post_init__(self):
        if self.close_order not in CLOSE_ORDERS:
            raise InputError(f"close_order: expected one of {', '.join(CLOSE_ORDERS)}, got {self.close_order!r}")


@dataclass(frozen=True)
class Timeline:
    """Phase start times (s); ``end`` is the last instant (the press is over)."""

    settle: float = 0.0
    approach: float = 0.0
    reach: float = 0.0
    close: float = 0.0
    lift: float = 0.0
    hold: float = 0.0
    shake: float = 0.0
    press: float = 0.0
    end: float = 0.0

    def as_dict(self) -> dict:
        return {p: getattr(self, p) for p in PHASES}


@dataclass(frozen=True, eq=False)
class GraspPlan:
    """Joint-space knots of a grasp execution (or the reason there are none).

    ``times`` (M,), ``q_arm`` (M, 6) in ``ARM_JOINTS`` order, ``q_hand`` (M, 9)
    in ``HAND_ACTUATED_JOINTS`` order; the arm is interpolated with a
    shape-preserving cubic, the hand linearly. ``v_arm`` (M, 6, optional):
    prescribed arm joint velocities at the knots (rad/s), NaN rows where the
    shape-preserving cubic decides; with it the arm is a cubic Hermite
    through the knots whose velocities at the NaN rows are the
    shape-preserving cubic's through those knots alone (the shake's knots
    carry their exact velocities). ``candidate``: which of the grasp
    candidates given to the planner this plan executes (0: the first, or the
    only one); ``tried``: how many were planned to get it. ``object_shift``:
    the translation (m, W) the object clearance moved the pregrasp and grasp
    by (zero when the hand was clear, or the object's surface unknown).
    """

    status: str
    timeline: Timeline
    times: np.ndarray
    q_arm: np.ndarray
    q_hand: np.ndarray
    knot_names: tuple[str, ...] = ()
    solve_time_s: float = 0.0
    v_arm: np.ndarray | None = None
    candidate: int = 0
    tried: int = 1
    object_shift: tuple[float, float, float] = (0.0, 0.0, 0.0)  # m, W: the object clearance's move of the grasp

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def failure_kind(self) -> str | None:
        """``None`` when ok, else the status up to the colon (``unreachable``, ``ik_failed`` ...)."""
        return None if self.ok else self.status.split(":")[0]

    @property
    def failure_reason(self) -> str | None:
        """``None`` when ok, else the trial's failure reason for a grasp never executed (``FAILURE_REASONS``).

        ``collision`` -> "collision_before_closing"; ``unreachable``, ``ik_failed``,
        ``branch_flip`` -> "unreachable"; any other kind (``refused``, ...) is kept.
        """
        kind = self.failure_kind
        return None if kind is None else FAILURE_REASONS.get(kind, kind)

    def arm_trajectory(self) -> PiecewisePolynomial:
        if len(self.times) < 2:
            return PiecewisePolynomial(self.q_arm[0][:, None])
        free = None if self.v_arm is None else np.isnan(np.asarray(self.v_arm, float)).any(axis=1)
        if free is None or free.all():
            return PiecewisePolynomial.CubicShapePreserving(self.times, self.q_arm.T, True)
        v = np.asarray(self.v_arm, float).copy()
        if free.sum() >= 2:
            base = PiecewisePolynomial.CubicShapePreserving(self.times[free], self.q_arm[free].T, True).derivative(1)
            for i in np.flatnonzero(free):
                v[i] = base.value(self.times[i]).ravel()
        else:
            v[free] = 0.0
        return PiecewisePolynomial.CubicHermite(self.times, self.q_arm.T, v.T)

    def hand_trajectory(self) -> PiecewisePolynomial:
        if len(self.times) < 2:
            return PiecewisePolynomial(self.q_hand[0][:, None])
        return PiecewisePolynomial.FirstOrderHold(self.times, self.q_hand.T)


def hold_plan(q_arm: np.ndarray, q_hand: np.ndarray, status: str, duration: float = 0.0) -> GraspPlan:
    """A plan that holds one configuration (used for failures and as the default)."""
    q_arm = np.asarray(q_arm, float)[None]
    q_hand = np.asarray(q_hand, float)[None]
    return GraspPlan(status, Timeline(end=duration), np.zeros(1), q_arm, q_hand, ("start",))
