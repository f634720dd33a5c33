"""Session 36: which model points does the camera see? Hidden-point removal against a z-buffer, on the truth.

    python benchmarks/results/experiments/s36_visibility/probe.py [--views 12]

The latent fit's E-step uses as mixture centres only the model points the camera sees under the current pose
(``core.visibility``). This asks how right that set is, and what it costs, on the committed instances (a tuning
set): each instance's 10 mm model cloud (``full_cloud``, as the shape spaces are built) seen from ``--views``
seeded cameras like the benchmark's (0.6-0.9 m, elevation 20-50 deg, any azimuth). The truth: a ray from the
camera to the point meets the mesh no earlier than 4 mm before the point (open3d ray casting on the mesh).
Per method: points wrongly called visible (hidden ones the E-step would use) and wrongly called hidden (seen
surface the E-step would ignore), in % of the truly hidden / truly visible points, and the time per call.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.core.validation import as_points, positive, vector3  # noqa: E402
from catgrasp_drake.core.visibility import camera_on_sphere_position, hidden_point_removal  # noqa: E402
from catgrasp_drake.data.dataset import CATEGORIES, list_instances, load_mesh  # noqa: E402
from catgrasp_drake.data.pointclouds import _cast, full_cloud  # noqa: E402
from catgrasp_drake.errors import InputError  # noqa: E402

TRUTH_TOL_M = 0.004


def zbuffer_visibility(points, camera_position, *, pixel: float, depth_tolerance: float) -> np.ndarray:
    """Boolean mask (N,) of the points of ``points`` (N, 3) visible from ``camera_position`` (3,), by a z-buffer.

    The points are projected (pinhole, the optical axis through their centroid) onto a grid whose cells are
    ``pixel`` metres wide at the centroid's depth; each point covers its cell and the 8 around it (a splat,
    so the gaps of a sparse cloud do not let the surface behind show through), and a point is visible iff its
    depth is within ``depth_tolerance`` (m) of the nearest depth over its own cell. Tried with a pixel of
    0.7-2 point spacings and tolerances of 1-6 spacings (the sweep below). Points at the camera count as
    visible, points behind it as hidden. Cost O(N), no hull.
    """
    P = as_points(points, "points", min_points=1)
    cam = vector3(camera_position, "camera_position")
    pixel = positive(pixel, "pixel")
    depth_tolerance = positive(depth_tolerance, "depth_tolerance")
    q = P - cam
    at_cam = np.linalg.norm(q, axis=1) <= 1e-12
    axis = q.mean(axis=0)
    n = float(np.linalg.norm(axis))
    if n <= 1e-12:  # the camera at the centroid: no direction to look along
        raise InputError("zbuffer_visibility: the camera sits at the points' centroid")
    w = axis / n
    u = np.cross(w, [0.0, 0.0, 1.0] if abs(w[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    z = q @ w
    front = z > 1e-9
    visible = at_cam.copy()
    if not front.any():
        return visible
    zf = z[front]
    cell = pixel / float(np.median(zf))  # the grid's pitch in the image plane (tangent units)
    ij = np.floor(np.column_stack([q[front] @ u, q[front] @ v]) / zf[:, None] / cell).astype(np.int64)
    ij -= ij.min(axis=0) - 1  # indices from 1: the splat's -1 stays >= 0
    width = int(ij[:, 1].max()) + 2
    own = ij[:, 0] * width + ij[:, 1]
    splat = (own[:, None] + (np.arange(-1, 2)[:, None] * width + np.arange(-1, 2)).reshape(1, 9)).reshape(-1)
    n_cells = (int(ij[:, 0].max()) + 2) * width
    if n_cells <= 64 * len(zf) + 4096:  # a dense buffer
        nearest = np.full(n_cells, np.inf)
        np.minimum.at(nearest, splat, np.repeat(zf, 9))
        near_own = nearest[own]
    else:  # a pixel far below the points' spread: only the occupied cells
        cells, inverse = np.unique(splat, return_inverse=True)
        nearest = np.full(len(cells), np.inf)
        np.minimum.at(nearest, inverse, np.repeat(zf, 9))
        near_own = nearest[np.searchsorted(cells, own)]
    visible[np.flatnonzero(front)] |= zf <= near_own + depth_tolerance
    return visible


def truth(mesh, P, cam):
    d = P - cam
    n = np.linalg.norm(d, axis=1)
    t = _cast(mesh, np.repeat(cam[None], len(P), 0), d / n[:, None])
    return t >= n - TRUTH_TOL_M


def methods(spacing):
    out = {f"HPR R={f:g}": (lambda P, c, f=f: hidden_point_removal(P, c, radius_factor=f)) for f in (100.0,)}
    for pix in (0.7, 1.0, 1.5, 2.0):
        for tol in (1.0, 2.0, 3.0, 4.0, 6.0):
            out[f"z-buffer pixel {pix:g}x tol {tol:g}x"] = (
                lambda P, c, pix=pix, tol=tol: zbuffer_visibility(P, c, pixel=pix * spacing,
                                                                  depth_tolerance=tol * spacing))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--views", type=int, default=12)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(36)
    for category in CATEGORIES:
        stats = {}
        n_vis = n_hid = 0
        for inst in list_instances(category):
            mesh = load_mesh(category, inst)
            P = full_cloud(mesh, voxel=0.01)
            centre = 0.5 * (P.min(0) + P.max(0))
            for _ in range(args.views):
                cam = camera_on_sphere_position(centre, rng.uniform(0.6, 0.9), rng.uniform(0, 2 * np.pi),
                                                np.radians(rng.uniform(20, 50)))
                true = truth(mesh, P, cam)
                n_vis += int(true.sum())
                n_hid += int((~true).sum())
                for name, f in methods(0.01).items():
                    t0 = time.perf_counter()
                    m = f(P, cam)
                    dt = time.perf_counter() - t0
                    s = stats.setdefault(name, [0, 0, 0.0, 0])
                    s[0] += int((m & ~true).sum())
                    s[1] += int((~m & true).sum())
                    s[2] += dt
                    s[3] += 1
        print(f"\n{category}: {n_vis} truly visible, {n_hid} truly hidden points over the views")
        print("| method | wrongly visible (% of hidden) | wrongly hidden (% of visible) | ms per call |")
        print("|---|---:|---:|---:|")
        for name, (fv, fh, dt, k) in stats.items():
            print(f"| {name} | {100 * fv / n_hid:.1f} | {100 * fh / n_vis:.1f} | {1e3 * dt / k:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
