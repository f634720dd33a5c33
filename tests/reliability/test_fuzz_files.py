"""Fuzzing the file readers: point clouds (data/cloud_io.py), meshes (data/meshes.py) and the
trained category models (category_model.py), with missing, empty, truncated, corrupted, forged
and wrong-kind files."""

from __future__ import annotations

import io
import shutil
import warnings

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.data.cloud_io import read_point_cloud, write_point_cloud
from catgrasp_drake.data.meshes import read_mesh

from .conftest import TRAINED
from .harness import attempt, finite_array
from .strategies import CORRUPTIONS, MUST_REJECT, clouds, corrupt_bytes, npz_with_header, pickled_npz, scaled, seeds

# ----------------------------------------------------------------------------- point cloud files

_ASCII_PCD = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
              "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA ascii\n")
_ASCII_PLY = ("ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
              "end_header\n")


def _npy_bytes(a, **kw) -> bytes:
    buf = io.BytesIO()
    np.save(buf, a, **kw)
    return buf.getvalue()


@st.composite
def cloud_files(draw, tmp):
    """``(label, path)``: a cloud file in ``tmp``, valid or damaged."""
    rng = np.random.default_rng(draw(seeds))
    suffix = draw(st.sampled_from([".pcd", ".ply", ".npy"]))
    cl, pts = draw(clouds(min_n=1, max_n=200, valid_weight=6,
                          exclude=("wrong_dtype", "none", "wrong_shape", "empty", "nested_list", "huge")))
    pts = np.asarray(pts, dtype=np.float64)
    path = tmp / f"cloud{draw(seeds)}{suffix}"
    how = draw(st.sampled_from(["clean"] * 4 + list(CORRUPTIONS) + [
        "lying_header", "ascii_short", "missing", "directory", "wrong_suffix", "upper_suffix", "npy_pickle",
        "npy_complex", "npy_structured", "npy_strings", "npy_2d_wrong", "npy_scalar", "npy_big_endian",
        "npy_fortran", "npy_float16", "ascii_nan", "path_bytes", "path_none", "path_int"]))
    clean = how in ("clean", "upper_suffix", "npy_big_endian", "npy_fortran", "npy_float16", "path_bytes")
    undetectable = how in ("flipped", "zeroed")  # damaged data (no checksum in these formats) may read as a cloud
    if how in ("clean", "upper_suffix", "path_bytes") or how in CORRUPTIONS:
        if np.all(np.isfinite(pts)) and np.abs(pts).max() <= 1e6:
            write_point_cloud(path, pts)
        else:
            path.write_bytes(_npy_bytes(pts) if suffix == ".npy" else b"")
        if how in CORRUPTIONS:
            path.write_bytes(corrupt_bytes(path.read_bytes(), rng, how))
        if how == "upper_suffix":
            path = path.rename(path.with_suffix(suffix.upper()))
        if how == "path_bytes":
            return f"{suffix}:path_bytes", bytes(str(path), "utf-8"), cl, clean
        return f"{suffix}:{how}", path, cl, clean or (None if undetectable else False)
    if how == "lying_header":
        n = int(10 ** rng.integers(6, 13))
        head = {".pcd": _ASCII_PCD.replace("DATA ascii", "DATA binary"), ".ply": _ASCII_PLY.replace(
            "ascii", "binary_little_endian"), ".npy": None}[suffix]
        data = (head.format(n=n).encode() + pts.astype(np.float32).tobytes() if head else
                _npy_bytes(pts).replace(f"({len(pts)}, 3)".encode(), f"({n}, 3)".encode().ljust(
                    len(f"({len(pts)}, 3)"))[:len(f"({len(pts)}, 3)")]))
        path.write_bytes(data)
    elif how == "ascii_short":
        body = "".join(f"{x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in pts[: max(0, len(pts) - 1)])
        head = _ASCII_PLY if suffix == ".ply" else _ASCII_PCD
        path = path.with_suffix(".ply" if suffix == ".ply" else ".pcd")
        path.write_text(head.format(n=len(pts) + int(rng.integers(1, 10**8))) + body)
    elif how == "ascii_nan":
        head = _ASCII_PLY if suffix == ".ply" else _ASCII_PCD
        path = path.with_suffix(".ply" if suffix == ".ply" else ".pcd")
        path.write_text(head.format(n=3) + "0 0 0\nnan 0.1 0\n0.1 0.1 inf\n")
    elif how == "missing":
        pass
    elif how == "directory":
        path.mkdir()
    elif how == "wrong_suffix":
        path = path.with_suffix(draw(st.sampled_from([".xyz", ".txt", "", ".npz", ".obj"])))
        path.write_bytes(b"0 0 0\n")
    elif how.startswith("npy_"):
        path = path.with_suffix(".npy")
        a = {"npy_pickle": None, "npy_complex": pts + 1j,
             "npy_structured": np.zeros(5, dtype=[("x", "f8"), ("y", "f8")]),
             "npy_strings": np.array([["a", "b", "c"]]), "npy_2d_wrong": pts[:, :2], "npy_scalar": np.float64(1.0),
             "npy_big_endian": pts.astype(">f8"), "npy_fortran": np.asfortranarray(pts),
             "npy_float16": pts.astype(np.float16)}[how]
        if a is None:
            path.write_bytes(_npy_bytes(np.array([{"x": 1}], dtype=object), allow_pickle=True))
        else:
            path.write_bytes(_npy_bytes(a))
    elif how == "path_none":
        return "path:none", None, cl, False
    elif how == "path_int":
        return "path:int", 12345, cl, False
    return f"{suffix}:{how}", path, cl, clean


@scaled(120)
@given(data=st.data())
def test_read_point_cloud(tmp_path_factory, data):
    tmp = tmp_path_factory.mktemp("clouds")
    label, path, cl, clean = data.draw(cloud_files(tmp))
    # a clean file of a cloud that the in-memory validation would refuse must be refused from disk too
    expect = "reject" if clean is False or (clean and cl in MUST_REJECT) else None
    attempt("cloud_io.read_point_cloud", f"{label} cloud:{cl}", read_point_cloud, path,
            check=finite_array((None, 3)), expect=expect)
    shutil.rmtree(tmp, ignore_errors=True)


@scaled(60)
@given(points=clouds(min_n=1, max_n=100), suffix=st.sampled_from([".pcd", ".ply", ".npy", ".xyz", ""]))
def test_write_point_cloud(tmp_path_factory, points, suffix):
    tmp = tmp_path_factory.mktemp("write")
    path = tmp / f"out{suffix}"
    expect = "reject" if points[0] in MUST_REJECT or suffix in (".xyz", "") else None
    out = attempt("cloud_io.write_point_cloud", f"{suffix or 'no_suffix'} cloud:{points[0]}", write_point_cloud,
                  path, points[1], expect=expect)
    if not out.rejected:  # what was written reads back (float32 .pcd: 1e-7 relative)
        back = read_point_cloud(path, check_units=False)
        np.testing.assert_allclose(back, np.asarray(points[1], dtype=float), rtol=1e-6, atol=1e-7)
    assert [p.name for p in tmp.iterdir()] in ([], [path.name])  # never a temporary file left behind
    shutil.rmtree(tmp, ignore_errors=True)


# ----------------------------------------------------------------------------- meshes

def _box(size=0.1):
    return trimesh.creation.box(extents=(size, 0.6 * size, 1.5 * size))


@st.composite
def mesh_files(draw, tmp):
    rng = np.random.default_rng(draw(seeds))
    suffix = draw(st.sampled_from([".obj", ".obj", ".stl", ".ply"]))
    path = tmp / f"mesh{draw(seeds)}{suffix}"
    how = draw(st.sampled_from(["watertight"] * 3 + list(CORRUPTIONS) + [
        "non_watertight", "self_intersecting", "degenerate_faces", "no_faces", "nan_vertex", "millimetres",
        "huge", "bad_face_index", "single_triangle", "inverted", "duplicate_vertices", "missing", "directory",
        "wrong_suffix", "flat"]))
    watertight = how in ("watertight", "self_intersecting", "inverted", "duplicate_vertices")
    mesh = _box(float(rng.uniform(0.03, 0.3)))
    if how == "non_watertight":
        mesh = trimesh.Trimesh(mesh.vertices, mesh.faces[: -int(rng.integers(1, 4))], process=False)
    elif how == "self_intersecting":
        other = mesh.copy()
        other.apply_translation(0.3 * mesh.extents)
        mesh = trimesh.util.concatenate([mesh, other])
    elif how == "degenerate_faces":
        faces = mesh.faces.copy()
        faces[0] = [0, 0, 1]
        mesh = trimesh.Trimesh(mesh.vertices, faces, process=False)
    elif how == "millimetres":
        mesh.apply_scale(1000.0)
    elif how == "huge":
        mesh.apply_scale(1e200)
    elif how == "inverted":
        mesh.invert()
    elif how == "single_triangle":
        mesh = trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], [[0, 1, 2]], process=False)
    elif how == "flat":
        mesh = trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0.1, 0.1, 0]], [[0, 1, 2], [1, 3, 2]],
                               process=False)
    if how in ("no_faces", "nan_vertex", "bad_face_index", "duplicate_vertices"):
        path = path.with_suffix(".obj")
        v = "".join(f"v {x} {y} {z}\n" for x, y, z in mesh.vertices)
        f = "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in mesh.faces)
        if how == "no_faces":
            f = ""
        elif how == "nan_vertex":
            v = "v nan 0 0\n" + v
            f = "".join(f"f {a + 2} {b + 2} {c + 2}\n" for a, b, c in mesh.faces) + "f 1 2 3\n"
        elif how == "bad_face_index":
            f += f"f 1 2 {len(mesh.vertices) + 1000}\n"
        elif how == "duplicate_vertices":
            v = v + v
        path.write_text(v + f)
    elif how == "missing":
        pass
    elif how == "directory":
        path.mkdir()
    elif how == "wrong_suffix":
        path = path.with_suffix(".xyz")
        path.write_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    else:
        exported = mesh.export(file_type=path.suffix[1:])
        path.write_bytes(exported.encode() if isinstance(exported, str) else exported)
        if how in CORRUPTIONS:
            path.write_bytes(corrupt_bytes(path.read_bytes(), rng, how))
    return f"{path.suffix or 'none'}:{how}", path, watertight


