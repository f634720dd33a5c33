"""``catgrasp demo``: the main job on the embedded default data.

Current stages (later issues extend it into the full grasp transfer):
1. full clouds (ray-cast + voxel grid) of every training instance of a category;
2. a single depth view of one held-out instance at a seeded random yaw;
3. a contact sheet of the category and the clouds written to the output folder.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np


def _stage(name: str, t0: float, detail: str) -> float:
    t1 = time.perf_counter()
    print(f"[{t1 - t0:6.2f} s] {name:<14s} {detail}")
    return t1


def run_demo(args) -> int:
    from catgrasp_drake.data.cloud_io import write_point_cloud
    from catgrasp_drake.data.dataset import instance_clouds, list_instances, load_mesh
    from catgrasp_drake.data.pointclouds import camera_on_sphere, partial_cloud
    from catgrasp_drake.errors import InputError
    from catgrasp_drake.viz.sheets import dataset_contact_sheet

    out = Path(args.out)
    names = list_instances(args.category)
    held_out = args.instance or names[-1]
    if held_out not in names:
        raise InputError(f"unknown instance {held_out!r}; known: {', '.join(names)}")
    train = [n for n in names if n != held_out]
    rng = np.random.default_rng(args.seed)
    t = time.perf_counter()
    t_start = t

    clouds = dict(zip(train, instance_clouds(args.category, train)))
    for n, c in clouds.items():
        write_point_cloud(out / "clouds" / f"{n}.pcd", c)
    counts = [len(c) for c in clouds.values()]
    t = _stage("shape data", t, f"{len(train)} {args.category} clouds, {min(counts)}-{max(counts)} points each")

    mesh = load_mesh(args.category, held_out)
    yaw = rng.uniform(-np.pi, np.pi)
    cam = camera_on_sphere(mesh.bounds.mean(axis=0), 0.6, yaw, np.radians(30.0))
    view = partial_cloud(mesh, cam, depth_noise_std=0.001, rng=rng)
    write_point_cloud(out / f"{held_out}_view.pcd", view)
    t = _stage("depth view", t, f"{held_out} seen from azimuth {np.degrees(yaw):.0f} deg: {len(view)} points")

    dataset_contact_sheet(out / f"{args.category}_instances.png", categories=[args.category])
    t = _stage("contact sheet", t, str(out / f"{args.category}_instances.png"))
    print(f"done in {t - t_start:.1f} s; results in {out}/")
    return 0
