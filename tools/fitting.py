"""Fitting collision primitives (capsules, boxes, cylinders) to link meshes.

Pure numpy/scipy. Every fit returns a small record of the primitive's pose in
the link frame ``B`` and its dimensions; the enclosing fits cover every given
vertex (up to floating point).

- :func:`fit_capsule`: for each principal axis of the solid convex hull, the
  minimal enclosing circle of the vertices projected on the plane normal to
  that axis gives the radius and the axis position; the segment is then the
  shortest one whose hemispherical caps still cover every vertex. The axis
  giving the smallest capsule volume wins.
- :func:`fit_box`: the bounding box aligned with given axes (default: the link
  frame's).
- :func:`fit_cylinder`: minimal enclosing circle about a given axis and the
  axial extent.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError


@dataclass(frozen=True)
class CapsuleFit:
    """A capsule: centre ``p_BC``, unit axis ``axis_B``, radius and cylinder length (cap centres 2·half apart)."""

    p_BC: np.ndarray
    axis_B: np.ndarray
    radius: float
    length: float

    @property
    def volume(self) -> float:
        return float(np.pi * self.radius**2 * self.length + 4.0 / 3.0 * np.pi * self.radius**3)


@dataclass(frozen=True)
class BoxFit:
    """A box: centre ``p_BC``, orientation ``R_BC`` (columns = box axes in B) and full edge lengths ``size``."""

    p_BC: np.ndarray
    R_BC: np.ndarray
    size: np.ndarray

    @property
    def volume(self) -> float:
        return float(np.prod(self.size))


@dataclass(frozen=True)
class CylinderFit:
    """A cylinder: centre ``p_BC``, unit axis ``axis_B``, radius and length."""

    p_BC: np.ndarray
    axis_B: np.ndarray
    radius: float
    length: float

    @property
    def volume(self) -> float:
        return float(np.pi * self.radius**2 * self.length)


def _check_points(points: np.ndarray, dim: int) -> np.ndarray:
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != dim or len(p) < 2:
        raise ValueError(f"expected an (N, {dim}) array with N >= 2, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("points contain NaN or inf")
    return p


def min_enclosing_circle(points_2d: np.ndarray) -> tuple[np.ndarray, float]:
    """Exact smallest circle containing all 2-D points: (centre, radius).

    The circle is determined by two or three points of the convex hull; the
    circles through all pairs (as diameter) and triples (circumcircle) of hull
    vertices are computed at once and the smallest one containing every point
    wins.
    """
    p = _check_points(points_2d, 2)
    try:
        hull = p[ConvexHull(p).vertices]
    except QhullError:  # collinear / degenerate input
        hull = np.unique(p, axis=0)
    n = len(hull)
    centres, radii = [], []
    i, j = np.triu_indices(n, 1)
    centres.append(0.5 * (hull[i] + hull[j]))
    radii.append(0.5 * np.linalg.norm(hull[i] - hull[j], axis=1))
    if n >= 3:
        ijk = np.array(list(itertools.combinations(range(n), 3)))
        a, b, c = hull[ijk[:, 0]], hull[ijk[:, 1]], hull[ijk[:, 2]]
        d = 2.0 * (a[:, 0] * (b[:, 1] - c[:, 1]) + b[:, 0] * (c[:, 1] - a[:, 1]) + c[:, 0] * (a[:, 1] - b[:, 1]))
        ok = np.abs(d) > 1e-18
        a, b, c, d = a[ok], b[ok], c[ok], d[ok]
        a2, b2, c2 = (a * a).sum(1), (b * b).sum(1), (c * c).sum(1)
        ux = (a2 * (b[:, 1] - c[:, 1]) + b2 * (c[:, 1] - a[:, 1]) + c2 * (a[:, 1] - b[:, 1])) / d
        uy = (a2 * (c[:, 0] - b[:, 0]) + b2 * (a[:, 0] - c[:, 0]) + c2 * (b[:, 0] - a[:, 0])) / d
        cc = np.column_stack([ux, uy])
        centres.append(cc)
        radii.append(np.linalg.norm(a - cc, axis=1))
    centres = np.concatenate(centres)
    radii = np.concatenate(radii)
    for k in np.argsort(radii, kind="stable"):
        r = radii[k]
        if np.all(np.linalg.norm(hull - centres[k], axis=1) <= r * (1.0 + 1e-9) + 1e-12):
            return centres[k], float(r)
    raise ValueError("no enclosing circle found")  # pragma: no cover - impossible for distinct points


def orthonormal_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(a, helper)
    u /= np.linalg.norm(u)
    v = np.cross(a, u)
    return u, v


def principal_axes(points: np.ndarray) -> np.ndarray:
    """Principal axes (columns, longest extent first) of the solid convex hull of ``points``.

    Uses the hull's volume-weighted second moments (tetrahedra fan), so dense
    mesh regions do not bias the axes the way a vertex PCA would.
    """
    p = _check_points(points, 3)
    hull = ConvexHull(p)
    ref = p[hull.vertices].mean(axis=0)
    vol_total = 0.0
    first = np.zeros(3)
    second = np.zeros((3, 3))
    for simplex in hull.simplices:
        a, b, c = p[simplex] - ref
        v = abs(np.dot(a, np.cross(b, c))) / 6.0
        if v == 0.0:
            continue
        # Second moment of a tetrahedron with one vertex at the origin.
        s = a + b + c
        second += v / 20.0 * (np.outer(a, a) + np.outer(b, b) + np.outer(c, c) + np.outer(s, s))
        first += v * s / 4.0
        vol_total += v
    com = first / vol_total
    cov = second / vol_total - np.outer(com, com)
    w, vecs = np.linalg.eigh(cov)
    order = np.argsort(w)[::-1]
    axes = vecs[:, order]
    # Deterministic signs: make the largest component of each axis positive.
    for k in range(3):
        if axes[np.argmax(np.abs(axes[:, k])), k] < 0:
            axes[:, k] *= -1
    return axes


def fit_capsule_about_axis(points: np.ndarray, axis: np.ndarray) -> CapsuleFit:
    """Smallest capsule with the given axis direction containing all points."""
    p = _check_points(points, 3)
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    u, v = orthonormal_basis(a)
    q2 = np.column_stack([p @ u, p @ v])
    c2, radius = min_enclosing_circle(q2)
    t = p @ a
    r = np.linalg.norm(q2 - c2, axis=1)
    slack = np.sqrt(np.maximum(radius**2 - r**2, 0.0))
    t_hi = float(np.max(t - slack))  # upper cap centre
    t_lo = float(np.min(t + slack))  # lower cap centre
    if t_hi < t_lo:  # a sphere suffices; put it mid-way
        t_lo = t_hi = 0.5 * (t_lo + t_hi)
    centre = c2[0] * u + c2[1] * v + 0.5 * (t_lo + t_hi) * a
    return CapsuleFit(p_BC=centre, axis_B=a, radius=radius, length=t_hi - t_lo)


def fit_capsule(points: np.ndarray) -> CapsuleFit:
    """Minimal-volume capsule over the three principal axes of the points' convex hull."""
    axes = principal_axes(points)
    fits = [fit_capsule_about_axis(points, axes[:, k]) for k in range(3)]
    return min(fits, key=lambda f: f.volume)


