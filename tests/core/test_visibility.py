"""Hidden-point removal (Katz et al. 2007)."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.visibility import camera_on_sphere_position, hidden_point_removal
from catgrasp_drake.errors import InputError

from .test_synthetic_shapes import fibonacci_sphere


def test_sphere_visible_cap():
    P = 0.1 * fibonacci_sphere(2000)
    cam = np.array([0.6, 0.0, 0.0])
    vis = hidden_point_removal(P, cam)
    facing = ((cam - P) * P).sum(1) > 0  # the geometrically visible cap
    cos_to_cam = ((cam - P[vis]) * P[vis]).sum(1) / (np.linalg.norm(cam - P[vis], axis=1) * 0.1)
    assert cos_to_cam.min() > -0.1  # nothing from the back (a few points just past the horizon)
    assert abs(vis.mean() - facing.mean()) < 0.05
    assert vis[np.argmax(P[:, 0])] and not vis[np.argmin(P[:, 0])]


def test_camera_position_helper_and_small_inputs():
    cam = camera_on_sphere_position([0, 0, 0.1], 0.6, 0.0, np.radians(30))
    assert np.isclose(np.linalg.norm(cam - [0, 0, 0.1]), 0.6) and cam[2] > 0.1
    assert hidden_point_removal(np.eye(3), cam).all()
    with pytest.raises(InputError):
        hidden_point_removal(np.eye(3), [0, 0])
    with pytest.raises(InputError):
        hidden_point_removal(np.zeros((0, 3)), [0, 0, 1])
