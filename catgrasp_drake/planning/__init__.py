"""Grasp planning: the IK planner that turns a world-frame ``GraspMotion`` into joint knots.

- :mod:`~catgrasp_drake.planning.records`: the plan records (``PlanParams``,
  ``Timeline``, ``GraspPlan``) -- plain data, no Drake systems;
- :mod:`~catgrasp_drake.planning.scene`: the planning scene (plant, scratch
  contexts, geometry sets) and its queries: IK, collisions, distances, table
  clearance;
- :mod:`~catgrasp_drake.planning.planner`: :func:`~catgrasp_drake.planning.planner.plan_grasp`,
  one function per phase (pregrasp + approach, reach, lift, shake, press,
  timeline);
- :mod:`~catgrasp_drake.planning.model`: ``PlanningModel`` (the robot's own
  model of the world) and its factory ``make_planning_model``.

The LeafSystems that play plans back live in :mod:`catgrasp_drake.systems.grasp_execution`.
"""
