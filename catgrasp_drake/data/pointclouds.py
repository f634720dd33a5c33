"""Point clouds from meshes, as in the paper: ray-casting + voxel grid.

* :func:`full_cloud` ray-casts the mesh from the viewpoints of a tessellated
  sphere (icosphere vertices) and voxel-filters the union of the hits (PCL-style:
  one point per occupied voxel, the mean of its points).
* :func:`partial_cloud` keeps only what one camera sees (single depth view),
  with optional Gaussian depth noise along each ray.

All clouds are ``(N, 3)`` float64 arrays in the mesh frame, metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from catgrasp_drake.core.validation import as_points, count, non_negative, positive, real_number, vector3
from catgrasp_drake.core.visibility import camera_on_sphere_position, look_at_matrix
from catgrasp_drake.data.open3d_import import import_open3d
from catgrasp_drake.errors import InputError

DEFAULT_VOXEL_M = 0.01
#: Largest image side (pixels) of a simulated camera, and largest full-cloud resolution.
MAX_IMAGE_SIDE = 4096
#: Deepest icosphere subdivision of :func:`full_cloud` (5: 10242 viewpoints).
MAX_SUBDIVISIONS = 5
#: Most rays of one :func:`full_cloud` (the default casts 42 x 160^2 = 1.1e6).
MAX_RAYS = 20_000_000


@dataclass(frozen=True)
class PinholeCamera:
    """A pinhole depth camera: pose as eye/target/up in the mesh frame, image size, vertical fov."""

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    width: int = 160
    height: int = 120
    fov_y_deg: float = 45.0

    def __post_init__(self):
        eye, target, _ = (vector3(getattr(self, name), f"camera {name}") for name in ("eye", "target", "up"))
        if np.linalg.norm(target - eye) < 1e-9:
            raise InputError("camera: eye and target coincide")
        count(self.width, "camera width", 1, MAX_IMAGE_SIDE)
        count(self.height, "camera height", 1, MAX_IMAGE_SIDE)
        fov = real_number(self.fov_y_deg, "camera fov_y_deg")
        if not 0.0 < fov < 180.0:
            raise InputError(f"camera fov_y_deg: must be in (0, 180) degrees, got {fov}")

    def rays(self) -> tuple[np.ndarray, np.ndarray]:
        """(origins, unit directions) of one ray per pixel, each ``(H*W, 3)``."""
        eye = np.asarray(self.eye, float)
        X_MC = look_at_matrix(eye, self.target, self.up)  # camera axes: x right, y down, z forward
        right, down, forward = X_MC[:3, 0], X_MC[:3, 1], X_MC[:3, 2]
        f = 0.5 * self.height / np.tan(np.radians(self.fov_y_deg) / 2)
        u = np.arange(self.width) + 0.5 - self.width / 2
        v = np.arange(self.height) + 0.5 - self.height / 2
        uu, vv = np.meshgrid(u, v)
        d = forward[None] * f + uu.reshape(-1, 1) * right[None] + vv.reshape(-1, 1) * down[None]
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return np.broadcast_to(eye, d.shape).copy(), d


def camera_on_sphere(target, distance: float, azimuth_rad: float, elevation_rad: float, **kw) -> PinholeCamera:
    """Camera at ``distance`` from ``target``; azimuth from +x toward +y, elevation above the x-y plane."""
    target = vector3(target, "target")
    azimuth_rad, elevation_rad = real_number(azimuth_rad, "azimuth_rad"), real_number(elevation_rad, "elevation_rad")
    eye = camera_on_sphere_position(target, distance, azimuth_rad, elevation_rad)
    up = (0.0, 0.0, 1.0) if abs(np.cos(elevation_rad)) > 1e-6 else (1.0, 0.0, 0.0)
    return PinholeCamera(tuple(eye), tuple(target), up, **kw)


def _scene(mesh: trimesh.Trimesh):
    o3d = import_open3d()
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(np.asarray(mesh.vertices, np.float32)),
        o3d.core.Tensor(np.asarray(mesh.faces, np.uint32)),
    )
    return o3d, scene


def surface_distance(mesh: trimesh.Trimesh, points) -> np.ndarray:
    """Unsigned distance (metres) from each point to the mesh surface."""
    points = as_points(points, "points")
    o3d, scene = _scene(_check_mesh(mesh))
    d = scene.compute_distance(o3d.core.Tensor(points.astype(np.float32)))
    return d.numpy().astype(np.float64)


def _cast(mesh: trimesh.Trimesh, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Ray distances to the first hit (inf where missed), with open3d's raycasting scene."""
    o3d, scene = _scene(mesh)
    rays = o3d.core.Tensor(np.hstack([origins, directions]).astype(np.float32))
    return scene.cast_rays(rays)["t_hit"].numpy().astype(np.float64)


