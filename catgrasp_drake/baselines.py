"""Grasp prediction from an observed cloud by this project's method and the evaluation's baselines.

All four start from the same observation (object points in the world W, the
table frame T, optionally the camera position for a single view) and return a
grasping motion in W; each is offered a scale (DESIGN.md section 9):

``latent``   the paper's method: latent shape + similarity fit, regressed grasp
             R(x) warped by W(x) (:meth:`CategoryModel.transfer`).
``rigid``    the canonical motion on the canonical shape, aligned to the
             observation by a similarity only (no deformation): the same
             fit (yaw multi-start, visibility) with the shape space's
             deformation switched off.
``cpd``      the rigid alignment, then direct non-rigid CPD from the aligned
             canonical shape to the observation; the canonical motion is
             warped by that field (no latent space).
``nearest``  the latent fit, then the grasps that succeeded on the training
             instance whose latent vector is closest (their mean descriptor),
             warped by W(x) like the latent method (no regression).

Pose warping uses the model's functional-point anchor and rotation radius
throughout, so the methods differ only in what they predict.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.prediction import ESTIMATORS, predict_motion, rigid_space
from catgrasp_drake.systems.shape_estimator import estimate_on_table

METHODS = ("latent", "rigid", "cpd", "nearest")


@dataclass(frozen=True, eq=False)
class Prediction:
    """A method's grasp for one observation: the motion in W, the shape estimate it used, timings (s)."""

    method: str
    motion_W: GraspMotion | None
    estimate: object  # systems.shape_estimator.ShapeEstimate (pure record)
    timing: dict = field(default_factory=dict)
    detail: str = ""

    @property
    def ok(self) -> bool:
        return self.motion_W is not None


def predict_grasp(method: str, model: CategoryModel, observed_W, X_WT, *, camera_W=None,
                  yaw_candidates=8) -> Prediction:
    """``method``'s grasp (module docstring) for the object points ``observed_W`` (N, 3) on the table ``X_WT``.

    The maths of each method is :func:`catgrasp_drake.prediction.predict_motion`
    (shared with the transfer diagram's predictor systems).
    """
    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
    t0 = time.perf_counter()
    setup = ESTIMATORS[method]
    space = rigid_space(model.space) if setup.rigid else model.space
    est = estimate_on_table(space, observed_W, X_WT, camera_W=camera_W, yaw_candidates=yaw_candidates,
                            **dict(setup.inference))
    timing = {"fit": time.perf_counter() - t0}
    if not est.ok:
        return Prediction(method, None, est, timing | {"total": time.perf_counter() - t0}, est.status)
    t1 = time.perf_counter()
    motion, detail = predict_motion(method, model, est.x, est.X_WO, est.scale, observed_W=est.observed_W,
                                    completed_W=est.completed_W)
    if method == "cpd":
        timing["cpd"] = time.perf_counter() - t1
    timing["total"] = time.perf_counter() - t0
    return Prediction(method, motion, est, timing, detail)