@scaled(80)
@given(data=st.data(), require=st.booleans())
def test_read_mesh(tmp_path_factory, data, require):
    tmp = tmp_path_factory.mktemp("meshes")
    with warnings.catch_warnings():  # building the 1e200-m and degenerate meshes overflows: that is the point
        warnings.simplefilter("ignore", RuntimeWarning)
        label, path, watertight = data.draw(mesh_files(tmp))

    def check(mesh):
        assert isinstance(mesh, trimesh.Trimesh) and len(mesh.faces) > 0
        finite_array((None, 3))(np.asarray(mesh.vertices))
        assert float(np.linalg.norm(mesh.extents)) <= 3.0
        if require:
            assert mesh.is_watertight

    must_reject = any(k in label for k in (":missing", ":directory", ":no_faces", ":millimetres", ":huge",
                                           ":empty"))
    expect = "reject" if must_reject or (require and label.endswith(":non_watertight")) else None
    words = ("watertight",) if require and label.endswith(":non_watertight") else ()
    attempt("meshes.read_mesh", f"{label} require_watertight={require}", read_mesh, path,
            require_watertight=require, check=check, expect=expect, words=words)
    shutil.rmtree(tmp, ignore_errors=True)


# ----------------------------------------------------------------------------- category model files

@pytest.fixture(scope="module")
def model_bytes():
    missing = [c for c, p in TRAINED.items() if not p.is_file()]
    if missing:
        pytest.skip(f"trained models missing: {missing}")
    return {c: p.read_bytes() for c, p in TRAINED.items()}


