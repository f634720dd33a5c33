"""Clearance of a rigid point set (a preshaped hand) from an object known by its surface points.

The object is known only by points on its surface (a sampled mesh, or a
shape completed from one depth view). :class:`SignedDistanceGrid` turns them
into a solid on a voxel grid -- the surface voxels closed over the points'
spacing, the cavities that do not reach the grid's border filled -- and
stores the signed distance to that solid's boundary (metres, POSITIVE
INSIDE: a penetration depth). :func:`clearance_shift` finds the smallest
translation that brings every point of a rigid set (e.g. the hand's
collision geometry at a grasp pose) to at most ``tolerance`` inside.

All points are (N, 3) arrays in one frame (the caller's, e.g. W), metres.
numpy and scipy only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage, optimize
from scipy.spatial import cKDTree

from catgrasp_drake.core.validation import as_points, non_negative, positive, real_number


@dataclass(frozen=True)
class SignedDistanceGrid:
    """Signed distance (m, positive inside) to a solid, sampled at voxel centres.

    ``values[i, j, k]`` is the signed distance at ``origin + voxel * (i, j, k)``;
    ``gradient`` (3, *values.shape) its spatial gradient (unit-free, ~ the
    outward-to-inward direction: it points INTO the solid). Outside the grid
    the distance is clamped to the border's (the grid is padded so the border
    is outside the solid).
    """

    origin: np.ndarray
    voxel: float
    values: np.ndarray
    gradient: np.ndarray

    @classmethod
    def from_surface_points(cls, points, voxel: float = 0.003, closing: float | None = None,
                            padding: float = 0.03) -> "SignedDistanceGrid":
        """The solid bounded by surface ``points`` (N, 3), on a grid of ``voxel`` (m).

        ``closing`` (m): gaps in the surface up to about twice this wide are
        closed before the inside is filled (default: twice the 95th percentile
        of the points' nearest-neighbour spacing -- randomly sampled surfaces
        leave holes about that wide -- at least one voxel). Openings narrower
        than about twice ``closing`` (a mug handle's loop, sampled too
        sparsely) are closed too: sample densely. ``padding`` (m) of free
        space is kept around the points.
        """
        p = as_points(points, "surface points", min_points=4, check_units=True)
        voxel = positive(voxel, "voxel")
        if closing is None:
            d, _ = cKDTree(p).query(p, k=2)
            closing = max(voxel, 2.0 * float(np.percentile(d[:, 1], 95)))
        steps = int(np.ceil(closing / voxel))
        origin = p.min(axis=0) - padding - steps * voxel
        shape = np.ceil((p.max(axis=0) + padding + steps * voxel - origin) / voxel).astype(int) + 1
        idx = np.clip(np.rint((p - origin) / voxel).astype(int), 0, shape - 1)
        shell = np.zeros(shape, bool)
        shell[idx[:, 0], idx[:, 1], idx[:, 2]] = True
        # a closing by a ball of ``steps`` voxels (Euclidean, through distance transforms), with the cavities
        # filled between its dilation and its erosion
        closed = ndimage.distance_transform_edt(~shell) <= steps
        filled = ndimage.binary_fill_holes(closed)
        solid = (ndimage.distance_transform_edt(filled) > steps) | shell
        # voxel-centre distances to the other class, less half a voxel (the boundary lies between the two), less
        # another half voxel: the surface voxels are solid, which puts the boundary half a voxel outside the points
        inside = (ndimage.distance_transform_edt(solid) - 1.0) * voxel
        outside = ndimage.distance_transform_edt(~solid) * voxel
        values = np.where(solid, inside, -outside)
        gradient = np.stack(np.gradient(values, voxel))
        return cls(origin, float(voxel), values, gradient)

    def _coords(self, points: np.ndarray) -> np.ndarray:
        return ((np.asarray(points, float) - self.origin) / self.voxel).T

    def __call__(self, points) -> np.ndarray:
        """Signed distance (m, positive inside) at ``points`` (N, 3), trilinear."""
        return ndimage.map_coordinates(self.values, self._coords(points), order=1, mode="nearest")

    def gradient_at(self, points) -> np.ndarray:
        """(N, 3) gradient of the signed distance at ``points`` (points into the solid)."""
        c = self._coords(points)
        return np.stack([ndimage.map_coordinates(g, c, order=1, mode="nearest") for g in self.gradient], axis=1)


@dataclass(frozen=True)
class ClearanceShift:
    """The result of :func:`clearance_shift`.

    ``shift`` (3,): the translation found (m); ``depth_before``/``depth_after``:
    the deepest point's penetration (m) before and after it; ``ok``: the
    shifted set is within the tolerance and the shift within ``max_shift``.
    """

    shift: np.ndarray
    depth_before: float
    depth_after: float
    ok: bool


def clearance_shift(points, field: SignedDistanceGrid, tolerance: float, max_shift: float,
                    rounds: int = 4, max_active: int = 300) -> ClearanceShift:
    """The smallest translation ``t`` with ``field(points + t) <= tolerance`` everywhere, if ``|t| <= max_shift``.

    ``points`` (N, 3) move rigidly. Each round linearises the signed distance
    of the points within 1 cm of the tolerance (at most ``max_active``, the
    deepest) and solves ``min |t|^2`` under those constraints (SLSQP); the
    active set is re-read at the new ``t``. A set already within the
    tolerance gets ``t = 0``, unchanged.
    """
    p = as_points(points, "points")
    tolerance, max_shift = real_number(tolerance, "tolerance"), non_negative(max_shift, "max_shift")
    depth0 = float(field(p).max())
    t = np.zeros(3)
    if depth0 <= tolerance:
        return ClearanceShift(t, depth0, depth0, True)
    for _ in range(rounds):
        sd = field(p + t)
        if sd.max() <= tolerance:
            break
        active = np.flatnonzero(sd > tolerance - 0.01)
        active = active[np.argsort(-sd[active])[:max_active]]
        q = p[active] + t
        g = field.gradient_at(q)
        base = sd[active]

        t = t + _least_step(t, base, g, tolerance)
    depth = float(field(p + t).max())
    ok = depth <= tolerance + 0.5e-3 and float(np.linalg.norm(t)) <= max_shift
    return ClearanceShift(t, depth0, depth, ok)


def _least_step(t: np.ndarray, depth: np.ndarray, gradient: np.ndarray, tolerance: float) -> np.ndarray:
    """The step ``dt`` minimising ``|t + dt|^2`` with ``depth + gradient @ dt <= tolerance`` (SLSQP)."""
    res = optimize.minimize(lambda dt: float(np.sum((t + dt) ** 2)), np.zeros(3), jac=lambda dt: 2.0 * (t + dt),
                            method="SLSQP", options={"maxiter": 100, "ftol": 1e-12},
                            constraints=[{"type": "ineq", "fun": lambda dt: tolerance - (depth + gradient @ dt),
                                          "jac": lambda dt: -gradient}])
    return res.x
