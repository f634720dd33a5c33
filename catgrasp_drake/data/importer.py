"""Import your own object: a mesh or a point cloud -> an instance in a category's canonical frame.

``catgrasp import-object FILE --category C`` (docs/import.md) and
:func:`import_object` turn a user's file into the data set's layout
(``<name>.obj`` with normals, ``<name>.sdf``, ``annotations.json``; the
writer :func:`catgrasp_drake.data.dataset.write_model_files`), so that the
demo, the benchmark and the station use it like any instance. Steps:

1. **read** ``.obj/.stl/.ply/.off`` meshes with trimesh; ``.pcd/.npy`` (and a
   ``.ply`` without faces) as point clouds with :mod:`catgrasp_drake.data.cloud_io`.
   A cloud becomes a mesh by open3d's screened Poisson reconstruction
   (:func:`reconstruct_from_cloud`); the fit uses the cloud itself.
2. **units**: a largest extent above :data:`MAX_EXTENT_M` or below
   :data:`MIN_EXTENT_M` is refused in one line naming the likely unit.
3. **closed solid** for volume and inertia:
   :func:`catgrasp_drake.data.meshes.watertight_for_mass` (the mesh, else a
   repaired copy, else the convex hull, which only serves when ``mass_kg`` is
   given).
4. **alignment** X_canonical_input (canonical frame of docs/design.md
   section 3), automatic unless ``transform`` is given: every resting pose of
   the object (trimesh's ``compute_stable_poses``: its convex-hull faces the
   centre of mass stands over) and the file's own orientation are starts; in
   each, the category's shape space is fitted with the yaw search
   (:func:`catgrasp_drake.core.inference.infer_latent_pose`, latent shape +
   similarity; its rotation is a full 3-D one, so a start a few tens of
   degrees off still converges); the fit of least energy wins; its up
   direction is snapped to the nearest resting pose (within
   :data:`SNAP_MAX_DEG`) so the base is a real support face; then the base is
   put on z = 0 and the lateral extent centred on x = 0; y comes from the fit
   (the category model's origin).
4a. **one piece**: pieces of the mesh stacked with a vertical gap of at most
   2 cm are joined by the convex hull of their surfaces next to the gap
   (:func:`catgrasp_drake.data.meshes.bridge_gaps`: the Windex scan misses its neck).
4b. **flat base**: the lowest :data:`BASE_FLATTEN_M` (3 mm) cut off by a
   horizontal plane and closed flat (:func:`catgrasp_drake.data.meshes.flatten_base`),
   everything moved down by as much (regions too): the rounded underside a
   scan's reconstruction invents makes a tall object fall over by itself.
5. **functional region**: the canonical instance's box, its corners and
   centre deformed by the fitted field W(x) and moved by the fit's similarity
   into the object's canonical frame, as an axis-aligned box; ``grown_by``
   scaled with the fit. Or the user's point (input frame) with default
   half-extents.
6. **mass**: given, else the category's density times the solid's volume.
"""

from __future__ import annotations

import hashlib
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, Sequence

import numpy as np
import trimesh

from catgrasp_drake.core.deformation import deform_points
from catgrasp_drake.core.inference import infer_latent_pose
from catgrasp_drake.core.rotations import rotation_angle
from catgrasp_drake.core.shape_space import ShapeSpace
from catgrasp_drake.data.categories import DENSITY_KG_M3, FUNCTIONAL_REGION, REGION_MARGIN_M
from catgrasp_drake.data.cloud_io import read_point_cloud
from catgrasp_drake.data.dataset import CATEGORIES, load_annotations, read_annotations, write_model_files
from catgrasp_drake.data.meshes import (
    MIN_TIPPING_ANGLE_DEG,
    bridge_gaps,
    drop_debris,
    flatten_base,
    read_mesh,
    support_margin,
    tipping_angle_deg,
    watertight_for_mass,
)
from catgrasp_drake.data.open3d_import import import_open3d
from catgrasp_drake.data.pointclouds import full_cloud, voxel_downsample
from catgrasp_drake.errors import InputError, ModelFileError

MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off")
CLOUD_SUFFIXES = (".pcd", ".ply", ".npy")
#: Accepted largest extent of an object (m): a graspable object, in metres.
MAX_EXTENT_M = 1.5
MIN_EXTENT_M = 0.01
#: Units a too-large file may be in, tried in this order (name, metres per unit).
UNIT_GUESSES = (("millimetres", 0.001), ("centimetres", 0.01), ("inches", 0.0254))
#: Voxel of the cloud the shape space is fitted to (the trained models' clouds are 1 cm voxels).
FIT_VOXEL_M = 0.01
YAW_CANDIDATES = 12
FIT_ITERATIONS = 100
#: Resting poses closer than this (deg, between their down directions) are one start of the fit.
START_MERGE_DEG = 20.0
MAX_STARTS = 12
#: The fitted up direction is snapped to the nearest resting pose within this angle (deg).
SNAP_MAX_DEG = 10.0
#: The lowest part of an imported object cut off by a horizontal plane and closed flat (m): a scan's
#: underside is a reconstructed dome on which a tall object rocks and falls (meshes.flatten_base).
BASE_FLATTEN_M = 0.003
#: Below this fit confidence the alignment is flagged for a person to check (and the CLI says so).
LOW_CONFIDENCE = 0.6
#: Half-extents (m) of the box put around a user's region point, per region name.
DEFAULT_HALF_EXTENTS_M = {"trigger": (0.012, 0.012, 0.018), "handle": (0.010, 0.016, 0.030)}
#: ``grown_by`` of a box around a user's point: the box is taken as the part's bounding box plus 3 mm,
#: like the hand-annotated YCB boxes.
POINT_REGION_GROWN_BY_M = 0.003
#: Screened Poisson octree depth for clouds (~1 mm cells for a 25 cm object).
POISSON_DEPTH = 8
#: The Poisson surface is decimated to this many triangles (at most; and at least by 30 %).
POISSON_FACES = 20_000
#: A Poisson surface sample farther than this from the cloud was invented, not measured (m).
UNSUPPORTED_DISTANCE_M = 0.005
_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}$")


class CategoryShape(Protocol):
    """What the importer needs of a category model (a :class:`catgrasp_drake.category_model.CategoryModel`)."""

    category: str
    space: ShapeSpace
    canonical_instance: str


def canonical_annotations(shape: CategoryShape) -> dict:
    """The annotations of ``shape``'s canonical instance: an imported object's (a category folder's canonical,
    named in the model's optional ``params["objects"]``) or the embedded data set's."""
    objects = (getattr(shape, "params", None) or {}).get("objects") or {}
    if shape.canonical_instance in objects:
        return read_annotations(Path(objects[shape.canonical_instance]) / "annotations.json")
    return load_annotations(shape.category, shape.canonical_instance)


# ----------------------------------------------------------------------------- transforms
def transform_matrix(rpy_deg: Sequence[float], xyz_m: Sequence[float]) -> np.ndarray:
    """4x4 of roll, pitch, yaw (deg; R = Rz(yaw) Ry(pitch) Rx(roll), Drake's RollPitchYaw) and xyz (m)."""
    r, p, y = np.radians(np.asarray(rpy_deg, float))
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    X = np.eye(4)
    X[:3, :3] = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]]) @ np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]]) \
        @ np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    X[:3, 3] = np.asarray(xyz_m, float)
    return X


def rpy_xyz(X: np.ndarray) -> tuple[list[float], list[float]]:
    """(roll, pitch, yaw in deg, xyz in m) of a 4x4 rigid transform (inverse of :func:`transform_matrix`)."""
    R = np.asarray(X, float)[:3, :3]
    pitch = math.asin(float(np.clip(-R[2, 0], -1.0, 1.0)))
    if abs(R[2, 0]) < 1.0 - 1e-9:
        roll, yaw = math.atan2(R[2, 1], R[2, 2]), math.atan2(R[1, 0], R[0, 0])
    else:  # gimbal lock: yaw absorbs roll
        roll, yaw = 0.0, math.atan2(-R[0, 1], R[1, 1])
    return ([round(math.degrees(a), 6) for a in (roll, pitch, yaw)],
            [round(float(v), 6) for v in np.asarray(X, float)[:3, 3]])


def parse_transform(text: str | Sequence[float]) -> np.ndarray:
    """``"rx ry rz x y z"`` (deg, m; canonical <- input) -> 4x4; InputError naming the problem."""
    parts = text.replace(",", " ").split() if isinstance(text, str) else list(text)
    try:
        values = [float(v) for v in parts]
    except (TypeError, ValueError):
        values = []
    if len(values) != 6 or not all(math.isfinite(v) for v in values):
        raise InputError(f"transform: expected six numbers 'roll pitch yaw x y z' (deg, m), got {text!r}")
    if max(abs(v) for v in values[3:]) > 10.0:
        raise InputError(f"transform: a translation of {max(abs(v) for v in values[3:]):g} m; expected metres")
    return transform_matrix(values[:3], values[3:])


