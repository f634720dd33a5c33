"""Cloud and mesh files: round trips, the real drills, and one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.fileio import load_arrays, save_arrays
from catgrasp_drake.core.validation import as_points
from catgrasp_drake.data.cloud_io import read_point_cloud, write_point_cloud
from catgrasp_drake.data.meshes import read_mesh
from catgrasp_drake.errors import InputError, ModelFileError


@pytest.mark.parametrize("suffix", [".pcd", ".ply", ".npy"])
def test_cloud_round_trip(tmp_path, suffix):
    pts = np.random.default_rng(0).uniform(-0.1, 0.1, size=(500, 3))
    path = tmp_path / f"c{suffix}"
    write_point_cloud(path, pts)
    # .pcd stores float32 (1e-8 m resolution at these sizes); .ply and .npy are exact
    tol = 1e-7 if suffix == ".pcd" else 0.0
    assert np.allclose(read_point_cloud(path), pts, atol=tol, rtol=0)
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary file left behind


def test_real_drills_load_in_metres_in_the_canonical_frame(ais_drill_paths):
    assert len(ais_drill_paths) == 11
    for path in ais_drill_paths:
        pts = read_point_cloud(path)
        assert 359 <= len(pts) <= 542
        ext = pts.max(0) - pts.min(0)
        assert 0.04 < ext[0] < 0.09 and 0.12 < ext[1] < 0.25 and 0.12 < ext[2] < 0.28
        assert abs(pts[:, 2].min()) < 0.012  # battery base on z = 0


def test_cloud_errors_are_one_line(tmp_path):
    cases = []
    with pytest.raises(ModelFileError, match="not found") as e:
        read_point_cloud(tmp_path / "missing.pcd")
    cases.append(e)
    (tmp_path / "empty.pcd").write_bytes(b"")
    with pytest.raises(InputError, match="empty") as e:
        read_point_cloud(tmp_path / "empty.pcd")
    cases.append(e)
    (tmp_path / "junk.ply").write_bytes(b"this is not a ply file\n" * 10)
    with pytest.raises(InputError, match="no points") as e:
        read_point_cloud(tmp_path / "junk.ply")
    cases.append(e)
    np.save(tmp_path / "nan.npy", np.array([[0.0, 0, 0], [np.nan, 0, 0]]))
    with pytest.raises(InputError, match="NaN") as e:
        read_point_cloud(tmp_path / "nan.npy")
    cases.append(e)
    np.save(tmp_path / "mm.npy", np.random.default_rng(0).uniform(0, 200, (50, 3)))
    with pytest.raises(InputError, match="millimetres") as e:
        read_point_cloud(tmp_path / "mm.npy")
    cases.append(e)
    with pytest.raises(InputError, match="unsupported") as e:
        read_point_cloud(tmp_path / "x.xyz")
    cases.append(e)
    np.save(tmp_path / "flat.npy", np.zeros((5, 2)))
    with pytest.raises(InputError, match=r"shape \(N, 3\)") as e:
        read_point_cloud(tmp_path / "flat.npy")
    cases.append(e)
    for e in cases:
        assert "\n" not in str(e.value)


def test_as_points_rejects_bad_input():
    with pytest.raises(InputError, match="empty"):
        as_points(np.zeros((0, 3)))
    with pytest.raises(InputError, match="at least 3"):
        as_points(np.zeros((2, 3)), min_points=3)
    with pytest.raises(InputError, match="numeric"):
        as_points([["a", "b", "c"]])


def test_mesh_errors(tmp_path):
    with pytest.raises(ModelFileError, match="not found"):
        read_mesh(tmp_path / "nope.obj")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nthis is garbage\n")
    with pytest.raises(ModelFileError):
        read_mesh(tmp_path / "bad.obj")
    import trimesh

    box = trimesh.creation.box((1.0, 1.0, 1.0))
    big = box.copy()
    big.apply_scale(100.0)
    big.export(tmp_path / "mm.obj")
    with pytest.raises(InputError, match="millimetres"):
        read_mesh(tmp_path / "mm.obj")
    small = trimesh.creation.box((0.1, 0.1, 0.1))
    open_box = trimesh.Trimesh(small.vertices, small.faces[:-2])
    open_box.export(tmp_path / "open.obj")
    with pytest.raises(InputError, match="not watertight"):
        read_mesh(tmp_path / "open.obj", require_watertight=True)


def test_versioned_array_files(tmp_path):
    path = tmp_path / "m.npz"
    save_arrays(path, {"a": np.arange(5.0)}, kind="test.kind", version=2, meta={"q": 3})
    arrays, meta = load_arrays(path, kind="test.kind", version=2)
    assert np.array_equal(arrays["a"], np.arange(5.0)) and meta == {"q": 3}
    with pytest.raises(ModelFileError, match="format version 2"):
        load_arrays(path, kind="test.kind", version=3)
    with pytest.raises(ModelFileError, match="expected 'other'"):
        load_arrays(path, kind="other", version=2)
    good = path.read_bytes()
    for pos in range(0, len(good), 7):  # flip bytes all over the file: an error or the same data, never other data
        data = bytearray(good)
        data[pos] ^= 0xFF
        path.write_bytes(bytes(data))
        try:
            arrays, _ = load_arrays(path, kind="test.kind", version=2)
        except ModelFileError as e:
            assert "\n" not in str(e)
        else:
            assert np.array_equal(arrays["a"], np.arange(5.0))
    path.write_bytes(good[: len(good) // 2])
    with pytest.raises(ModelFileError):
        load_arrays(path, kind="test.kind", version=2)
    path.write_bytes(b"")
    with pytest.raises(ModelFileError, match="not a readable"):
        load_arrays(path, kind="test.kind", version=2)
    with pytest.raises(ValueError, match="dtype object"):
        save_arrays(tmp_path / "o.npz", {"o": np.array([{}], dtype=object)}, kind="k", version=1)
