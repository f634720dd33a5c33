"""Full and partial clouds: density like the paper's data, on the surface, visibility, noise."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.data.dataset import list_instances, load_mesh
from catgrasp_drake.data.open3d_import import import_open3d
from catgrasp_drake.data.pointclouds import (
    PinholeCamera,
    camera_on_sphere,
    full_cloud,
    partial_cloud,
    surface_distance,
    voxel_downsample,
)
from catgrasp_drake.errors import InputError


@pytest.fixture(scope="module")
def drill():
    return load_mesh("drill", "drill_00")


def test_full_cloud_is_on_the_surface_and_voxel_spaced(drill):
    cloud = full_cloud(drill)
    assert 400 <= len(cloud) <= 1100
    assert surface_distance(drill, cloud).mean() < 0.001
    # one point per 1 cm voxel: no two points closer than a few mm on average
    from scipy.spatial import cKDTree

    d, _ = cKDTree(cloud).query(cloud, k=2)
    assert 0.004 < np.median(d[:, 1]) < 0.01
    # covers the whole object: the bounding box is reproduced within a voxel
    assert np.allclose(cloud.min(0), drill.bounds[0], atol=0.01)
    assert np.allclose(cloud.max(0), drill.bounds[1], atol=0.01)


def test_full_cloud_is_deterministic(drill):
    assert np.array_equal(full_cloud(drill), full_cloud(drill))


def test_partial_view_sees_only_the_near_side(drill):
    center = drill.bounds.mean(axis=0)
    cam = camera_on_sphere(center, 0.6, 0.0, np.radians(30))  # camera on the +x side
    view = partial_cloud(drill, cam, voxel=None)
    full = full_cloud(drill)
    assert surface_distance(drill, view).max() < 0.002
    # every point is the first hit along its camera ray (nothing in front of it)
    o3d = import_open3d()
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(drill.vertices.astype(np.float32)),
                        o3d.core.Tensor(drill.faces.astype(np.uint32)))
    eye = np.asarray(cam.eye)
    d = view - eye
    r = np.linalg.norm(d, axis=1)
    rays = np.hstack([np.broadcast_to(eye, d.shape), d / r[:, None]]).astype(np.float32)
    t_hit = scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy()
    assert np.all(np.abs(t_hit - r) < 1e-3)
    # the far (-x) side is not seen, and a single view holds clearly less than the full cloud
    assert np.mean(view[:, 0] < center[0] - 0.02) < 0.02
    assert len(voxel_downsample(view)) < 0.7 * len(full)


def test_depth_noise_is_seeded_and_needs_an_rng(drill):
    cam = camera_on_sphere(drill.bounds.mean(axis=0), 0.6, 1.0, 0.4)
    a = partial_cloud(drill, cam, voxel=None, depth_noise_std=0.002, rng=np.random.default_rng(3))
    b = partial_cloud(drill, cam, voxel=None, depth_noise_std=0.002, rng=np.random.default_rng(3))
    clean = partial_cloud(drill, cam, voxel=None)
    assert np.array_equal(a, b)
    err = np.linalg.norm(a - clean, axis=1)
    assert 0.001 < err.mean() < 0.003
    with pytest.raises(InputError, match="explicit rng"):
        partial_cloud(drill, cam, depth_noise_std=0.002)


def test_camera_looking_away_sees_nothing(drill):
    cam = PinholeCamera(eye=(1.0, 0.0, 0.1), target=(2.0, 0.0, 0.1))
    with pytest.raises(InputError, match="sees no part"):
        partial_cloud(drill, cam)


def test_voxel_grid_averages_points_per_voxel():
    pts = np.array([[0.001, 0.001, 0.001], [0.003, 0.003, 0.003], [0.015, 0.0, 0.0]])
    out = voxel_downsample(pts, 0.01)
    assert np.allclose(out, [[0.002, 0.002, 0.002], [0.015, 0.0, 0.0]])
    with pytest.raises(InputError, match="voxel"):
        voxel_downsample(pts, 0.0)


def test_every_category_gives_plausible_clouds():
    for category in ("spray_bottle", "mug"):
        mesh = load_mesh(category, list_instances(category)[0])
        cloud = full_cloud(mesh)
        assert 300 <= len(cloud) <= 1500
        assert surface_distance(mesh, cloud).mean() < 0.001