def _apply(X: np.ndarray, points: np.ndarray) -> np.ndarray:
    return np.asarray(points, float) @ X[:3, :3].T + X[:3, 3]


def _rotation_taking(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit vector ``a`` to unit vector ``b``."""
    v = np.cross(a, b)
    s, c = float(np.linalg.norm(v)), float(a @ b)
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        axis = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        axis /= np.linalg.norm(axis)
        return 2.0 * np.outer(axis, axis) - np.eye(3)
    k = v / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    angle = math.atan2(s, c)
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


# ----------------------------------------------------------------------------- reading
def check_size(extents, what: str) -> None:
    """InputError unless the largest of ``extents`` (m) is a graspable object's: names the likely unit."""
    largest = float(np.max(extents))
    if largest > MAX_EXTENT_M:
        guesses = [(unit, f) for unit, f in UNIT_GUESSES if MIN_EXTENT_M * 3 <= largest * f <= MAX_EXTENT_M / 1.5]
        hint = (f"it looks like {guesses[0][0]}: scale it by {guesses[0][1]:g}" if guesses
                else "scale it to metres")
        raise InputError(f"{what}: spans {largest:.4g} units, more than {MAX_EXTENT_M:g} m if metres; {hint}")
    if largest < MIN_EXTENT_M:
        raise InputError(f"{what}: spans {largest:.3g} m, less than {100 * MIN_EXTENT_M:g} cm: not a graspable "
                         "object in metres; check its units and scale it to metres")


def _ply_has_faces(path: Path) -> bool:
    """Whether a .ply file's header declares faces (a mesh) rather than only vertices (a cloud)."""
    with open(path, "rb") as f:
        head = f.read(4096)
    for line in head.split(b"\n"):
        words = line.strip().split()
        if words[:2] == [b"element", b"face"] and len(words) == 3:
            return words[2].isdigit() and int(words[2]) > 0
        if words[:1] == [b"end_header"]:
            break
    return False


@dataclass(frozen=True)
class ObjectFile:
    """A read input: a mesh (``points`` None) or a cloud (``mesh`` None), in the file's frame, metres."""

    path: Path
    kind: str  # "mesh" or "cloud"
    mesh: trimesh.Trimesh | None
    points: np.ndarray | None
    sha256: str
    normals: np.ndarray | None = None  # a cloud's own normals (N, 3), when its file stores them


def read_object_file(path) -> ObjectFile:
    """Read a mesh or a point cloud file; ModelFileError if unreadable, InputError for units or file type."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES + CLOUD_SUFFIXES:
        raise InputError(f"{path}: unsupported file type {suffix or '(none)'!r}; meshes: "
                         f"{' '.join(MESH_SUFFIXES)}, point clouds: {' '.join(CLOUD_SUFFIXES)}")
    if not path.is_file():
        raise ModelFileError(f"{path}: file not found")
    try:
        sha = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as e:
        raise ModelFileError(f"{path}: unreadable ({e.strerror or e})") from None
    if suffix in (".pcd", ".npy") or (suffix == ".ply" and not _ply_has_faces(path)):
        points, normals = read_point_cloud(path, check_units=False, with_normals=True)
        if len(points) < 100:
            raise InputError(f"{path}: {len(points)} points; a cloud of the whole object needs hundreds at least")
        check_size(np.ptp(points, axis=0), str(path))
        return ObjectFile(path, "cloud", None, points, sha, normals)
    mesh = read_mesh(path, check_units=False)
    check_size(mesh.extents, str(path))
    return ObjectFile(path, "mesh", mesh, None, sha)


def reconstruct_from_cloud(points: np.ndarray, normals: np.ndarray | None = None) -> tuple[trimesh.Trimesh, dict]:
    """A closed mesh of a cloud of the whole object: open3d's screened Poisson reconstruction.

    Normals: the cloud's own (``normals`` (N, 3), e.g. from the file: a CAD model's or a scanner's)
    first (a cloud of more than 200 000 points is thinned to a 2 mm grid, and its normals estimated);
    if their surface is not closed (or there are none), normals from 12 nearest neighbours,
    oriented consistently (tangent-plane propagation); either way turned outward (the majority pointing
    away from the centroid). The first closed surface is kept, else the last. On sparse clouds either
    can fail: on the 1 cm grids of the 11 real AIS drills the estimated orientation agrees with the
    files' normals on 52-100 % of the points, and Poisson then inflates the object into an open blob
    (drill_7, drill_9), while the files' normals leave drill_1 open. Octree depth :data:`POISSON_DEPTH`,
    then quadric decimation to :data:`POISSON_FACES` triangles or by 30 %, whichever is more. Returns
    the mesh and a record with the normals used and the fraction of its surface farther than
    :data:`UNSUPPORTED_DISTANCE_M` from every cloud point (surface Poisson invented where the cloud
    has gaps).
    """
    pts = np.asarray(points, float)
    if len(pts) > 200_000:
        pts = voxel_downsample(pts, 0.002)
        normals = None
    sources = ([("the cloud's own", np.asarray(normals, float))]
               if normals is not None and np.shape(normals) == np.shape(pts) else [])
    sources.append(("estimated (12 nearest neighbours)", None))
    for label, n in sources:  # noqa: B007 (the label of the surface kept is recorded below)
        mesh = _poisson_surface(pts, n)
        if mesh.is_watertight:
            break
    if len(mesh.faces) == 0:
        raise InputError("point cloud: the Poisson reconstruction gave no surface (too few or too scattered points)")
    samples, _ = trimesh.sample.sample_surface(mesh, 4000, seed=0)
    from scipy.spatial import cKDTree

    d, _ = cKDTree(pts).query(samples)
    info = {"method": f"open3d screened Poisson, depth {POISSON_DEPTH}", "points": int(len(points)),
            "normals": label, "unsupported_area_fraction": round(float(np.mean(d > UNSUPPORTED_DISTANCE_M)), 4)}
    return mesh, info


def _poisson_surface(pts: np.ndarray, normals: np.ndarray | None) -> trimesh.Trimesh:
    """Poisson surface of ``pts`` with these normals (None: estimated and oriented), turned outward."""
    o3d = import_open3d()
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        if normals is not None:
            cloud.normals = o3d.utility.Vector3dVector(normals)
        else:
            cloud.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(12))
            cloud.orient_normals_consistent_tangent_plane(12)
        n = np.asarray(cloud.normals)
        if float(np.mean(np.einsum("ij,ij->i", n, pts - pts.mean(axis=0)))) < 0:
            cloud.normals = o3d.utility.Vector3dVector(-n)
        # one thread: open3d's threaded Poisson gives a slightly different surface on every call
        surface, _ = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(cloud, depth=POISSON_DEPTH, n_threads=1)
        # quadric decimation (shortest, flattest edges first): no sub-micrometre edges, which the 1e-6 m
        # rounding of the written mesh would collapse into a non-manifold surface, and a collision mesh of a
        # sensible size
        surface = surface.simplify_quadric_decimation(min(POISSON_FACES, int(0.7 * len(surface.triangles))))
    return trimesh.Trimesh(np.asarray(surface.vertices), np.asarray(surface.triangles), process=True)


# ----------------------------------------------------------------------------- alignment
@dataclass(frozen=True)
class Alignment:
    """X_canonical_input (4x4, canonical <- input) and the category fit behind it.

    ``model_to_canonical`` ``(R, t, s)``: the fit's similarity from the
    category model's frame to the object's canonical frame (p -> s R p + t),
    with the latent vector ``latent``; None without a fit.
    """

    X_canonical_input: np.ndarray
    automatic: bool
    fit: dict = field(default_factory=dict)
    latent: np.ndarray | None = None
    model_to_canonical: tuple | None = None

    def record(self) -> dict:
        rpy, xyz = rpy_xyz(self.X_canonical_input)
        return {"rpy_deg": rpy, "xyz_m": xyz, "automatic": self.automatic,
                "convention": "canonical <- input; R = Rz(yaw) Ry(pitch) Rx(roll), then the translation"}


def resting_rotations(mesh: trimesh.Trimesh, center_mass) -> list[np.ndarray]:
    """Rotations (input -> upright) of the object's resting poses, most probable first (trimesh)."""
    transforms, _ = trimesh.poses.compute_stable_poses(mesh, center_mass=np.asarray(center_mass, float))
    return [np.asarray(T, float)[:3, :3] for T in transforms]


def _starts(rotations: list[np.ndarray]) -> list[np.ndarray]:
    """The file's own orientation, then the resting poses whose down direction differs by > START_MERGE_DEG."""
    out, downs = [], []
    for R in [np.eye(3)] + rotations:
        down = R.T @ np.array([0.0, 0.0, -1.0])  # the direction (input frame) that points down
        if all(down @ d < math.cos(math.radians(START_MERGE_DEG)) for d in downs):
            out.append(R)
            downs.append(down)
        if len(out) >= MAX_STARTS:
            break
    return out


def _fit_record(r, **extra) -> dict:
    return {"confidence": round(float(r.confidence), 4), "scale": round(float(r.s), 4),
            "energy": round(float(r.energy), 3), "latent_norm": round(float(np.linalg.norm(r.x)), 4),
            "iterations": int(r.iterations), **extra}


def snap_rotation(R_canonical_input: np.ndarray, resting: list[np.ndarray]) -> tuple[np.ndarray, float | None]:
    """``(R_snap, deg)``: the rotation (canonical frame) that turns the object's nearest resting pose
    (``resting``: rotations input -> upright, :func:`resting_rotations`) exactly upright, and how far
    it is (deg) -- the identity when none lies within :data:`SNAP_MAX_DEG` (``deg`` None: no resting
    pose at all). Snapping makes the base a face the object really stands on."""
    downs = [R_canonical_input @ (R.T @ np.array([0.0, 0.0, -1.0])) for R in resting]
    if not downs:
        return np.eye(3), None
    d = min(downs, key=lambda v: v[2])
    deg = math.degrees(math.acos(float(np.clip(-d[2] / np.linalg.norm(d), -1.0, 1.0))))
    if deg > SNAP_MAX_DEG:
        return np.eye(3), deg
    return _rotation_taking(d / np.linalg.norm(d), np.array([0.0, 0.0, -1.0])), deg


def level_stated_transform(X_stated: np.ndarray, mesh: trimesh.Trimesh, center_mass) -> tuple[np.ndarray, float | None,
                                                                                          bool]:
    """``(X, deg, snapped)``: a stated X_canonical_input levelled onto the nearest resting pose (within
    :data:`SNAP_MAX_DEG`; a transform found by eye leaves the base a few degrees off, and the object
    rocks onto its edge), turned about the base's lowest point, the base put back on z = 0."""
    Rs, deg = snap_rotation(X_stated[:3, :3], resting_rotations(mesh, center_mass))
    v = _apply(X_stated, mesh.vertices)
    lowest = v[np.argmin(v[:, 2])]
    X_snap = np.eye(4)
    X_snap[:3, :3], X_snap[:3, 3] = Rs, lowest - Rs @ lowest
    X = X_snap @ X_stated
    X[2, 3] -= _apply(X, mesh.vertices)[:, 2].min()
    return X, deg, bool(np.abs(Rs - np.eye(3)).max() > 0)


def align_to_category(shape: CategoryShape, mesh: trimesh.Trimesh, center_mass, observed: np.ndarray | None = None,
                      *, yaw_candidates: int = YAW_CANDIDATES) -> Alignment:
    """The automatic alignment (module docstring, step 4) of ``mesh`` (input frame) to ``shape``'s category.

    ``observed``: the points to fit (input frame; default a 1 cm full cloud ray-cast from ``mesh``).
    """
    t0 = time.perf_counter()
    pts = full_cloud(mesh, voxel=FIT_VOXEL_M) if observed is None else voxel_downsample(observed, FIT_VOXEL_M)
    resting = resting_rotations(mesh, center_mass)
    starts = _starts(resting)
    best = None
    for k, R_up in enumerate(starts):
        r = infer_latent_pose(shape.space, pts @ R_up.T, yaw_candidates=yaw_candidates, max_iter=FIT_ITERATIONS)
        if best is None or r.energy < best[0].energy:
            best = (r, R_up, k)
    r, R_up, k = best
    # object canonical frame = the model frame, unscaled: p_c = R^T (R_up p_in - t)
    Rc = r.R.T @ R_up
    tc = -r.R.T @ r.t
    Rs, snap_deg = snap_rotation(Rc, resting)
    snapped = snap_deg is not None and snap_deg <= SNAP_MAX_DEG
    Rc, tc = Rs @ Rc, Rs @ tc
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = Rc, tc
    v = _apply(X, mesh.vertices)
    lo, hi = v.min(axis=0), v.max(axis=0)
    X[0, 3] -= (lo[0] + hi[0]) / 2  # lateral extent centred on x = 0
    X[2, 3] -= lo[2]  # base on z = 0
    # the fit's similarity, model frame -> object canonical frame: p_c = Rc R_up^T (s R p + t) + tc
    A = X[:3, :3] @ R_up.T
    model_to_canonical = (A @ r.R, A @ r.t + X[:3, 3], float(r.s))
    fit = _fit_record(r, starts=len(starts), chosen_start=k, resting_poses=len(resting),
                      snapped_to_resting_pose=snapped,
                      snap_deg=None if snap_deg is None else round(snap_deg, 3),
                      yaw_candidates=int(yaw_candidates), fit_points=int(len(pts)),
                      seconds=round(time.perf_counter() - t0, 2))
    return Alignment(X, True, fit, r.x.copy(), model_to_canonical)


def fit_in_canonical_frame(shape: CategoryShape, points_canonical: np.ndarray) -> tuple[dict, np.ndarray, tuple]:
    """The category fit of an object already in its canonical frame (a stated transform): record, x, similarity."""
    t0 = time.perf_counter()
    r = infer_latent_pose(shape.space, voxel_downsample(points_canonical, FIT_VOXEL_M), max_iter=FIT_ITERATIONS)
    fit = _fit_record(r, rotation_vs_stated_deg=round(math.degrees(float(rotation_angle(r.R))), 3),
                      seconds=round(time.perf_counter() - t0, 2))
    return fit, r.x.copy(), (r.R, r.t, float(r.s))


# ----------------------------------------------------------------------------- regions
def transfer_region(shape: CategoryShape, alignment: Alignment, name: str) -> dict:
    """The canonical instance's ``name`` box carried by the fit into the object's canonical frame (step 5)."""
    if alignment.model_to_canonical is None or alignment.latent is None:
        raise InputError(f"region {name!r}: no category fit to transfer it with; give the region's point")
    regions = canonical_annotations(shape).get("regions", {})
    if name not in regions:
        raise InputError(f"the canonical instance {shape.canonical_instance} has no {name!r} region "
                         f"(it has {sorted(regions)})")
    box = regions[name]
    W = shape.space.decode(alignment.latent)
    deformed = deform_points(shape.space.canonical, W, shape.space.beta, box_points(box))
    R, t, s = alignment.model_to_canonical
    mapped = s * deformed @ np.asarray(R).T + np.asarray(t)
    grown = float(box.get("grown_by", REGION_MARGIN_M.get(name, 0.0)))
    return box_around(mapped) | {"grown_by": round(grown * s, 6), "transferred_from": shape.canonical_instance}


def box_points(box: dict) -> np.ndarray:
    """The 8 corners, then the centre, of an axis-aligned region box (``center``, ``half_extents``; m): (9, 3)."""
    c, h = np.asarray(box["center"], float), np.asarray(box["half_extents"], float)
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
    return np.vstack([c + signs * h, c])


def box_around(points: np.ndarray) -> dict:
    """The axis-aligned box of :func:`box_points` moved by some map (``points`` (9, 3)): its centre and
    half-extents from the moved corners, and where the moved centre went (``deformed_center``)."""
    lo, hi = points[:8].min(axis=0), points[:8].max(axis=0)
    return {"center": [round(float(v), 6) for v in (lo + hi) / 2],
            "half_extents": [round(float(v), 6) for v in (hi - lo) / 2],
            "deformed_center": [round(float(v), 6) for v in points[8]]}


def point_region(name: str, point_canonical) -> dict:
    """A box of :data:`DEFAULT_HALF_EXTENTS_M` around a user's point (canonical frame)."""
    p = np.asarray(point_canonical, float)
    return {"center": [round(float(v), 6) for v in p],
            "half_extents": list(DEFAULT_HALF_EXTENTS_M.get(name, (0.015, 0.015, 0.015))),
            "grown_by": POINT_REGION_GROWN_BY_M}


# ----------------------------------------------------------------------------- the import
@dataclass(frozen=True)
class ImportedObject:
    """An imported object, written (``directory``) in the data set's layout."""

    name: str
    category: str
    directory: Path
    mesh: trimesh.Trimesh  # the written visual/collision mesh, canonical frame
    mass_kg: float
    regions: dict
    alignment: Alignment
    record: dict  # the "import" block of annotations.json

    @property
    def confidence(self) -> float | None:
        return self.alignment.fit.get("confidence")

    @property
    def low_confidence(self) -> bool:
        c = self.confidence
        return c is not None and c < LOW_CONFIDENCE


def default_name(path) -> str:
    """An instance name from a file name: ``My Drill (2).obj`` -> ``my_drill_2``."""
    stem = re.sub(r"[^a-z0-9]+", "_", Path(path).stem.lower()).strip("_")
    return (stem or "object")[:64]


def default_out_dir(category: str, name: str) -> Path:
    return Path("out") / "objects" / category / name


def _check_inputs(category, name, mass_kg, region_point, functional):
    if category not in CATEGORIES:
        raise InputError(f"unknown category {category!r}; known: {', '.join(CATEGORIES)}")
    if not isinstance(name, str) or not _NAME.match(name):
        raise InputError(f"name: {name!r} is not a file-safe instance name (letters, digits, _ . -; <= 64)")
    if mass_kg is not None and not (isinstance(mass_kg, (int, float)) and math.isfinite(mass_kg)
                                    and 0.001 <= mass_kg <= 50.0):
        raise InputError(f"mass: expected 0.001..50 kg, got {mass_kg!r}")
    if region_point is not None:
        rname, p = region_point
        if rname != functional:
            raise InputError(f"region: a {category}'s functional region is {functional!r}, not {rname!r}")
        p = np.asarray(p, float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)) or np.abs(p).max() > MAX_EXTENT_M * 10:
            raise InputError(f"region {rname!r}: expected a finite point X Y Z in metres, got {region_point[1]!r}")


