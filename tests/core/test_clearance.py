"""Object clearance (core.clearance): signed distance from surface points, and the smallest clearing shift.

Known answers: a sphere's and a box's signed distance; a point set pushed into a box comes out along the
face it went in by, by exactly its depth less the tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.clearance import SignedDistanceGrid, clearance_shift
from catgrasp_drake.errors import InputError


def _sphere_points(radius: float, n: int, seed: int = 0) -> np.ndarray:
    u = np.random.default_rng(seed).normal(size=(n, 3))
    return radius * u / np.linalg.norm(u, axis=1, keepdims=True)


def _box_points(half: np.ndarray, spacing: float) -> np.ndarray:
    """Points on the surface of the box [-half, half] (m), about ``spacing`` apart."""
    grids = [np.arange(-h, h + 1e-9, spacing) for h in half]
    out = []
    for axis in range(3):
        a, b = [i for i in range(3) if i != axis]
        A, B = (m.ravel() for m in np.meshgrid(grids[a], grids[b]))
        for sign in (-1.0, 1.0):
            face = np.zeros((len(A), 3))
            face[:, a], face[:, b], face[:, axis] = A, B, sign * half[axis]
            out.append(face)
    return np.vstack(out)


def test_signed_distance_of_a_sphere_is_its_radius_less_the_distance_from_the_centre():
    field = SignedDistanceGrid.from_surface_points(_sphere_points(0.05, 20000), voxel=0.002)
    q = np.array([[0.0, 0.0, 0.0], [0.03, 0.0, 0.0], [0.0, 0.045, 0.0], [0.0, 0.0, 0.06], [0.08, 0.0, 0.0]])
    expected = 0.05 - np.linalg.norm(q, axis=1)
    np.testing.assert_allclose(field(q), expected, atol=0.0025)
    # the gradient points into the solid: towards the centre
    g = field.gradient_at(np.array([[0.04, 0.0, 0.0], [0.0, -0.055, 0.0]]))
    assert g[0, 0] < -0.8 and g[1, 1] > 0.8


def test_a_hollow_box_open_nowhere_is_filled_but_a_cup_open_at_the_top_is_not():
    half = np.array([0.03, 0.02, 0.04])
    box = _box_points(half, 0.002)
    field = SignedDistanceGrid.from_surface_points(box, voxel=0.002)
    assert field(np.zeros((1, 3)))[0] == pytest.approx(0.02, abs=0.0025)  # the nearest face is 2 cm away
    cup = box[box[:, 2] < half[2] - 1e-9]  # the top face removed
    field = SignedDistanceGrid.from_surface_points(cup, voxel=0.002)
    assert field(np.zeros((1, 3)))[0] < 0.0  # the cup's inside is free space


def test_a_set_pushed_into_a_box_comes_out_through_the_face_it_went_in_by():
    half = np.array([0.03, 0.02, 0.04])
    field = SignedDistanceGrid.from_surface_points(_box_points(half, 0.002), voxel=0.002)
    # a small rigid set 8 mm inside the +x face, well away from the other faces
    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(0.022, 0.05, 50), rng.uniform(-0.005, 0.005, 50), rng.uniform(-0.01, 0.01, 50)])
    r = clearance_shift(pts, field, tolerance=0.002, max_shift=0.02)
    assert r.ok
    assert r.depth_before == pytest.approx(0.008, abs=0.0015)
    assert r.shift[0] == pytest.approx(0.006, abs=0.0015)  # 8 mm deep, 2 mm allowed
    assert np.abs(r.shift[1:]).max() < 0.001
    assert r.depth_after <= 0.002 + 0.5e-3


def test_a_clear_set_is_not_moved_and_one_too_deep_is_refused():
    field = SignedDistanceGrid.from_surface_points(_sphere_points(0.05, 20000), voxel=0.002)
    clear = np.array([[0.07, 0.0, 0.0], [0.0, 0.08, 0.0]])
    r = clearance_shift(clear, field, tolerance=0.0, max_shift=0.02)
    assert r.ok and not r.shift.any() and r.depth_after == r.depth_before
    deep = np.array([[0.01, 0.0, 0.0]])  # 4 cm inside: more than 2 cm from clear
    r = clearance_shift(deep, field, tolerance=0.0, max_shift=0.02)
    assert not r.ok and r.depth_before > 0.035


def test_bad_input_gets_a_one_line_error():
    with pytest.raises(InputError, match="empty"):
        SignedDistanceGrid.from_surface_points(np.zeros((0, 3)))
    with pytest.raises(InputError, match="NaN"):
        SignedDistanceGrid.from_surface_points(np.full((10, 3), np.nan))
    with pytest.raises(InputError, match="millimetres"):
        SignedDistanceGrid.from_surface_points(_sphere_points(50.0, 100))
    with pytest.raises(InputError, match="voxel"):
        SignedDistanceGrid.from_surface_points(_sphere_points(0.05, 100), voxel=0.0)