def fit_box(points: np.ndarray, R_BC: np.ndarray | None = None) -> BoxFit:
    """Bounding box of ``points`` aligned with the columns of ``R_BC`` (default: identity)."""
    p = _check_points(points, 3)
    R = np.eye(3) if R_BC is None else np.asarray(R_BC, float)
    q = p @ R
    lo, hi = q.min(axis=0), q.max(axis=0)
    return BoxFit(p_BC=R @ (0.5 * (lo + hi)), R_BC=R, size=hi - lo)


def fit_cylinder(points: np.ndarray, axis: np.ndarray) -> CylinderFit:
    """Smallest cylinder with the given axis direction containing all points."""
    p = _check_points(points, 3)
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    u, v = orthonormal_basis(a)
    c2, radius = min_enclosing_circle(np.column_stack([p @ u, p @ v]))
    t = p @ a
    centre = c2[0] * u + c2[1] * v + 0.5 * (t.min() + t.max()) * a
    return CylinderFit(p_BC=centre, axis_B=a, radius=radius, length=float(t.max() - t.min()))


def fit_boxes_along_axis(
    points: np.ndarray, axis: int = 2, max_boxes: int = 3, min_gain: float = 0.15, n_candidates: int = 40
) -> list[BoxFit]:
    """Cover ``points`` by up to ``max_boxes`` axis-aligned boxes stacked along coordinate ``axis``.

    Split heights are searched on a grid of ``n_candidates`` levels; each box
    is the bounding box of the points in its slab, extended along ``axis`` to
    the slab's limits so the stack has no gaps. More boxes are used only when
    they reduce the total volume by at least ``min_gain`` (fraction) each.
    """
    p = _check_points(points, 3)
    if not 0 <= axis <= 2 or max_boxes < 1:
        raise ValueError("axis must be 0, 1 or 2 and max_boxes >= 1")
    t = p[:, axis]
    lo, hi = float(t.min()), float(t.max())
    grid = np.linspace(lo, hi, n_candidates + 2)[1:-1]

    def boxes_for(cuts: tuple[float, ...]) -> list[BoxFit] | None:
        edges = (lo,) + cuts + (hi,)
        out = []
        for a, b in zip(edges[:-1], edges[1:]):
            sel = p[(t >= a) & (t <= b)]
            if len(sel) < 2:
                return None
            bmin, bmax = sel.min(axis=0), sel.max(axis=0)
            bmin[axis], bmax[axis] = a, b
            out.append(BoxFit(p_BC=0.5 * (bmin + bmax), R_BC=np.eye(3), size=bmax - bmin))
        return out

    best = boxes_for(())
    best_volume = sum(b.volume for b in best)
    for n_cuts in range(1, max_boxes):
        candidate, candidate_volume = None, np.inf
        for cuts in itertools.combinations(grid, n_cuts):
            boxes = boxes_for(tuple(float(c) for c in cuts))
            if boxes is None:
                continue
            v = sum(b.volume for b in boxes)
            if v < candidate_volume:
                candidate, candidate_volume = boxes, v
        if candidate is None or candidate_volume > (1.0 - min_gain) * best_volume:
            break
        best, best_volume = candidate, candidate_volume
    return best
