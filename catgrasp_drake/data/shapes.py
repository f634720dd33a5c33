"""Solid-modelling helpers for the procedural object categories.

Thin layer over manifold3d (exact, watertight booleans and hulls). All
lengths in metres; all frames are the instance's canonical frame (z up, base
on z = 0, functional direction +y).
"""

from __future__ import annotations

import numpy as np
import trimesh
from manifold3d import CrossSection, Manifold

#: Circle resolution for large round parts and for small ones (fillets, nozzles).
SEGMENTS = 40
SMALL_SEGMENTS = 16


def _affine(R: np.ndarray, p) -> list[list[float]]:
    """3x4 affine matrix [R | p] as manifold3d expects."""
    M = np.hstack([np.asarray(R, float), np.asarray(p, float).reshape(3, 1)])
    return M.tolist()


def rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def sphere(center, radius: float, segments: int = SMALL_SEGMENTS) -> Manifold:
    return Manifold.sphere(radius, segments).translate(tuple(map(float, center)))


def ellipsoid(center, radii, segments: int = SEGMENTS) -> Manifold:
    return Manifold.sphere(1.0, segments).scale(tuple(map(float, radii))).translate(tuple(map(float, center)))


def capsule(p0, p1, radius: float, segments: int = SMALL_SEGMENTS) -> Manifold:
    """Capsule (hull of two spheres) between points ``p0`` and ``p1``."""
    return Manifold.batch_hull([sphere(p0, radius, segments), sphere(p1, radius, segments)])


def rounded_box(center, size, radius: float, segments: int = SMALL_SEGMENTS) -> Manifold:
    """Axis-aligned box of full ``size`` (x, y, z) with edges rounded by ``radius``."""
    size = np.asarray(size, float)
    radius = float(min(radius, 0.49 * size.min()))
    half = size / 2.0 - radius
    corners = [
        sphere(np.asarray(center, float) + half * np.array([sx, sy, sz]), radius, segments)
        for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)
    ]
    return Manifold.batch_hull(corners)


def elliptic_slab(center, rx: float, ry: float, thickness: float, segments: int = SEGMENTS) -> Manifold:
    """Thin elliptic cylinder with axis along z, centred at ``center``."""
    c = Manifold.cylinder(thickness, 1.0, 1.0, segments, True).scale((rx, ry, 1.0))
    return c.translate(tuple(map(float, center)))


def cylinder_y(y0: float, y1: float, radius0: float, radius1: float, x: float, z: float,
               segments: int = SEGMENTS) -> Manifold:
    """(Tapered) cylinder with axis along +y from ``y0`` to ``y1`` through (x, ., z)."""
    c = Manifold.cylinder(y1 - y0, radius0, radius1, segments, False)  # along +z from 0
    return c.transform(_affine(rot_x(-np.pi / 2), (x, y0, z)))  # +z -> +y


def partial_torus_yz(center, ring_radius: float, tube_rx: float, tube_ry: float,
                     degrees: float, start_deg: float, segments: int = SEGMENTS) -> Manifold:
    """Arc of a torus lying in the y-z plane (a mug handle), opening toward -y.

    The arc runs from ``start_deg`` over ``degrees`` measured from +z toward +y.
    The tube cross-section is an ellipse (``tube_rx`` across x, ``tube_ry`` in plane).
    """
    cs = CrossSection.circle(1.0, SMALL_SEGMENTS).scale((tube_ry, tube_rx)).translate((ring_radius, 0.0))
    arc = Manifold.revolve(cs, segments, degrees)  # revolve about z, arc in x-y from +x
    arc = arc.rotate((0.0, 0.0, float(start_deg)))
    # map the x-y plane of the arc to the z-y plane: x -> z, y -> y, z -> x
    M = np.array([[0, 0, 1], [0, 1, 0], [1, 0, 0]], float)
    return arc.transform(_affine(M, center))


def to_trimesh(solid: Manifold) -> trimesh.Trimesh:
    """Convert a manifold solid into a watertight trimesh with merged vertices."""
    m = solid.to_mesh()
    verts = np.asarray(m.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(m.tri_verts, dtype=np.int64)
    mesh = trimesh.Trimesh(vertices=verts, faces=faces, process=True)
    return mesh
