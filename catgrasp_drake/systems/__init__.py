"""Drake LeafSystems of the transfer: thin wrappers over the package's pure functions (ports and calls only).

- :mod:`~catgrasp_drake.systems.shape_estimator`: ``LatentShapeEstimator`` (cloud -> latent shape, pose);
- :mod:`~catgrasp_drake.systems.predictors`, :mod:`~catgrasp_drake.systems.grasp_regressor`:
  ``GraspPredictor``/``GraspRegressor`` (latent shape, pose -> grasp motion in W);
- :mod:`~catgrasp_drake.systems.grasp_execution`: ``PlanPlayback`` (plays a given plan) and
  ``MotionPlanner`` (plans an input motion, plays it).

The camera -> object-cloud systems the station needs are in :mod:`catgrasp_drake.perception`.
Import the submodules explicitly (they import pydrake).
"""
