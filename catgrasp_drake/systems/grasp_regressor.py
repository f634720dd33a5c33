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

from pydrake.math import RigidTransform

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.validation import real_array
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.systems.predictors import GraspPredictor


def predict_motion_W(model: CategoryModel, x, X_WO, scale: float) -> GraspMotion:
    """The transferred grasp (control poses of the hand base H in W, postures) for latent ``x`` at ``X_WO``."""
    X = X_WO.GetAsMatrix4() if isinstance(X_WO, RigidTransform) else real_array(X_WO, "X_WO", "4x4 pose")
    if X.shape != (4, 4):
        raise InputError(f"X_WO: expected a 4x4 pose or a RigidTransform, got shape {X.shape}")
    return model.transfer(x, X[:3, :3], X[:3, 3], scale, frame="world")


class GraspRegressor(GraspPredictor):
    """Predicts the grasping motion for an estimated shape and pose: the ``latent`` :class:`GraspPredictor`.

    .. pydrake_system::

        name: GraspRegressor
        input_ports:
        - x
        - X_WO
        - scale
        output_ports:
        - grasp_motion_W

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
        super().__init__(model, "latent")