def _forge_model(raw: bytes, how: str, rng) -> bytes:
    """A model file damaged at the array/header level with a correct checksum (only validation can catch it)."""
    import json

    from catgrasp_drake.core.fileio import _arrays_checksum

    with np.load(io.BytesIO(raw)) as z:
        arrays = {k: z[k] for k in z.files}
    header = json.loads(arrays.pop("__header__").tobytes().decode())
    meta = header["meta"]
    if how == "other_version":
        header["format_version"] = int(rng.choice([0, 2, 7]))
    elif how == "other_kind":
        header["format"] = "catgrasp.shape_space"
    elif how == "missing_array":
        arrays.pop(str(rng.choice(sorted(arrays))))
    elif how == "nan_regressor":
        arrays["regressor/coef"] = arrays["regressor/coef"].copy()
        arrays["regressor/coef"][0, 0] = np.nan
    elif how == "wrong_regressor_shape":
        arrays["regressor/coef"] = arrays["regressor/coef"][:, :-1]
    elif how == "template_garbage":
        meta["template"] = rng.choice(["nope", 5, None, {"poses": "x", "postures": {}, "frame": "object"}]).item() \
            if False else {"poses": [[1, 2]], "postures": {}, "frame": "object"}
    elif how == "template_missing":
        meta.pop("template")
    elif how == "meta_not_dict":
        header["meta"] = ["not", "a", "dict"]
    elif how == "instances_int":
        meta["instances"] = 5
    elif how == "anchor_nan":
        meta["grasp_anchor_H"] = [float("nan"), 0.0, 0.0]
    elif how == "radius_string":
        meta["grasp_rotation_radius"] = "wide"
    elif how == "category_list":
        meta["category"] = ["drill"]
    elif how == "training_groups_short":
        if "training/groups" in arrays:
            arrays["training/groups"] = arrays["training/groups"][:-1]
    elif how == "alpha_nan":
        meta["regressor_alpha"] = "NaN"
        if isinstance(meta.get("regressor"), dict) and "alpha" in meta["regressor"]:
            meta["regressor"]["alpha"] = "NaN"
    header["sha256"] = _arrays_checksum(arrays)
    return npz_with_header(arrays, header)


