"""Meshcat helpers: Drake's built-in ``pydrake.geometry.Meshcat``, bound to localhost.

Point clouds, pose triads and self-contained HTML export. Paths in the
Meshcat tree group what a user toggles together (e.g. ``/catgrasp/observed``).
"""

from __future__ import annotations

import os

import numpy as np
from pydrake.geometry import Cylinder, Meshcat, MeshcatParams, Rgba
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.perception import BaseField, Fields, PointCloud

from catgrasp_drake.core.fileio import atomic_write_text
from catgrasp_drake.core.validation import as_points

#: Colours used consistently across the project's Meshcat scenes.
COLORS = {
    "observed": Rgba(0.1, 0.4, 0.95, 1.0),
    "completed": Rgba(0.1, 0.75, 0.2, 1.0),
    "canonical": Rgba(0.9, 0.2, 0.2, 1.0),
}


def start_meshcat() -> Meshcat:
    """A Meshcat server on localhost only, on a free port."""
    return Meshcat(MeshcatParams(host="localhost", port=0))


def draw_cloud(meshcat: Meshcat, path: str, points_W, rgba: Rgba, point_size: float = 0.004) -> None:
    """Show an ``(N, 3)`` cloud (world frame, metres) at ``path``."""
    points_W = as_points(points_W, "points_W")
    cloud = PointCloud(len(points_W), Fields(BaseField.kXYZs))
    cloud.mutable_xyzs()[:] = points_W.T
    meshcat.SetObject(path, cloud, point_size, rgba)


def draw_triad(meshcat: Meshcat, path: str, X_WF, length: float = 0.05, radius: float = 0.002,
               opacity: float = 1.0) -> None:
    """Show frame F (4x4 array or RigidTransform, world frame) as red/green/blue axes."""
    X = X_WF if isinstance(X_WF, RigidTransform) else RigidTransform(np.asarray(X_WF, float))
    meshcat.SetTransform(path, X)
    for name, axis, color in (("x", 0, Rgba(1, 0, 0, opacity)), ("y", 1, Rgba(0, 1, 0, opacity)),
                              ("z", 2, Rgba(0, 0, 1, opacity))):
        offset = np.zeros(3)
        offset[axis] = length / 2
        R = {0: RotationMatrix.MakeYRotation(np.pi / 2), 1: RotationMatrix.MakeXRotation(np.pi / 2),
             2: RotationMatrix()}[axis]
        meshcat.SetTransform(f"{path}/{name}", RigidTransform(R, offset))
        meshcat.SetObject(f"{path}/{name}", Cylinder(radius, length), color)


def save_static_html(meshcat: Meshcat, path: str | os.PathLike) -> None:
    """Write the current scene (and any published recording) as one self-contained HTML file."""
    atomic_write_text(path, meshcat.StaticHtml())
