"""Grasp execution systems: a plan (given, or made from an input motion) played back as desired joint states.

- :class:`PlanPlayback` plays a given :class:`~catgrasp_drake.planning.records.GraspPlan`;
  the plan is an abstract *parameter*, so one built diagram serves any number
  of trials (``set_plan(context, plan)``). The trial diagram uses it.
- :class:`MotionPlanner` plans the ``GraspMotion`` on its input port with a
  :class:`~catgrasp_drake.planning.model.PlanningModel` (once, in a cache
  entry) and plays that plan back. The transfer diagram uses it.

Both are ports and calls only: planning is :mod:`catgrasp_drake.planning`.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex
from pydrake.perception import PointCloud
from pydrake.systems.framework import BasicVector, LeafSystem, ValueProducer

from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.perception.object_cloud import points_from_cloud
from catgrasp_drake.planning.model import PlanningModel
from catgrasp_drake.planning.records import GraspPlan, PlanParams, hold_plan
from catgrasp_drake.robot.models import ARM_JOINTS, HAND_ACTUATED_JOINTS


def placeholder_motion_W() -> GraspMotion:
    """A valid do-nothing world-frame motion: the model value of abstract ``grasp_motion_W`` ports."""
    postures = {k: np.zeros(9) for k in ("open", "preshape", "closed")}
    return GraspMotion(np.tile(np.eye(4), (2, 1, 1)), postures=postures, frame="world")


def refusal_status(confidence: float, min_confidence: float) -> str | None:
    """Why a transferred grasp is refused (``None``: go ahead)."""
    if not np.isfinite(confidence) or confidence <= 0.0:
        return "refused: no shape estimate (confidence 0): take another view"
    if confidence < min_confidence:
        return f"refused: low confidence ({confidence:.2f} < {min_confidence:.2f}): take another view"
    return None


def actuator_order(plant: MultibodyPlant, instance: ModelInstanceIndex, joint_names) -> np.ndarray:
    """perm such that x_actuators = x_named[perm] (actuator order of the instance)."""
    names = list(joint_names)
    perm = []
    for ai in plant.GetJointActuatorIndices(instance):
        jname = plant.get_joint_actuator(ai).joint().name()
        if jname not in names:
            raise InputError(f"actuated joint {jname!r} is not in the joint list {names}")
        perm.append(names.index(jname))
    return np.array(perm, int)


def _state_perm(perm: np.ndarray) -> np.ndarray:
    """The permutation of ``[q; v]`` for the position permutation ``perm``."""
    return np.concatenate([perm, perm + len(perm)])


class _PlanCache:
    """A plan with its trajectories built once (the abstract parameter's or cache entry's value)."""

    def __init__(self, plan: GraspPlan):
        self.plan = plan
        self._arm = plan.arm_trajectory()
        self._hand = plan.hand_trajectory()
        self._arm_d = self._arm.derivative(1)
        self._hand_d = self._hand.derivative(1)
        self._t0, self._t1 = float(plan.times[0]), float(plan.times[-1])

    def _eval(self, traj, dtraj, t):
        inside = self._t0 < t < self._t1
        tc = min(max(t, self._t0), self._t1)
        q = traj.value(tc).ravel()
        v = dtraj.value(tc).ravel() if inside else np.zeros_like(q)
        return np.concatenate([q, v])

    def arm_state(self, t: float) -> np.ndarray:
        return self._eval(self._arm, self._arm_d, t)

    def hand_state(self, t: float) -> np.ndarray:
        return self._eval(self._hand, self._hand_d, t)

    # Contexts deep-copy their abstract parameters; the plan and its trajectories are immutable.
    def __deepcopy__(self, memo):
        return self

    def __copy__(self):
        return self


class PlanPlayback(LeafSystem):
    """Plays back a :class:`~catgrasp_drake.planning.records.GraspPlan` as desired states of the PD-gained actuators.

    .. pydrake_system::

        name: PlanPlayback
        output_ports:
        - arm_desired_state
        - hand_desired_state
        - plan_status

    Parameters (abstract):
        plan: the ``GraspPlan`` (``set_plan(context, plan)``; default: the
            plan given at construction).
    Output ports:
        arm_desired_state: [q; v] (2 * 6) of the arm, actuator order, rad and rad/s.
        hand_desired_state: [q; v] (2 * 9) of the hand's actuated joints, actuator order.
        plan_status: str, ``"ok"`` or the planning failure.
    Before ``plan.times[0]`` and after ``plan.times[-1]`` the end values are held (zero velocity).
    """

    def __init__(self, plant: MultibodyPlant, arm: ModelInstanceIndex, hand: ModelInstanceIndex,
                 default_plan: GraspPlan):
        super().__init__()
        self._arm_perm = _state_perm(actuator_order(plant, arm, ARM_JOINTS))
        self._hand_perm = _state_perm(actuator_order(plant, hand, HAND_ACTUATED_JOINTS))
        self._plan_index = self.DeclareAbstractParameter(AbstractValue.Make(_PlanCache(default_plan)))
        self.DeclareVectorOutputPort("arm_desired_state", len(self._arm_perm), self._calc_arm)
        self.DeclareVectorOutputPort("hand_desired_state", len(self._hand_perm), self._calc_hand)
        self.DeclareAbstractOutputPort("plan_status", lambda: AbstractValue.Make(""), self._calc_status,
                                       prerequisites_of_calc={self.all_parameters_ticket()})

    def set_plan(self, context, plan: GraspPlan) -> None:
        """Use ``plan`` in ``context`` (this system's context)."""
        context.get_mutable_abstract_parameter(self._plan_index).set_value(_PlanCache(plan))

    def get_plan(self, context) -> GraspPlan:
        return self._cache(context).plan

    def _cache(self, context) -> _PlanCache:
        return context.get_abstract_parameter(self._plan_index).get_value()

    def _calc_arm(self, context, output: BasicVector):
        output.SetFromVector(self._cache(context).arm_state(context.get_time())[self._arm_perm])

    def _calc_hand(self, context, output: BasicVector):
        output.SetFromVector(self._cache(context).hand_state(context.get_time())[self._hand_perm])

    def _calc_status(self, context, output):
        output.set_value(self.get_plan(context).status)


class MotionPlanner(LeafSystem):
    """Plans a grasping motion given on an input port and plays the plan back.

    .. pydrake_system::

        name: MotionPlanner
        input_ports:
        - grasp_motion_W
        - confidence
        - object_cloud_W (with obstacle_model only)
        - grasp_candidates_W (optional)
        output_ports:
        - plan
        - arm_desired_state
        - hand_desired_state
        - plan_status

    Input ports:
        grasp_motion_W: ``GraspMotion`` (frame "world"): hand-base control
            poses X_WH and postures, e.g. from ``GraspRegressor``.
        confidence: (1,) the shape estimate's confidence in [0, 1] (optional;
            unconnected = 1). Below ``min_confidence`` (or 0: no estimate) the
            motion is refused: the plan holds the start configuration with the
            hand open and its status says "refused: ... take another view".
        object_cloud_W: ``PointCloud`` of the object as perceived (e.g. the
            completed shape), metres, W (optional; declared when an
            ``obstacle_model`` is given): the plan is made on
            ``obstacle_model(points_W)`` (>= 4 finite points), so the arm's way
            to the pregrasp avoids the object.
        grasp_candidates_W: tuple of ``GraspCandidate`` (optional; e.g. from
            ``GraspPredictor``), best first: when connected and not empty it
            replaces ``grasp_motion_W`` -- each is planned in turn, around its
            own ``object_points_W`` (with an ``obstacle_model``; else around
            ``object_cloud_W``), and the first plan without collision is
            executed (``plan.candidate`` says which); if none, the first's
            failure is reported.
    Output ports:
        plan: ``GraspPlan`` (joint knots, timeline, status).
        arm_desired_state: [q; v] (2 * 6) of the arm, actuator order, rad and rad/s.
        hand_desired_state: [q; v] (2 * 9) of the hand's actuated joints, actuator order.
        plan_status: str, "ok" or why there is no motion.
    Parameters (constructor): the executing ``plant`` and its ``arm``/``hand``
    instances (for the actuator order), the ``PlanningModel`` without the
    object, ``obstacle_model`` (``points_W (N, 3) -> PlanningModel`` with
    them as the object, e.g. ``planning_model.with_obstacle``),
    ``params``, ``min_confidence``.
    Evaluation model: the plan is a cache entry that depends on the input
    ports only, so IK runs once per motion (at the first evaluation) and every
    simulation step reuses it. The plan's time 0 is the simulation's time 0.
    """

    def __init__(self, plant: MultibodyPlant, arm: ModelInstanceIndex, hand: ModelInstanceIndex,
                 planning_model: PlanningModel, *,
                 obstacle_model: Callable[[np.ndarray], PlanningModel] | None = None,
                 params: PlanParams = PlanParams(), min_confidence: float = 0.0):
        super().__init__()
        if not 0.0 <= float(min_confidence) <= 1.0:
            raise InputError(f"min_confidence: expected a value in [0, 1], got {min_confidence}")
        self._arm_perm = _state_perm(actuator_order(plant, arm, ARM_JOINTS))
        self._hand_perm = _state_perm(actuator_order(plant, hand, HAND_ACTUATED_JOINTS))
        self._planning = planning_model
        self._obstacle_model = obstacle_model
        self._params = params
        self._min_conf = float(min_confidence)
        self._motion_in = self.DeclareAbstractInputPort("grasp_motion_W", AbstractValue.Make(placeholder_motion_W()))
        self._conf_in = self.DeclareVectorInputPort("confidence", 1)
        self._candidates_in = self.DeclareAbstractInputPort("grasp_candidates_W", AbstractValue.Make(()))
        self._obstacle_in = None
        if obstacle_model is not None:
            self._obstacle_in = self.DeclareAbstractInputPort("object_cloud_W", AbstractValue.Make(PointCloud()))
        q_open = np.zeros(9)
        self._idle = _PlanCache(hold_plan(planning_model.q_arm_start, q_open, "no motion"))
        self._cache = self.DeclareCacheEntry(
            "plan", ValueProducer(allocate=AbstractValue.Make(self._idle).Clone, calc=self._calc_plan),
            {self.all_input_ports_ticket()})
        self.DeclareAbstractOutputPort("plan", lambda: AbstractValue.Make(self._idle.plan),
                                       lambda c, o: o.set_value(self._plan_cache(c).plan),
                                       prerequisites_of_calc={self._cache.ticket()})
        self.DeclareVectorOutputPort("arm_desired_state", len(self._arm_perm), self._calc_arm)
        self.DeclareVectorOutputPort("hand_desired_state", len(self._hand_perm), self._calc_hand)
        self.DeclareAbstractOutputPort("plan_status", lambda: AbstractValue.Make(""),
                                       lambda c, o: o.set_value(self._plan_cache(c).plan.status),
                                       prerequisites_of_calc={self._cache.ticket()})

    @property
    def planning_model(self) -> PlanningModel:
        """The robot's planning model (without the perceived object; that is added per plan)."""
        return self._planning

    def _plan_cache(self, context) -> _PlanCache:
        return self._cache.Eval(context)

    def _calc_plan(self, context, value):
        candidates = self._candidates_in.Eval(context) if self._candidates_in.HasValue(context) else ()
        motion = candidates[0].motion if candidates else self._motion_in.Eval(context)
        conf = float(self._conf_in.Eval(context)[0]) if self._conf_in.HasValue(context) else 1.0
        refusal = refusal_status(conf, self._min_conf)
        if refusal is not None:
            value.set_value(_PlanCache(hold_plan(self._planning.q_arm_start, motion.posture("open"), refusal)))
            return
        cloud_W = None
        if self._obstacle_in is not None and self._obstacle_in.HasValue(context):
            cloud_W = points_from_cloud(self._obstacle_in.Eval(context))
        # (motion, its own obstacle points or None: the object_cloud_W port's) in rank order
        tries = [(c.motion, c.object_points_W if len(c.object_points_W) >= 4 else None) for c in candidates]
        first = None
        for i, (m, points_W) in enumerate(tries or [(motion, None)]):
            plan = self._planning_for(cloud_W if points_W is None else points_W).plan(m, self._params)
            if plan.ok:
                value.set_value(_PlanCache(dataclasses.replace(plan, candidate=i, tried=i + 1)))
                return
            if first is None:
                first = plan
        value.set_value(_PlanCache(dataclasses.replace(first, tried=max(1, len(tries)))))

    def _planning_for(self, points_W) -> PlanningModel:
        """The planning model with ``points_W`` (N, 3) as the object (>= 4 points and an obstacle model), else
        without it."""
        if self._obstacle_model is not None and points_W is not None and len(points_W) >= 4:
            return self._obstacle_model(points_W)
        return self._planning

    def _calc_arm(self, context, output: BasicVector):
        output.SetFromVector(self._plan_cache(context).arm_state(context.get_time())[self._arm_perm])

    def _calc_hand(self, context, output: BasicVector):
        output.SetFromVector(self._plan_cache(context).hand_state(context.get_time())[self._hand_perm])