def import_mesh(mesh: trimesh.Trimesh, category: str, name: str, *, model: CategoryShape | None = None,
                transform=None, mass_kg: float | None = None, region_point=None, regions: dict | None = None,
                out=None, source: dict | None = None, observed: np.ndarray | None = None,
                extra: dict | None = None, what: str = "mesh",
                base_flatten_m: float = BASE_FLATTEN_M, density_kg_m3: float | None = None) -> ImportedObject:
    """Import an in-memory mesh (input frame, metres); see :func:`import_object`.

    ``regions``: boxes already in the canonical frame (skips the transfer);
    ``observed``: the points to fit instead of a cloud ray-cast from the mesh;
    ``extra``: more top-level annotation fields (e.g. the YCB table's);
    ``base_flatten_m``: the base's lowest part cut off flat (module docstring, step 4b; 0: as it is);
    ``density_kg_m3``: without ``mass_kg``, the mass is this density (default: the category's) times the volume.
    """
    functional = FUNCTIONAL_REGION.get(category)
    _check_inputs(category, name, mass_kg, region_point, functional)
    if model is not None and model.category != category:
        raise InputError(f"the category model is a {model.category!r} model, not {category!r}")
    check_size(mesh.extents, what)
    mesh = drop_debris(mesh)
    solid_in, _ = watertight_for_mass(mesh)
    # ---- alignment
    if transform is not None:
        X_stated = np.array(transform if isinstance(transform, np.ndarray) else parse_transform(transform), float)
        X, snap_deg, snapped = level_stated_transform(X_stated, mesh, solid_in.center_mass)
        if regions is not None:  # given in the stated frame: they move with the levelling
            moved = X @ np.linalg.inv(X_stated)
            regions = {k: dict(v) | {"center": [round(float(c), 6) for c in _apply(moved, np.asarray(
                v["center"], float)[None])[0]]} for k, v in regions.items()}
        alignment = Alignment(X, False, {"snap_deg": None if snap_deg is None else round(snap_deg, 3),
                                         "snapped_to_resting_pose": snapped})
        if model is not None and regions is None and region_point is None:
            pts = full_cloud(mesh, voxel=FIT_VOXEL_M) if observed is None else observed
            fit, x, sim = fit_in_canonical_frame(model, _apply(alignment.X_canonical_input, pts))
            alignment = Alignment(alignment.X_canonical_input, False, fit, x, sim)
    else:
        if model is None:
            raise InputError("the automatic alignment needs the category model (or give a stated transform)")
        alignment = align_to_category(model, mesh, solid_in.center_mass, observed)
    X = alignment.X_canonical_input
    canonical = mesh.copy()
    canonical.apply_transform(X)
    canonical, bridges = bridge_gaps(canonical)  # a scan in stacked pieces (a neck it missed) made one
    solid, solid_method = watertight_for_mass(canonical)
    # ---- a flat base (a scan's rounded underside rocks): the lowest base_flatten_m cut off flat
    flattened, volume_m3 = False, float(solid.volume)  # the mass is the object's, before the cut
    if solid_method != "convex_hull" and base_flatten_m > 0:
        solid, flattened = flatten_base(solid, base_flatten_m)
        if flattened:
            canonical = solid
    drop = base_flatten_m if flattened else 0.0
    # ---- regions
    if regions is not None:
        regions, region_source = {k: dict(v) for k, v in regions.items()}, "given"
    elif region_point is not None:
        p_canonical = _apply(X, np.asarray(region_point[1], float)[None])[0]
        regions = {region_point[0]: point_region(region_point[0], p_canonical)}
        region_source = "the user's point (input frame), default half-extents"
    elif model is not None and functional is not None:
        regions = {functional: transfer_region(model, alignment, functional)}
        region_source = f"transferred from {model.canonical_instance} by the category fit"
    else:
        regions, region_source = {}, "none"
    # everything above the cut moved down with it (the alignment X_canonical_input is kept as fitted or
    # stated: the written mesh is X followed by the drop, as the record's base_flattened_m says)
    if drop:
        regions = {k: dict(v) | {"center": [float(v["center"][0]), float(v["center"][1]),
                                            round(float(v["center"][2]) - drop, 6)]} for k, v in regions.items()}
    # ---- mass
    if mass_kg is not None:
        mass, mass_source = float(mass_kg), "given"
    elif solid_method == "convex_hull":
        raise InputError(f"{what}: not watertight and hole filling cannot close it, so its volume (and mass) "
                         "is unknown: close it (e.g. Poisson in MeshLab) or give the mass (--mass KG)")
    else:
        mass, mass_source = ((DENSITY_KG_M3[category] * volume_m3, "category density x volume")
                             if density_kg_m3 is None else (float(density_kg_m3) * volume_m3, "given density x volume"))
    density = mass / float(solid.volume)
    solid.density = density
    written_mesh = solid if solid_method == "repaired" else canonical
    margin = support_margin(written_mesh, solid.center_mass)
    tipping = tipping_angle_deg(written_mesh, solid.center_mass)
    record = {
        "source": source or {},
        "transform": alignment.record(),
        "fit": alignment.fit or None,
        "collision_mesh": {"mesh": "the input mesh", "repaired": "the input mesh, holes filled",
                           "convex_hull": "the input mesh (open; inertia from its convex hull)"}[solid_method],
        "mass_source": mass_source,
        "region_source": region_source,
        "base_flattened_m": drop,
        "bridged_gaps": bridges,
        # the centre of mass over the base (m; meshes.support_margin): negative, it falls over by itself;
        # the angle it tips at (meshes.tipping_angle_deg): below MIN_TIPPING_ANGLE_DEG it falls in simulation
        "support_margin_m": round(margin, 4),
        "tipping_angle_deg": round(tipping, 2),
        "stands": bool(tipping >= MIN_TIPPING_ANGLE_DEG),
    }
    directory = Path(out) if out is not None else default_out_dir(category, name)
    fields = {"inertia_from": solid_method, "density_kg_m3": round(density, 3), "functional": bool(regions),
              **(extra or {}), "import": record}
    write_model_files(directory, name, category, written_mesh, solid, mass, regions, fields)
    return ImportedObject(name, category, directory, written_mesh, mass, regions, alignment, record)