def voxel_downsample(points, voxel: float = DEFAULT_VOXEL_M) -> np.ndarray:
    """PCL-style voxel grid filter: the centroid of the points in each occupied voxel.

    Deterministic: output sorted by voxel index.
    """
    points = as_points(points, "points")
    voxel = positive(voxel, "voxel")
    if float(np.abs(points).max()) / voxel > 2.0**60:
        raise InputError(f"voxel: {voxel:g} m is too small for coordinates up to {float(np.abs(points).max()):.3g} m "
                         "(voxel indices overflow)")
    keys = np.floor(points / voxel).astype(np.int64)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    sums = np.zeros((len(uniq), 3))
    np.add.at(sums, inverse, points)
    counts = np.bincount(inverse, minlength=len(uniq)).astype(float)
    return sums / counts[:, None]


def _check_mesh(mesh) -> trimesh.Trimesh:
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError("mesh: expected a non-empty trimesh.Trimesh")
    v = np.asarray(mesh.vertices)
    if not np.all(np.isfinite(v)):
        raise InputError("mesh: has NaN or inf vertices")
    as_points(v, "mesh vertices")  # metres, within MAX_COORDINATE_M
    return mesh


def full_cloud(
    mesh: trimesh.Trimesh,
    *,
    voxel: float = DEFAULT_VOXEL_M,
    subdivisions: int = 1,
    resolution: int = 160,
) -> np.ndarray:
    """Cloud of the whole visible surface: ray-cast from every vertex of an icosphere.

    ``subdivisions=1`` gives 42 viewpoints on a sphere of twice the object's
    bounding radius around its bounding-box centre; each view casts a
    ``resolution`` x ``resolution`` image. Then a voxel grid of ``voxel`` metres.
    """
    mesh = _check_mesh(mesh)
    voxel = positive(voxel, "voxel")
    subdivisions = count(subdivisions, "subdivisions", 0, MAX_SUBDIVISIONS)
    resolution = count(resolution, "resolution", 1, MAX_IMAGE_SIDE)
    n_views = 10 * 4**subdivisions + 2
    if n_views * resolution**2 > MAX_RAYS:
        raise InputError(f"full_cloud: {n_views} views of {resolution}x{resolution} rays exceed {MAX_RAYS:.0e} rays; "
                         "lower resolution or subdivisions")
    center = mesh.bounds.mean(axis=0)
    radius = 0.5 * float(np.linalg.norm(mesh.extents))
    if not radius > 1e-6:
        raise InputError(f"mesh: spans {2 * radius:.3g} m; too small to ray-cast (metres expected)")
    distance = 2.0 * radius
    fov = 2 * np.degrees(np.arcsin(min(0.99, 1.05 * radius / distance)))
    views = trimesh.creation.icosphere(subdivisions=subdivisions).vertices
    origins, directions = [], []
    for v in views:
        up = (0.0, 0.0, 1.0) if abs(v[2]) < 0.99 else (1.0, 0.0, 0.0)
        cam = PinholeCamera(tuple(center + distance * v), tuple(center), up, resolution, resolution, fov)
        o, d = cam.rays()
        origins.append(o)
        directions.append(d)
    origins, directions = np.vstack(origins), np.vstack(directions)
    t = _cast(mesh, origins, directions)
    hit = np.isfinite(t)
    if not np.any(hit):
        raise InputError("full_cloud: no ray hit the mesh (degenerate or flat mesh?)")
    return voxel_downsample(origins[hit] + t[hit, None] * directions[hit], voxel)


def partial_cloud(
    mesh: trimesh.Trimesh,
    camera: PinholeCamera,
    *,
    voxel: float | None = DEFAULT_VOXEL_M,
    depth_noise_std: float = 0.0,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """The part of the surface one camera sees (single depth view), optionally noisy.

    Depth noise is Gaussian along each ray with ``depth_noise_std`` metres and
    needs an explicit ``rng``. Raises InputError if the camera sees nothing.
    """
    mesh = _check_mesh(mesh)
    if not isinstance(camera, PinholeCamera):
        raise InputError(f"camera: expected a PinholeCamera, got {type(camera).__name__}")
    depth_noise_std = non_negative(depth_noise_std, "depth_noise_std")
    if voxel is not None:
        voxel = positive(voxel, "voxel")
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise InputError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    origins, directions = camera.rays()
    t = _cast(mesh, origins, directions)
    hit = np.isfinite(t)
    if not np.any(hit):
        raise InputError("partial_cloud: the camera sees no part of the mesh")
    t = t[hit]
    if depth_noise_std > 0:
        if rng is None:
            raise InputError("partial_cloud: depth noise needs an explicit rng (numpy.random.Generator)")
        t = t + rng.normal(0.0, depth_noise_std, size=t.shape)
    points = origins[hit] + t[:, None] * directions[hit]
    return voxel_downsample(points, voxel) if voxel else points
