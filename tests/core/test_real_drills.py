"""The core on the 11 real drills of ../shared (skipped when absent)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from catgrasp_drake.core.cpd import rigid_cpd
from catgrasp_drake.core.inference import infer_latent_pose
from catgrasp_drake.core.rotations import rotz
from catgrasp_drake.core.shape_space import build_shape_space
from catgrasp_drake.core.visibility import camera_on_sphere_position, hidden_point_removal

DRILLS = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "ais_drills"


@pytest.fixture(scope="module")
def drills():
    paths = sorted(DRILLS.glob("drill_*.pcd"), key=lambda p: int(p.stem.split("_")[1]))
    if not paths:
        pytest.skip("../shared/datasets/ais_drills not present")
    return [np.loadtxt(p, skiprows=11)[:, :3] for p in paths]


def test_leave_one_out_partial_views_beat_rigid_plus_scale_on_the_unseen_part(drills):
    test = 4
    space = build_shape_space([d for i, d in enumerate(drills) if i != test], canonical_index=0)
    T = drills[test]
    c = T.mean(0)
    rng = np.random.default_rng(0)
    ours, base = [], []
    for az in (0, 90, 180, 270):
        cam = camera_on_sphere_position(c, 0.6, np.radians(az), np.radians(30))
        vis = hidden_point_removal(T, cam)
        Rz, shift = rotz(rng.uniform(-0.26, 0.26)), np.r_[rng.uniform(-0.02, 0.02, 2), 0.0]
        move = lambda p: (p - c) @ Rz.T + c + shift  # noqa: E731
        obs, hidden, cam_o = move(T[vis]), move(T[~vis]), move(cam[None])[0]
        r = infer_latent_pose(space, obs, camera_position=cam_o)
        ours.append(cKDTree(r.completed).query(hidden)[0].mean())
        C = space.canonical
        v0 = hidden_point_removal(C + obs.mean(0) - C.mean(0), cam_o)
        rb = rigid_cpd(C + obs.mean(0) - C[v0].mean(0), obs, scale=True, w=0.05)
        base.append(cKDTree(rb.transformed).query(hidden)[0].mean())
        assert 0.0 < r.confidence <= 1.0
    assert np.mean(ours) < np.mean(base), (ours, base)
    assert np.mean(ours) < 0.012  # m