def import_object(path, category: str, *, model: CategoryShape | None = None, mass_kg: float | None = None,
                  region=None, transform=None, out=None, name: str | None = None,
                  regions: dict | None = None) -> ImportedObject:
    """Import a mesh or point-cloud file as an instance of ``category`` (module docstring).

    ``model``: the category model (``CategoryModel.load("models/trained/<category>.npz")``), needed for
    the automatic alignment and the region transfer; ``transform``: a stated alignment, ``"rx ry rz x y z"``
    (deg, m; canonical <- input) or a 4x4; ``region``: ``(name, (x, y, z))``, a point of the functional part
    in the file's frame (m); ``mass_kg``: else the category's density times the volume; ``out``: the
    directory (default ``out/objects/<category>/<name>``); ``name``: default from the file name; ``regions``:
    annotated boxes (``{name: {"center", "half_extents", ...}}``, m) in the frame ``transform`` maps from, given
    instead of transferred (the benchmark's pinned AIS triggers).
    """
    if category not in CATEGORIES:
        raise InputError(f"unknown category {category!r}; known: {', '.join(CATEGORIES)}")
    f = read_object_file(path)
    name = default_name(f.path) if name is None else name
    source = {"file": str(f.path), "sha256": f.sha256, "kind": f.kind}
    if f.kind == "cloud":
        mesh, info = reconstruct_from_cloud(f.points, f.normals)
        source["reconstruction"] = info
        observed = f.points
    else:
        mesh, observed = f.mesh, None
        source["faces"] = int(len(f.mesh.faces))
    return import_mesh(mesh, category, name, model=model, transform=transform, mass_kg=mass_kg,
                       region_point=region, regions=regions, out=out, source=source, observed=observed,
                       what=str(f.path))
