"""The grasp regressor: latent shape x + object pose -> grasping motion in the world (Alg. 2, lines 2-3).

A thin LeafSystem over :meth:`catgrasp_drake.category_model.CategoryModel.transfer`:
the canonical descriptor R(x) is predicted, its control poses are warped by
the dense deformation field W(x) and re-orthonormalised, scaled by the fitted
scale s and moved by the object pose X_WO (the estimator's rigid part), so a
canonical-frame pose X_OH lands at ``X_WO * (s p_OH, R_OH)`` in W.

Evaluation model: output calculation with Drake's cache. The output depends
on the input ports only (not on time), so it is computed once per estimate
and reused by every simulation step.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.validation import real_array
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion


def predict_motion_W(model: CategoryModel, x, X_WO, scale: float) -> GraspMotion:
    """The transferred grasp (control poses of the hand base H in W, postures) for latent ``x`` at ``X_WO``."""
    X = X_WO.GetAsMatrix4() if isinstance(X_WO, RigidTransform) else real_array(X_WO, "X_WO", "4x4 pose")
    if X.shape != (4, 4):
        raise InputError(f"X_WO: expected a 4x4 pose or a RigidTransform, got shape {X.shape}")
    return model.transfer(x, X[:3, :3], X[:3, 3], scale, frame="world")


class GraspRegressor(LeafSystem):
    """Predicts the grasping motion for an estimated shape and pose.

    Input ports:
        x: latent vector (q,) of the category model's shape space.
        X_WO: ``RigidTransform``, pose of the canonical object frame O in the world W.
        scale: (1,) uniform scale of the canonical shape (1 if unconnected).
    Output ports:
        grasp_motion_W: ``GraspMotion`` with ``frame == "world"``: control
            poses X_WH (pregrasp, grasp) of the hand base link H, metres, and
            the hand postures (open, preshape, closed; rad, HAND_ACTUATED_JOINTS order).
    Parameters (constructor): the trained ``CategoryModel``.
    """

    def __init__(self, model: CategoryModel):
        super().__init__()
        if not isinstance(model, CategoryModel):
            raise InputError(f"model: expected a CategoryModel, got {type(model).__name__}")
        self._model = model
        self._x_in = self.DeclareVectorInputPort("x", model.space.q)
        self._X_in = self.DeclareAbstractInputPort("X_WO", AbstractValue.Make(RigidTransform()))
        self._s_in = self.DeclareVectorInputPort("scale", 1)
        default = model.transfer(np.zeros(model.space.q), frame="world")
        self.DeclareAbstractOutputPort("grasp_motion_W", lambda: AbstractValue.Make(default), self._calc,
                                       prerequisites_of_calc={self.all_input_ports_ticket()})

    @property
    def model(self) -> CategoryModel:
        return self._model

    def _calc(self, context, output):
        s = float(self._s_in.Eval(context)[0]) if self._s_in.HasValue(context) else 1.0
        output.set_value(predict_motion_W(self._model, self._x_in.Eval(context), self._X_in.Eval(context), s))
