"""A trained category model: shape space + grasp regressor + canonical motion (paper, Alg. 1 output).

``CategoryModel.transfer(x, R, t, s)`` is Algorithm 2 lines 2-3: predict the
canonical descriptor R(x), warp its control poses with the dense deformation
field W(x) (positions and rotation bases, re-orthonormalised), then apply the
similarity transform of the fit (rotation R, translation t, scale s) into the
observation frame.

File format (one ``.npz``, atomic, checksummed, no pickle): the shape space's
arrays under ``shape/``, the regressor under ``regressor/``, and a JSON header
with the canonical motion (template), the parameters and the training
statistics. Kind ``catgrasp.category_model``, version 1.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from catgrasp_drake.core.deformation import warp_poses
from catgrasp_drake.core.fileio import load_arrays, save_arrays
from catgrasp_drake.core.regression import LinearRegressor
from catgrasp_drake.core.shape_space import ShapeSpace
from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.grasping.descriptor import descriptor_size, motion_from_descriptor
from catgrasp_drake.grasping.motion import GraspMotion

FILE_KIND = "catgrasp.category_model"
FILE_VERSION = 1


def similarity_matrix(R, t, s: float = 1.0) -> np.ndarray:
    """4x4 matrix of p -> s R p + t."""
    S = np.eye(4)
    S[:3, :3] = float(s) * np.asarray(R, float)
    S[:3, 3] = np.asarray(t, float)
    return S


def apply_similarity_to_poses(poses: np.ndarray, R, t, s: float = 1.0) -> np.ndarray:
    """Poses (K, 4, 4) moved by p -> s R p + t; rotations become R @ R_k (scale does not rotate)."""
    out = np.array(poses, dtype=float, copy=True)
    R = np.asarray(R, float)
    out[:, :3, :3] = R @ out[:, :3, :3]
    out[:, :3, 3] = float(s) * out[:, :3, 3] @ R.T + np.asarray(t, float)
    return out


@dataclass(frozen=True, eq=False)
class CategoryModel:
    """Everything needed to transfer a category's grasp to a novel instance."""

    category: str
    space: ShapeSpace
    regressor: LinearRegressor
    template: GraspMotion  # the canonical motion, canonical object frame
    instances: tuple[str, ...]  # training instances, in the shape space's order
    canonical_instance: str
    params: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.template.frame != "object":
            raise InputError("template motion must be in the object frame")
        D = descriptor_size(len(self.template.poses))
        if self.regressor.coef.shape != (D, self.space.q):
            raise InputError(f"regressor maps {self.regressor.coef.shape[1]} -> {self.regressor.coef.shape[0]}, "
                             f"expected q={self.space.q} -> D={D}")
        if len(self.instances) != len(self.space.latent_train):
            raise InputError("instances and the shape space's training vectors differ in number")

    # ------------------------------------------------------------------ Algorithm 2
    def canonical_motion(self, x) -> GraspMotion:
        """The regressed grasp R(x) in the canonical (undeformed) object frame."""
        return motion_from_descriptor(self.regressor.predict(self.space.check_latent(x)), self.template)

    def warped_motion(self, x) -> GraspMotion:
        """R(x) warped by the deformation W(x): the grasp on the completed shape, canonical frame."""
        m = self.canonical_motion(x)
        poses = warp_poses(self.space.canonical, self.space.decode(x), self.space.beta, m.poses)
        return GraspMotion(poses, m.pose_names, dict(m.postures), "object", m.lift_height, m.hold_time)

    def transfer(self, x, R=np.eye(3), t=np.zeros(3), s: float = 1.0, *, frame: str = "world") -> GraspMotion:
        """The grasp for an observed instance: warped by W(x), then moved by p -> s R p + t.

        (R, t, s) is the similarity transform from the canonical frame to the
        observation frame (the latent fit's rigid part); the returned motion
        is in that frame (``frame`` names it, "world" by default).
        """
        m = self.warped_motion(x)
        poses = apply_similarity_to_poses(m.poses, R, t, s)
        return GraspMotion(poses, m.pose_names, dict(m.postures), frame, m.lift_height, m.hold_time)

    # ------------------------------------------------------------------ files
    def save(self, path: str | os.PathLike) -> None:
        shape_arrays, shape_meta = self.space.to_arrays()
        arrays = {f"shape/{k}": v for k, v in shape_arrays.items()}
        arrays["regressor/coef"] = self.regressor.coef
        arrays["regressor/intercept"] = self.regressor.intercept
        meta = {
            "category": self.category,
            "shape": shape_meta,
            "regressor_alpha": self.regressor.alpha,
            "template": self.template.to_dict(),
            "instances": list(self.instances),
            "canonical_instance": self.canonical_instance,
            "params": self.params,
            "stats": self.stats,
        }
        save_arrays(path, arrays, kind=FILE_KIND, version=FILE_VERSION, meta=meta)

    @classmethod
    def load(cls, path: str | os.PathLike, *, category: str | None = None) -> "CategoryModel":
        """Read a model file; ModelFileError if corrupt/mismatched, InputError if of another category."""
        arrays, meta = load_arrays(path, kind=FILE_KIND, version=FILE_VERSION)
        try:
            space = ShapeSpace.from_arrays({k[6:]: v for k, v in arrays.items() if k.startswith("shape/")},
                                           meta["shape"], source=str(path))
            regressor = LinearRegressor(arrays["regressor/coef"], arrays["regressor/intercept"],
                                        float(meta["regressor_alpha"]))
            model = cls(
                category=str(meta["category"]),
                space=space,
                regressor=regressor,
                template=GraspMotion.from_dict(meta["template"]),
                instances=tuple(meta["instances"]),
                canonical_instance=str(meta["canonical_instance"]),
                params=dict(meta.get("params", {})),
                stats=dict(meta.get("stats", {})),
            )
        except (KeyError, TypeError, ValueError) as e:
            raise ModelFileError(f"{path}: incomplete or inconsistent category model ({e})") from None
        if category is not None and model.category != category:
            raise InputError(f"{path}: is a {model.category!r} model, not {category!r}")
        return model
