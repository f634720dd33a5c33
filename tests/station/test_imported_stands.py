"""An imported scan with a rounded underside stands on the table once its base is flattened (and falls without)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from catgrasp_drake.data.importer import import_mesh
from catgrasp_drake.data.meshes import flatten_base

from .standing import tilt_after


def _domed_bottle() -> trimesh.Trimesh:
    """A 26 cm bottle, 8 cm wide, whose underside is a dome like a scan's reconstructed bottom (15 mm sag:
    a radius of curvature of about 5 cm under a centre of mass 14 cm high)."""
    body = trimesh.creation.cylinder(radius=0.04, height=0.26, sections=64)
    body.apply_translation([0.0, 0.0, 0.13 + 0.015])
    dome = trimesh.creation.icosphere(subdivisions=5, radius=1.0)
    dome.apply_scale([0.0399, 0.0399, 0.015])
    dome.apply_translation([0.0, 0.0, 0.015])
    return trimesh.boolean.union([body, dome], engine="manifold")


def test_flatten_base_cuts_a_flat_face_at_the_old_lowest_height():
    m = _domed_bottle()
    flat, done = flatten_base(m, 0.003)
    assert done and flat.is_watertight
    assert flat.bounds[0][2] == pytest.approx(m.bounds[0][2], abs=1e-6)
    assert flat.bounds[1][2] == pytest.approx(m.bounds[1][2] - 0.003, abs=1e-6)
    base = flat.vertices[np.abs(flat.vertices[:, 2] - flat.bounds[0][2]) < 1e-6]
    radius = np.hypot(base[:, 0], base[:, 1]).max()
    assert 0.015 < radius < 0.03  # a flat disc where the dome was cut (r = 4 cm * sqrt(1 - (1 - 0.2)^2))
    same, done = flatten_base(m, 0.0)
    assert same is m and not done


@pytest.mark.slow
def test_a_domed_scan_falls_over_by_itself_and_stands_once_imported_with_a_flat_base(tmp_path):
    m = _domed_bottle()
    m.apply_translation([0.0, 0.0, -m.bounds[0][2]])
    m.apply_transform(trimesh.transformations.rotation_matrix(np.radians(1.0), [1, 0, 0]))  # leaning by 1 deg
    regions = {"trigger": {"center": [0.0, 0.04, 0.23], "half_extents": [0.01, 0.01, 0.01], "grown_by": 0.003}}
    kw = dict(transform="0 0 0 0 0 0", regions=regions, mass_kg=1.0)
    domed = import_mesh(m, "spray_bottle", "domed", out=tmp_path / "domed", base_flatten_m=0.0, **kw)
    flat = import_mesh(m, "spray_bottle", "flat", out=tmp_path / "flat", **kw)
    assert domed.record["base_flattened_m"] == 0.0 and flat.record["base_flattened_m"] == 0.003
    assert flat.regions["trigger"]["center"][2] == pytest.approx(0.23 - 0.003, abs=5e-4)  # moved down with the cut
    assert tilt_after("spray_bottle", "domed", tmp_path / "domed", 2.5) > 30.0  # rocks on its dome and falls
    assert tilt_after("spray_bottle", "flat", tmp_path / "flat", 2.5) < 2.0


def test_a_scan_in_two_stacked_pieces_is_bridged_into_one_solid():
    from catgrasp_drake.data.meshes import bridge_gaps

    body = trimesh.creation.cylinder(radius=0.04, height=0.18, sections=48)
    body.apply_translation([0.0, 0.0, 0.09])
    head = trimesh.creation.box([0.03, 0.08, 0.04])
    head.apply_translation([0.0, 0.01, 0.18 + 0.015 + 0.02])  # 15 mm above the body: the missing neck
    joined, bridges = bridge_gaps(trimesh.util.concatenate([body, head]))
    assert bridges == 1 and joined.is_watertight and len(joined.split(only_watertight=False)) == 1
    assert joined.volume > body.volume + head.volume  # the bridge adds the neck
    # at mid-gap there is solid now, no wider than the pieces next to it
    section = joined.section(plane_origin=[0.0, 0.0, 0.1875], plane_normal=[0.0, 0.0, 1.0])
    assert section is not None
    lo, hi = section.bounds
    assert np.all(lo[:2] >= [-0.04 - 1e-6, -0.04 - 1e-6]) and np.all(hi[:2] <= [0.04 + 1e-6, 0.05 + 1e-6])
    side_by_side = trimesh.util.concatenate([body, body.copy().apply_translation([0.2, 0.0, 0.0])])
    assert bridge_gaps(side_by_side)[1] == 0
