"""Mesh reading with clear errors, and the mesh helpers shared by the importers (scan debris, closed solids)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import trimesh

from catgrasp_drake.core.validation import MAX_OBJECT_EXTENT_M
from catgrasp_drake.errors import InputError, ModelFileError, one_line

#: Scan debris: connected pieces with fewer faces than this are dropped from an imported mesh
#: (the YCB STLs carry a few isolated 2-triangle slivers).
MIN_PIECE_FACES = 10
#: A hole filling that adds more than this fraction of the mesh's area is not a repair but a guess.
MAX_REPAIR_AREA_FRACTION = 0.10


def read_mesh(path: str | os.PathLike, *, require_watertight: bool = False,
              check_units: bool = True) -> trimesh.Trimesh:
    """Read a triangle mesh (.obj/.stl/.ply/...) in metres as one ``trimesh.Trimesh``.

    Raises ModelFileError if the file is missing, unreadable or has no
    triangles, and InputError if it is not watertight (when required) or looks
    like millimetres (``check_units``: its bounding-box diagonal exceeds
    ``MAX_OBJECT_EXTENT_M``).
    """
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"path: expected a mesh file name, got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise ModelFileError(f"{path}: mesh file not found")
    try:
        mesh = trimesh.load(str(path), force="mesh", process=True)
    except Exception as e:  # trimesh raises many types for corrupt files
        raise ModelFileError(f"{path}: unreadable mesh ({one_line(e, limit=120)})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ModelFileError(f"{path}: the file holds no triangles")
    if not np.all(np.isfinite(mesh.vertices)):
        raise ModelFileError(f"{path}: mesh has NaN or inf vertices")
    extent = float(np.linalg.norm(mesh.extents))
    if check_units and extent > MAX_OBJECT_EXTENT_M:
        raise InputError(f"{path}: mesh spans {extent:.3g} units; expected metres. "
                         "Is it in millimetres? Scale by 0.001.")
    if require_watertight and not mesh.is_watertight:
        raise InputError(f"{path}: mesh is not watertight (has holes); repair it or use a closed mesh")
    return mesh


def drop_debris(mesh: trimesh.Trimesh, min_faces: int = MIN_PIECE_FACES) -> trimesh.Trimesh:
    """``mesh`` without its connected pieces of fewer than ``min_faces`` faces (scan slivers); as is if none."""
    parts = mesh.split(only_watertight=False, repair=False)
    keep = [p for p in parts if len(p.faces) >= min_faces]
    if len(keep) == len(parts) or not keep:
        return mesh
    return trimesh.util.concatenate(keep)


def _closed(m: trimesh.Trimesh) -> bool:
    return bool(m.is_watertight and m.is_winding_consistent and m.volume > 0)


def _filled_by_open3d(m: trimesh.Trimesh) -> trimesh.Trimesh | None:
    """``m`` with its boundary loops closed by open3d's hole filling (VTK's filter), outward winding; or None."""
    # deferred: open3d is a heavy import, needed only for meshes with holes
    from catgrasp_drake.data.open3d_import import import_open3d

    o3d = import_open3d()
    t = o3d.t.geometry.TriangleMesh(o3d.core.Tensor(np.asarray(m.vertices, np.float64)),
                                    o3d.core.Tensor(np.asarray(m.faces, np.int64)))
    try:
        filled = t.fill_holes(hole_size=1e9)
    except RuntimeError:
        return None
    r = trimesh.Trimesh(vertices=filled.vertex.positions.numpy(), faces=filled.triangle.indices.numpy(),
                        process=True)
    if len(r.faces) == 0:
        return None
    trimesh.repair.fix_normals(r, multibody=True)
    return r


def watertight_for_mass(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, str]:
    """A closed version of ``mesh`` for volume and inertia, and how it was made.

    1. the mesh itself if every piece is closed with consistent outward winding
       (``"mesh"``); 2. else a repaired copy (``"repaired"``): trimesh's hole
       filling (triangle and quad holes) and normal fixing, then, if still
       open, open3d's hole filling (any boundary loop), accepted only if the
       result is closed, outward and adds at most
       :data:`MAX_REPAIR_AREA_FRACTION` of the area (a repair closes holes;
       it does not invent a missing side); 3. else the convex hull
       (``"convex_hull"``, an over-estimate of the volume: fit for the
       inertia of a body whose mass is known, not for a mass estimate).
    """
    m = trimesh.Trimesh(vertices=np.round(mesh.vertices, 6), faces=mesh.faces, process=True)
    if _closed(m):
        return m, "mesh"
    r = m.copy()
    trimesh.repair.fill_holes(r)
    trimesh.repair.fix_normals(r, multibody=True)
    if _closed(r):
        return r, "repaired"
    f = _filled_by_open3d(r)
    if f is not None and _closed(f) and f.area <= (1.0 + MAX_REPAIR_AREA_FRACTION) * m.area \
            and f.volume <= 1.001 * m.convex_hull.volume:
        return f, "repaired"
    return m.convex_hull, "convex_hull"


def _manifold(mesh: trimesh.Trimesh):
    """``mesh`` as a manifold3d solid (single precision, as manifold3d stores it)."""
    import manifold3d

    return manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(mesh.vertices, np.float32),
                                               tri_verts=np.asarray(mesh.faces, np.uint32)))


#: Vertices this close above an object's lowest point carry it on the table (its support polygon), m.
SUPPORT_BAND_M = 0.0015


def support_margin(mesh: trimesh.Trimesh, center_of_mass, band_m: float = SUPPORT_BAND_M) -> float:
    """How far (m) the centre of mass's vertical projection lies inside the object's support polygon.

    The polygon is the convex hull (x, y) of the vertices within ``band_m`` of the lowest one (the
    object standing on z = min). Positive: it stands; negative: the projection is that far outside and
    the object falls over by itself (a corded drill without a battery on its base, a scan whose base
    was not measured). A base of fewer than three points, or all on a line, counts as outside by the
    projection's distance to the nearest of them.
    """
    from scipy.spatial import ConvexHull, QhullError

    v = np.asarray(mesh.vertices, float)
    c = np.asarray(center_of_mass, float).reshape(-1)[:2]
    low = v[v[:, 2] <= v[:, 2].min() + band_m][:, :2]
    try:
        eq = ConvexHull(low).equations  # n . p + d <= 0 inside, |n| = 1
    except (QhullError, ValueError):
        return -float(np.linalg.norm(low - c, axis=1).min())
    return float(-(eq[:, :2] @ c + eq[:, 2]).max())


#: An object stands on its own (a generated draw is kept, an import is called standing) when its centre of
#: mass is at least this angle inside the edge of its base, seen from the edge (``tipping_angle_deg``). In
#: simulation (``tests/station/test_generated_stand.py``) a drill of 2.5 deg (the validation split's first draw
#: of drill_09, session 37) and one of 4.05 deg (the fourth fresh seed's first draw of drill_00, session 46: it
#: fell in all 9 of its benchmark trials before the hand closed) fall over by themselves, nothing touching them,
#: while the committed drills, the lowest 4.55 deg (drill_11), stand (leaning < 1 deg into the compliant table).
#: Of the 315 instances of the committed data set, the test and validation splits and the four fresh seeds,
#: generated under the earlier 4.0 deg rule, only that 4.05 deg draw lay below 4.5 deg (every other instance is
#: the same draw under both); the real objects the benchmark imports (8 AIS drills, 3 YCB scans) tip at 7.0 deg
#: or more.
MIN_TIPPING_ANGLE_DEG = 4.5


def tipping_angle_deg(mesh: trimesh.Trimesh, center_of_mass=None) -> float:
    """How far (deg) ``mesh``, standing on its lowest point, must be tilted before its centre of mass (default:
    the closed mesh's at uniform density) passes the edge of its base (``support_margin``); negative: it falls."""
    com = np.asarray(mesh.center_mass if center_of_mass is None else center_of_mass, float).reshape(3)
    height = float(com[2] - mesh.vertices[:, 2].min())
    return float(np.degrees(np.arctan2(support_margin(mesh, com), height)))


def back_overhang_underside_m(mesh: trimesh.Trimesh, behind_m: float, step_m: float = 0.001,
                              start_m: float | None = None) -> float:
    """The height (m, frame O) of the underside of the mesh's topmost part that reaches ``behind_m`` behind its
    axis (y <= -behind_m): descending from ``start_m`` (default: the top less one step) in horizontal sections
    every ``step_m``, the lowest height of that first run of sections. NaN when the run reaches the base. E.g. a
    spray bottle's head: where its back begins (``benchmarks/results/experiments/s41_windex_thumb``)."""
    if not (behind_m > 0 and step_m > 0):
        raise InputError(f"back_overhang_underside_m: expected behind_m, step_m > 0, got {behind_m}, {step_m}")
    z = mesh.bounds[1, 2] - step_m if start_m is None else start_m
    seen = False
    while z > 0:
        section = mesh.section(plane_origin=[0, 0, z], plane_normal=[0, 0, 1])
        reaches = section is not None and section.vertices[:, 1].min() <= -behind_m
        if seen and not reaches:
            return float(z + step_m)
        seen = seen or reaches
        z -= step_m
    return float("nan")


def flatten_base(mesh: trimesh.Trimesh, depth_m: float) -> tuple[trimesh.Trimesh, bool]:
    """``mesh`` (upright: z up, base at its lowest point) with its lowest ``depth_m`` cut off by a
    horizontal plane and the cut closed flat (manifold3d's ``trim_by_plane``), then moved down by
    ``depth_m`` so the new flat base is at the old lowest height. Returns ``(mesh, flattened)``.

    Why: a scan's underside is rarely measured -- the surface reconstruction closes it with a rounded
    dome, on which a tall object rocks and falls over by itself (the YCB Windex bottle: a base
    curvature radius of about 2 cm under a centre of mass 10 cm high). A real bottle stands on a flat
    base. A mesh manifold3d cannot take (not closed) is returned as it is, with ``False``.
    """
    import manifold3d

    if depth_m <= 0:
        return mesh, False
    lo = float(mesh.bounds[0][2])
    try:
        solid = _manifold(mesh)
    except Exception:  # noqa: BLE001 -- manifold3d raises its own types for non-manifold input
        return mesh, False
    if solid.is_empty() or solid.status() != manifold3d.Error.NoError:
        return mesh, False
    out = solid.trim_by_plane([0.0, 0.0, 1.0], lo + float(depth_m)).to_mesh()
    flat = trimesh.Trimesh(np.asarray(out.vert_properties[:, :3], float), np.asarray(out.tri_verts), process=True)
    if len(flat.faces) == 0 or not flat.is_watertight:
        return mesh, False
    flat.apply_translation([0.0, 0.0, -float(depth_m)])
    return flat, True


#: Pieces of a scan stacked one over the other with a vertical gap up to this are bridged (m).
MAX_BRIDGED_GAP_M = 0.02
#: The bridge is the convex hull of both pieces' surface within this band beyond the gap (m).
BRIDGE_BAND_M = 0.004


def bridge_gaps(mesh: trimesh.Trimesh, max_gap_m: float = MAX_BRIDGED_GAP_M) -> tuple[trimesh.Trimesh, int]:
    """``mesh`` (upright) with every pair of its closed pieces that are stacked with a vertical gap of at most
    ``max_gap_m`` joined by a bridge: the convex hull of both pieces' vertices within :data:`BRIDGE_BAND_M`
    of the gap, united with them (manifold3d). Returns ``(mesh, bridges)``; pieces that overlap, lie side by
    side or are not closed are left as they are.

    Why: a scanner that cannot see a narrow part leaves the object in pieces -- the YCB Windex bottle's
    scan misses its neck, so its trigger head floats 15 mm above the body -- and a hand that grasps the
    neck closes on nothing. The bridge is a convex stand-in for the unseen part, no wider than what the
    scan saw next to it.
    """

    pieces = [p for p in mesh.split(only_watertight=False) if len(p.faces) >= MIN_PIECE_FACES]
    if len(pieces) < 2 or not all(p.is_watertight for p in pieces):
        return mesh, 0
    pieces.sort(key=lambda p: p.bounds[0][2])
    bridges = []
    for lower, upper in zip(pieces, pieces[1:]):
        gap = float(upper.bounds[0][2] - lower.bounds[1][2])
        if not 0.0 < gap <= max_gap_m:
            continue
        lo_band = lower.vertices[lower.vertices[:, 2] >= lower.bounds[1][2] - BRIDGE_BAND_M]
        up_band = upper.vertices[upper.vertices[:, 2] <= upper.bounds[0][2] + BRIDGE_BAND_M]
        # side by side, not stacked: the bands' footprints must overlap
        (a0, a1), (b0, b1) = (lo_band[:, :2].min(0), lo_band[:, :2].max(0)), (up_band[:, :2].min(0),
                                                                               up_band[:, :2].max(0))
        if np.any(np.minimum(a1, b1) <= np.maximum(a0, b0)):
            continue
        bridges.append(trimesh.convex.convex_hull(np.vstack([lo_band, up_band])))
    if not bridges:
        return mesh, 0

    solid = _manifold(pieces[0])
    for p in pieces[1:] + bridges:
        solid = solid + _manifold(p)
    out = solid.to_mesh()
    joined = trimesh.Trimesh(np.asarray(out.vert_properties[:, :3], float), np.asarray(out.tri_verts), process=True)
    if not joined.is_watertight:
        return mesh, 0
    return joined, len(bridges)
