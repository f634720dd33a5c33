"""A trained category model: shape space + grasp regressor + canonical motion (paper, Alg. 1 output).

``CategoryModel.transfer(x, R, t, s)`` is Algorithm 2 lines 2-3: predict the
canonical descriptor R(x), warp its control poses with the dense deformation
field W(x) (positions and rotation bases, re-orthonormalised), then apply the
similarity transform of the fit (rotation R, translation t, scale s) into the
observation frame. Both act on the grasp's functional point ``grasp_anchor_H``
(the canonical trigger or handle centre, fixed in the hand frame), the hand
staying rigid about it, turned by the field's rotation averaged over
``grasp_rotation_radius`` (on the drills the Jacobian at the trigger turns the
hand by 6.9 deg on average, up to 15.3; averaged over 5 cm, 3.1 and 7.6:
``benchmarks/bench_grasp_warp.py``). The hand base frame sits ~15 cm from the
object, where the kernel field has died out, and a scale error would be
multiplied by that lever arm.

File format (one ``.npz``, atomic, checksummed, no pickle): the shape space's
arrays under ``shape/``, the regressor under ``regressor/`` (its kind -- ridge,
kernel ridge or nearest instance, ``core.regression`` -- in the header; files
without one hold a ridge), the training set under ``training/``, and a JSON
header with the canonical motion (template), the parameters and the training
statistics. Kind ``catgrasp.category_model``, version 1.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace

import numpy as np

from catgrasp_drake.core.deformation import warp_poses
from catgrasp_drake.core.fileio import load_arrays, save_arrays
from catgrasp_drake.core.regression import Regressor, fit_ridge, regressor_from_arrays, regressor_to_arrays
from catgrasp_drake.core.shape_space import ShapeSpace
from catgrasp_drake.core.validation import positive, real_array, vector3
from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.grasping.descriptor import descriptor_size, motion_from_descriptor
from catgrasp_drake.grasping.motion import GraspMotion

FILE_KIND = "catgrasp.category_model"
FILE_VERSION = 1


def check_similarity(R, t, s):
    """``(R, t, s)`` of a similarity checked: a proper 3x3 rotation, a finite translation (m), a scale > 0."""
    R = real_array(R, "R", "3x3 rotation matrix")
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise InputError(f"R: expected a finite 3x3 rotation matrix, got shape {R.shape}")
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
        raise InputError("R: not a proper rotation matrix (R^T R != I or det < 0); orthonormalise it first")
    return R, vector3(t, "t"), positive(s, "s")


def apply_similarity_to_poses(poses: np.ndarray, R, t, s: float = 1.0, anchor=None) -> np.ndarray:
    """Poses (K, 4, 4) of a rigid body moved by the similarity p -> s R p + t of the object.

    The body's ``anchor`` (3,) (in its own frame; default its origin) goes to
    ``s R a + t``, its rotation to ``R @ R_k``; the body itself is not
    scaled (a hand stays a hand), so its origin is placed rigidly about the
    anchor.
    """
    out = np.array(poses, dtype=float, copy=True)
    R, t, s = check_similarity(R, t, s)
    anc = np.zeros(3) if anchor is None else vector3(anchor, "anchor")
    a = out[:, :3, 3] + out[:, :3, :3] @ anc
    out[:, :3, :3] = R @ out[:, :3, :3]
    out[:, :3, 3] = float(s) * a @ R.T + np.asarray(t, float) - out[:, :3, :3] @ anc
    return out


@dataclass(frozen=True, eq=False)
class CategoryModel:
    """Everything needed to transfer a category's grasp to a novel instance."""

    category: str
    space: ShapeSpace
    regressor: Regressor  # latent x (q,) -> canonical descriptor (D,)
    template: GraspMotion  # the canonical motion, canonical object frame
    instances: tuple[str, ...]  # training instances, in the shape space's order
    canonical_instance: str
    params: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    #: The grasp's functional point (m, hand-base frame H): the point of the control poses that is
    #: warped and scaled with the object (None: the frame origin, the paper's plain warp).
    grasp_anchor_H: tuple | None = None
    #: Radius (m) over which the deformation's rotation is averaged for the hand's orientation
    #: (``core.deformation.local_rotations``); None: the field's Jacobian at the anchor (the paper).
    grasp_rotation_radius: float | None = None
    #: The regressor's training set (functional successes mapped to the canonical frame): latent
    #: vectors (n, q), descriptors (n, D) and the index of each row's training instance (n,); optionally
    #: each row's weight within its instance (n,), e.g. its robustness score (None: equal weights).
    training_latent: np.ndarray | None = field(default=None, repr=False)
    training_descriptors: np.ndarray | None = field(default=None, repr=False)
    training_groups: np.ndarray | None = field(default=None, repr=False)
    training_weights: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        if self.template.frame != "object":
            raise InputError("template motion must be in the object frame")
        D = descriptor_size(len(self.template.poses))
        if tuple(self.regressor.shape) != (self.space.q, D):
            raise InputError(f"regressor maps {self.regressor.shape[0]} -> {self.regressor.shape[1]}, "
                             f"expected q={self.space.q} -> D={D}")
        if self.grasp_anchor_H is not None:
            a = np.asarray(self.grasp_anchor_H, float).reshape(-1)
            if a.shape != (3,) or not np.all(np.isfinite(a)):
                raise InputError(f"grasp_anchor_H: expected a finite 3-vector (m), got {self.grasp_anchor_H!r}")
            object.__setattr__(self, "grasp_anchor_H", tuple(float(v) for v in a))
        if self.grasp_rotation_radius is not None and not (float(self.grasp_rotation_radius) > 0):
            raise InputError(f"grasp_rotation_radius: expected > 0 m or None, got {self.grasp_rotation_radius!r}")
        if len(self.instances) != len(self.space.latent_train):
            raise InputError("instances and the shape space's training vectors differ in number")
        training = (self.training_latent, self.training_descriptors, self.training_groups)
        if any(a is not None for a in training):
            if any(a is None for a in training):
                raise InputError("training set: latent vectors, descriptors and groups must be given together")
            L, Dd, g = (np.asarray(a) for a in training)
            n = len(L)
            if (L.shape != (n, self.space.q) or Dd.shape != (n, D) or g.shape != (n,)
                    or not np.all(np.isfinite(L)) or not np.all(np.isfinite(Dd))):
                raise InputError(f"training set: expected latent (n, {self.space.q}), descriptors (n, {D}) and "
                                 f"groups (n,) of finite numbers, got {L.shape}, {Dd.shape}, {g.shape}")
            if self.training_weights is not None:
                w = np.asarray(self.training_weights, float)
                if w.shape != (n,) or not np.all(np.isfinite(w)) or np.any(w < 0):
                    raise InputError(f"training set: expected {n} finite weights >= 0, got shape {w.shape}")
        elif self.training_weights is not None:
            raise InputError("training set: weights given without the training set")

    def refit(self, alpha: float) -> "CategoryModel":
        """The same model with the regressor re-fitted on its stored training set with ridge ``alpha``."""

        if self.training_descriptors is None:
            raise InputError("this model file holds no training set to re-fit (trained by an older version)")
        reg = fit_ridge(self.training_latent, self.training_descriptors, alpha=alpha, groups=self.training_groups,
                        weights=self.training_weights)
        return replace(self, regressor=reg, params=self.params | {"ridge_alpha": float(alpha)})

    def instance_grasps(self, index: int) -> np.ndarray:
        """Rows of the training set (canonical descriptors) that belong to training instance ``index``."""
        if self.training_descriptors is None:
            raise InputError("this model file holds no training set")
        return self.training_descriptors[np.asarray(self.training_groups) == int(index)]

    def instance_descriptor(self, index: int) -> np.ndarray:
        """Training instance ``index``'s grasp knowledge as one canonical descriptor: the mean of its rows,
        weighted by ``training_weights`` when the model has them."""
        rows = self.instance_grasps(index)
        if not len(rows):
            raise InputError(f"training instance {index} has no stored grasp")
        if self.training_weights is None:
            return rows.mean(axis=0)
        w = np.asarray(self.training_weights, float)[np.asarray(self.training_groups) == int(index)]
        return w @ rows / w.sum() if w.sum() > 0 else rows.mean(axis=0)

    def warp_options(self) -> dict:
        """Keyword arguments of ``warp_poses``/``inverse_warp_poses`` for this model's control poses."""
        return {"anchor": self.grasp_anchor_H, "rotation_radius": self.grasp_rotation_radius}

    # ------------------------------------------------------------------ Algorithm 2
    def canonical_motion(self, x) -> GraspMotion:
        """The regressed grasp R(x) in the canonical (undeformed) object frame."""
        return motion_from_descriptor(self.regressor.predict(self.space.check_latent(x)), self.template)

    def warped_motion(self, x) -> GraspMotion:
        """R(x) warped by the deformation W(x): the grasp on the completed shape, canonical frame."""
        m = self.canonical_motion(x)
        poses = warp_poses(self.space.canonical, self.space.decode(x), self.space.beta, m.poses,
                           **self.warp_options())
        return GraspMotion(poses, m.pose_names, dict(m.postures), "object", m.lift_height, m.hold_time)

    def transfer(self, x, R=np.eye(3), t=np.zeros(3), s: float = 1.0, *, frame: str = "world") -> GraspMotion:
        """The grasp for an observed instance: warped by W(x), then moved by p -> s R p + t.

        (R, t, s) is the similarity transform from the canonical frame to the
        observation frame (the latent fit's rigid part); the returned motion
        is in that frame (``frame`` names it, "world" by default).
        """
        R, t, s = check_similarity(R, t, s)
        m = self.warped_motion(x)
        poses = apply_similarity_to_poses(m.poses, R, t, s, anchor=self.grasp_anchor_H)
        return GraspMotion(poses, m.pose_names, dict(m.postures), frame, m.lift_height, m.hold_time)

    # ------------------------------------------------------------------ files
    def save(self, path: str | os.PathLike) -> None:
        shape_arrays, shape_meta = self.space.to_arrays()
        arrays = {f"shape/{k}": v for k, v in shape_arrays.items()}
        reg_arrays, reg_meta = regressor_to_arrays(self.regressor)
        arrays |= {f"regressor/{k}": v for k, v in reg_arrays.items()}
        if self.training_descriptors is not None:
            arrays["training/latent"] = np.asarray(self.training_latent, float)
            arrays["training/descriptors"] = np.asarray(self.training_descriptors, float)
            arrays["training/groups"] = np.asarray(self.training_groups, np.int64)
            if self.training_weights is not None:
                arrays["training/weights"] = np.asarray(self.training_weights, float)
        meta = {
            "category": self.category,
            "shape": shape_meta,
            "regressor": reg_meta,
            "regressor_alpha": float(getattr(self.regressor, "alpha", 0.0)),
            "template": self.template.to_dict(),
            "instances": list(self.instances),
            "canonical_instance": self.canonical_instance,
            "params": self.params,
            "stats": self.stats,
            "grasp_anchor_H": None if self.grasp_anchor_H is None else [float(v) for v in self.grasp_anchor_H],
            "grasp_rotation_radius": self.grasp_rotation_radius,
        }
        save_arrays(path, arrays, kind=FILE_KIND, version=FILE_VERSION, meta=meta)

    @classmethod
    def load(cls, path: str | os.PathLike, *, category: str | None = None) -> "CategoryModel":
        """Read a model file; ModelFileError if corrupt/mismatched, InputError if of another category."""
        arrays, meta = load_arrays(path, kind=FILE_KIND, version=FILE_VERSION)
        if not isinstance(meta, dict):
            raise ModelFileError(f"{path}: category model header is not a JSON object")
        names = (meta.get("category"), meta.get("canonical_instance"))
        if not all(isinstance(n, str) and n for n in names) or not (
                isinstance(meta.get("instances"), list) and all(isinstance(n, str) for n in meta["instances"])):
            raise ModelFileError(f"{path}: category model header lacks its category or instance names")
        try:
            space = ShapeSpace.from_arrays({k[6:]: v for k, v in arrays.items() if k.startswith("shape/")},
                                           meta["shape"], source=str(path))
            alpha = float(meta["regressor_alpha"])  # written by every version; the kind's own header wins
            if not (np.isfinite(alpha) and alpha >= 0):
                raise ModelFileError(f"{path}: the grasp regressor's alpha is not a finite number >= 0")
            reg_meta = meta.get("regressor") or {"kind": "ridge", "alpha": alpha}
            try:
                regressor = regressor_from_arrays(
                    {k[len("regressor/"):]: v for k, v in arrays.items() if k.startswith("regressor/")}, reg_meta)
            except InputError as e:
                raise ModelFileError(f"{path}: the grasp regressor is unreadable ({e})") from None
            if not getattr(regressor, "alpha", 0.0) >= 0:
                raise ModelFileError(f"{path}: the grasp regressor's alpha is negative")
            model = cls(
                category=str(meta["category"]),
                space=space,
                regressor=regressor,
                template=GraspMotion.from_dict(meta["template"]),
                instances=tuple(meta["instances"]),
                canonical_instance=str(meta["canonical_instance"]),
                params=dict(meta.get("params", {})),
                stats=dict(meta.get("stats", {})),
                grasp_anchor_H=(None if meta.get("grasp_anchor_H") is None
                                else tuple(float(v) for v in meta["grasp_anchor_H"])),
                grasp_rotation_radius=(None if meta.get("grasp_rotation_radius") is None
                                       else float(meta["grasp_rotation_radius"])),
                training_latent=arrays.get("training/latent"),
                training_descriptors=arrays.get("training/descriptors"),
                training_groups=arrays.get("training/groups"),
                training_weights=arrays.get("training/weights"),
            )
        except (KeyError, TypeError, ValueError, AttributeError) as e:
            raise ModelFileError(f"{path}: incomplete or inconsistent category model ({e})") from None
        if category is not None and model.category != category:
            raise InputError(f"{path}: is a {model.category!r} model, not {category!r}")
        return model
