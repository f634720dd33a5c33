"""Hidden-point removal (Katz, Tal & Basri, "Direct visibility of point sets", SIGGRAPH 2007).

With the camera at the origin, every point ``p`` is "spherically flipped" to
``p + 2 (R - |p|) p / |p|`` (inversion in a sphere of radius ``R`` enclosing
the cloud); a point is visible iff its flipped image is a vertex of the convex
hull of the flipped cloud plus the camera. ``R = radius_factor * max |p|``:
a larger factor marks more points visible (Katz's ``R = max|p| 10^gamma``;
Open3D's examples use ``100 x`` the diameter). The default 100 suits the
~500-point real drills seen from 0.6 m (see tests).

Uses scipy.spatial.ConvexHull (Qhull; deterministic).

Camera placement lives here too (the one home of both): :func:`camera_on_sphere_position`
(a camera at a distance, azimuth and elevation about a point) and :func:`look_at_matrix`
(the pose X_WC of a Drake camera at an eye looking at a target).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from catgrasp_drake.core.validation import as_points, positive, real_number, vector3
from catgrasp_drake.errors import InputError

DEFAULT_RADIUS_FACTOR = 100.0
#: Largest accepted radius factor (beyond, the flipped points differ by less than float64 resolves).
MAX_RADIUS_FACTOR = 1e9


def hidden_point_removal(points, camera_position, *, radius_factor: float = DEFAULT_RADIUS_FACTOR) -> np.ndarray:
    """Boolean mask (N,) of the points of ``points`` (N, 3) visible from ``camera_position`` (3,).

    Points at the camera position count as visible. Fewer than 4 points, or a
    degenerate (flat) cloud that Qhull cannot hull even when joggled, are all
    reported visible.
    """
    P = as_points(points, "points", min_points=1)
    cam = vector3(camera_position, "camera_position")
    radius_factor = positive(radius_factor, "radius_factor")
    if not 1.0 < radius_factor <= MAX_RADIUS_FACTOR:
        raise InputError(f"radius_factor: must be in (1, {MAX_RADIUS_FACTOR:g}] (the sphere must enclose the cloud; "
                         f"larger loses all precision), got {radius_factor}")
    q = P - cam
    norms = np.linalg.norm(q, axis=1)
    at_cam = norms <= 1e-12
    visible = np.zeros(len(P), dtype=bool)
    visible[at_cam] = True
    idx = np.flatnonzero(~at_cam)
    if len(idx) < 4:
        visible[idx] = True
        return visible
    qn = q[idx]
    nn = norms[idx][:, None]
    R = radius_factor * float(nn.max())
    flipped = qn + 2.0 * (R - nn) * qn / nn
    pts = np.vstack([flipped, np.zeros((1, 3))])
    hull = None
    for opts in (None, "QJ"):
        try:
            hull = ConvexHull(pts, qhull_options=opts)
            break
        except (QhullError, ValueError):
            continue
    if hull is None:
        visible[idx] = True
        return visible
    v = hull.vertices[hull.vertices < len(idx)]
    visible[idx[v]] = True
    return visible


def camera_on_sphere_position(center, distance: float, azimuth: float, elevation: float) -> np.ndarray:
    """Camera position ``distance`` m from ``center`` at ``azimuth`` (about +z, from +x) and ``elevation`` (rad)."""
    c = vector3(center, "center")
    d = positive(distance, "distance")
    azimuth, elevation = real_number(azimuth, "azimuth"), real_number(elevation, "elevation")
    return c + d * np.array([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                             np.sin(elevation)])


def look_at_matrix(eye, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """X_WC (4x4) of a Drake camera (z forward, x right, y down) at ``eye`` looking at ``target``."""
    eye, target, up = (np.asarray(v, float) for v in (eye, target, up))
    z = target - eye
    n = np.linalg.norm(z)
    if n < 1e-9:
        raise InputError("camera look_at: eye and target coincide")
    z /= n
    x = np.cross(z, up)
    if np.linalg.norm(x) < 1e-9:
        x = np.cross(z, np.array([0.0, 1.0, 0.0]))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    X = np.eye(4)
    X[:3, :3] = np.column_stack([x, y, z])
    X[:3, 3] = eye
    return X
