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

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from catgrasp_drake.category_model import CategoryModel, apply_similarity_to_poses
from catgrasp_drake.core.cpd import nonrigid_cpd
from catgrasp_drake.core.deformation import warp_poses
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.descriptor import motion_from_descriptor
from catgrasp_drake.grasping.motion import GraspMotion

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


def rigid_space(space):
    """The shape space with its deformation switched off: every latent vector decodes to the canonical shape."""
    return dataclasses.replace(space, W_mean=np.zeros_like(space.W_mean),
                               components=np.zeros_like(space.components))


def _placed(model: CategoryModel, poses_O: np.ndarray, X_WO: np.ndarray, s: float) -> np.ndarray:
    return apply_similarity_to_poses(poses_O, X_WO[:3, :3], X_WO[:3, 3], s, anchor=model.grasp_anchor_H)


def _motion(model: CategoryModel, poses_W: np.ndarray, like: GraspMotion) -> GraspMotion:
    return GraspMotion(poses_W, like.pose_names, dict(like.postures), "world", like.lift_height, like.hold_time)


def nearest_instance(model: CategoryModel, x) -> int:
    """Index of the training instance with at least one stored success whose latent vector is closest to x."""
    if model.training_groups is None:
        raise InputError("the nearest-instance baseline needs a model file with its training set")
    with_success = np.unique(model.training_groups)
    d = np.linalg.norm(model.space.latent_train[with_success] - np.asarray(x, float), axis=1)
    return int(with_success[int(np.argmin(d))])


def predict_grasp(method: str, model: CategoryModel, observed_W, X_WT, *, camera_W=None,
                  yaw_candidates=8) -> Prediction:
    """``method``'s grasp (module docstring) for the object points ``observed_W`` (N, 3) on the table ``X_WT``."""
    from catgrasp_drake.systems.shape_estimator import estimate_on_table

    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
    t0 = time.perf_counter()
    space = rigid_space(model.space) if method in ("rigid", "cpd") else model.space
    est = estimate_on_table(space, observed_W, X_WT, camera_W=camera_W, yaw_candidates=yaw_candidates)
    timing = {"fit": time.perf_counter() - t0}
    if not est.ok:
        return Prediction(method, None, est, timing | {"total": time.perf_counter() - t0}, est.status)
    template = model.template
    if method == "latent":
        motion = model.transfer(est.x, est.X_WO[:3, :3], est.X_WO[:3, 3], est.scale, frame="world")
    elif method == "rigid":
        motion = _motion(model, _placed(model, template.poses, est.X_WO, est.scale), template)
    elif method == "cpd":
        t1 = time.perf_counter()
        source = est.completed_W  # the canonical shape, similarity-aligned (rigid space: no deformation)
        beta = model.space.beta * est.scale
        r = nonrigid_cpd(source, est.observed_W, beta=beta, lam=model.space.lam, w=0.05, max_iter=100, tol=1e-5)
        placed = _placed(model, template.poses, est.X_WO, est.scale)
        poses = warp_poses(source, r.W, beta, placed, **model.warp_options())
        timing["cpd"] = time.perf_counter() - t1
        motion = _motion(model, poses, template)
    else:  # nearest
        k = nearest_instance(model, est.x)
        canonical = motion_from_descriptor(model.instance_grasps(k).mean(axis=0), template)
        warped = warp_poses(model.space.canonical, model.space.decode(est.x), model.space.beta, canonical.poses,
                            **model.warp_options())
        motion = _motion(model, _placed(model, warped, est.X_WO, est.scale), canonical)
        timing["total"] = time.perf_counter() - t0
        return Prediction(method, motion, est, timing, f"nearest training instance: {model.instances[k]}")
    timing["total"] = time.perf_counter() - t0
    return Prediction(method, motion, est, timing)