MODEL_FORGERIES = ("other_version", "other_kind", "missing_array", "nan_regressor", "wrong_regressor_shape",
                   "template_garbage", "template_missing", "meta_not_dict", "instances_int", "anchor_nan",
                   "radius_string", "category_list", "training_groups_short", "alpha_nan")


@scaled(80)
@given(category=st.sampled_from(["drill", "spray_bottle", "mug"]),
       how=st.sampled_from(("valid", "valid", "other_category", "unknown_category", "missing", "directory",
                            "no_header_zip", "pickled", "npy_instead") + CORRUPTIONS + MODEL_FORGERIES),
       seed=seeds)
def test_category_model_load(model_bytes, tmp_path_factory, category, how, seed):
    rng = np.random.default_rng(seed)
    path = tmp_path_factory.mktemp("model") / f"{category}.npz"
    expect_category = None
    raw = model_bytes[category]
    if how in ("valid", "other_category", "unknown_category"):
        path.write_bytes(raw)
        expect_category = {"valid": category, "other_category": "mug" if category != "mug" else "drill",
                           "unknown_category": "teapot"}[how]
    elif how in CORRUPTIONS:
        path.write_bytes(corrupt_bytes(raw, rng, how))
    elif how in MODEL_FORGERIES:
        path.write_bytes(_forge_model(raw, how, rng))
    elif how == "directory":
        path.mkdir()
    elif how == "no_header_zip":
        path.write_bytes(npz_with_header({"a": np.zeros(3)}, {}).replace(b"__header__", b"__hidden__"))
    elif how == "pickled":
        path.write_bytes(pickled_npz())
    elif how == "npy_instead":
        path.write_bytes(_npy_bytes(np.zeros((3, 3))))

    def check(m):
        assert isinstance(m, CategoryModel) and m.category == category
        m.transfer(np.zeros(m.space.q))

    expect = "result" if how == "valid" else ("reject" if how not in ("flipped", "zeroed") else None)
    words = {"other_category": ("model", "not"), "unknown_category": ("model", "not"),
             "other_version": ("version",), "missing": ("not found",)}.get(how, ())
    attempt("CategoryModel.load", f"model:{how}", CategoryModel.load, path, category=expect_category,
            check=check, expect=expect, words=words)
