"""Grasp predictors: the transfer diagram's grasp-prediction stage for every method.

:class:`GraspPredictor` has the ports of :class:`~catgrasp_drake.systems.grasp_regressor.GraspRegressor`
(``x``, ``X_WO``, ``scale`` -> ``grasp_motion_W``) and runs one method of
:mod:`catgrasp_drake.prediction` (``latent``, ``paper``, ``rigid``, ``cpd``,
``nearest``, ``true_object``), so a baseline is swapped into
``make_transfer_diagram`` without touching the rest of the diagram: every
method is perceived, estimated, planned around the perceived shape, refused
below the confidence threshold and executed in the same way.

Evaluation model: the candidates are a cache entry on the input ports (the
estimate is state, so the prediction runs once per estimate); both outputs read it.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.perception import PointCloud
from pydrake.systems.framework import LeafSystem, ValueProducer

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.errors import CatgraspError, InputError
from catgrasp_drake.grasping.descriptor import motion_functional_point
from catgrasp_drake.perception.object_cloud import points_from_cloud
from catgrasp_drake.prediction import (
    GraspCandidate,
    ShapeHypothesis,
    check_method,
    grasp_candidates,
    predict_motion,
)
from catgrasp_drake.systems.shape_estimator import failed_estimate


class GraspPredictor(LeafSystem):
    """Predicts the grasping motion in W for an estimated shape and pose, by one method.

    .. pydrake_system::

        name: GraspPredictor
        input_ports:
        - x
        - X_WO
        - scale
        - observed_cloud_W (cpd only)
        - completed_cloud_W (cpd only)
        - estimate (optional)
        output_ports:
        - grasp_motion_W
        - grasp_candidates_W

    Input ports:
        x: latent vector (q,) of the model's shape space.
        X_WO: ``RigidTransform``, pose of the canonical frame O in the world W.
        scale: (1,) uniform scale of the canonical shape (1 if unconnected).
        observed_cloud_W, completed_cloud_W: ``PointCloud`` (W, metres), declared
            for the ``cpd`` method only (its field registers one onto the other);
            connect the estimator's outputs (fixed once estimated), not a camera's
            port, or the prediction and the plan are recomputed at every step.
        estimate: ``ShapeEstimate`` (optional): when it carries shape
            hypotheses (the estimator's ``hypotheses`` > 1), a grasp is
            predicted for each and ranked across the posterior
            (:func:`catgrasp_drake.prediction.grasp_candidates`); without
            hypotheses, its completed shape is the single candidate's obstacle.
    Output ports:
        grasp_motion_W: ``GraspMotion`` (``frame == "world"``): control poses
            X_WH of the hand base H, metres, and the hand postures -- the first
            of ``grasp_candidates_W``. If the method cannot predict (CPD
            without a cloud: no estimate) the output is the undeformed
            canonical grasp at X_WO, which the trajectory generator refuses by
            the estimate's zero confidence.
        grasp_candidates_W: tuple of ``GraspCandidate`` (best first), for a
            planner that executes the first feasible one (``MotionPlanner``).
    Parameters (constructor): the trained ``CategoryModel`` and the method name.
    """

    def __init__(self, model: CategoryModel, method: str = "latent"):
        super().__init__()
        if not isinstance(model, CategoryModel):
            raise InputError(f"model: expected a CategoryModel, got {type(model).__name__}")
        self._model = model
        self._method = check_method(method)
        self._x_in = self.DeclareVectorInputPort("x", model.space.q)
        self._X_in = self.DeclareAbstractInputPort("X_WO", AbstractValue.Make(RigidTransform()))
        self._s_in = self.DeclareVectorInputPort("scale", 1)
        self._clouds = None
        if method == "cpd":
            self._clouds = (self.DeclareAbstractInputPort("observed_cloud_W", AbstractValue.Make(PointCloud())),
                            self.DeclareAbstractInputPort("completed_cloud_W", AbstractValue.Make(PointCloud())))
        self._estimate_in = self.DeclareAbstractInputPort("estimate",
                                                          AbstractValue.Make(failed_estimate(model.space.q, "")))
        default = model.transfer(np.zeros(model.space.q), frame="world")
        idle = (GraspCandidate(default, np.zeros((0, 3)), 0, 1.0, 1.0,
                               motion_functional_point(default, model.grasp_anchor_H)),)
        self._candidates = self.DeclareCacheEntry(
            "grasp_candidates", ValueProducer(allocate=AbstractValue.Make(idle).Clone, calc=self._calc_candidates),
            {self.all_input_ports_ticket()})
        self.DeclareAbstractOutputPort("grasp_motion_W", lambda: AbstractValue.Make(default),
                                       lambda c, o: o.set_value(self._candidates.Eval(c)[0].motion),
                                       prerequisites_of_calc={self._candidates.ticket()})
        self.DeclareAbstractOutputPort("grasp_candidates_W", lambda: AbstractValue.Make(idle),
                                       lambda c, o: o.set_value(self._candidates.Eval(c)),
                                       prerequisites_of_calc={self._candidates.ticket()})

    @property
    def model(self) -> CategoryModel:
        return self._model

    @property
    def method(self) -> str:
        return self._method

    def _calc_candidates(self, context, value):
        estimate = self._estimate_in.Eval(context) if self._estimate_in.HasValue(context) else None
        fits = [h for h in estimate.hypotheses if np.isfinite(h.energy)] if estimate is not None and estimate.ok else []
        if len(fits) > 1 and self._method != "cpd":
            hypotheses = [ShapeHypothesis(h.x, h.X_WO, h.scale, h.completed_W, h.energy,
                                          h.result.plain_energy if h.result is not None else float("nan"),
                                          max(h.uncovered, 0))
                          for h in fits]
            value.set_value(tuple(grasp_candidates(self._method, self._model, hypotheses)))
            return
        motion = self._single(context)
        points = estimate.completed_W if estimate is not None else np.zeros((0, 3))
        value.set_value((GraspCandidate(motion, points, 0, 1.0, 1.0,
                                        motion_functional_point(motion, self._model.grasp_anchor_H)),))

    def _single(self, context):
        """The method's grasp for the estimate on the x, X_WO, scale (and cloud) ports."""
        s = float(self._s_in.Eval(context)[0]) if self._s_in.HasValue(context) else 1.0
        X_WO = self._X_in.Eval(context).GetAsMatrix4()
        x = self._x_in.Eval(context)
        clouds = {}
        if self._clouds is not None:
            clouds = {"observed_W": points_from_cloud(self._clouds[0].Eval(context)),
                      "completed_W": points_from_cloud(self._clouds[1].Eval(context))}
        try:
            motion, _ = predict_motion(self._method, self._model, x, X_WO, s, **clouds)
        except CatgraspError:  # no usable cloud: fall back to the undeformed grasp at the estimated pose
            motion = self._model.transfer(np.zeros(self._model.space.q), X_WO[:3, :3], X_WO[:3, 3], s)
        return motion
