"""Fuzzing mesh -> point cloud (data/pointclouds.py) and the grasp transfer of a trained model
(category_model.py: CategoryModel.transfer)."""

from __future__ import annotations

import warnings

import numpy as np
import trimesh
from hypothesis import given
from hypothesis import strategies as st

from catgrasp_drake.data.pointclouds import (
    PinholeCamera,
    camera_on_sphere,
    full_cloud,
    partial_cloud,
    surface_distance,
    voxel_downsample,
)
from catgrasp_drake.grasping.motion import GraspMotion

from .harness import attempt, finite_array, rigid_poses
from .strategies import BAD_NUMBERS, choice, clouds, latents, number, options, scaled, seeds


@scaled(60)
@given(points=clouds(min_n=1, max_n=300, valid_weight=6),
       voxel=st.one_of(st.floats(1e-4, 0.1).map(lambda v: ("valid", v)), st.sampled_from(BAD_NUMBERS)))
def test_voxel_downsample(points, voxel):
    def check(v):
        finite_array((None, 3))(v)
        assert 1 <= len(v) <= len(points[1])

    attempt("pointclouds.voxel_downsample", f"points:{points[0]} voxel:{voxel[0]}", voxel_downsample, points[1],
            voxel[1], check=check)


@st.composite
def _meshes(draw):
    """``(label, mesh)``: watertight, open, self-intersecting, degenerate, flat, tiny, huge, not-a-mesh."""
    rng = np.random.default_rng(draw(seeds))
    box = trimesh.creation.box(extents=rng.uniform(0.03, 0.2, 3))
    kind = draw(st.sampled_from(["watertight"] * 3 + ["non_watertight", "self_intersecting", "degenerate", "flat",
                                                      "tiny", "millimetres", "empty", "not_a_mesh", "far_1km",
                                                      "nan_vertex"]))
    if kind == "non_watertight":
        return kind, trimesh.Trimesh(box.vertices, box.faces[:-2], process=False)
    if kind == "self_intersecting":
        other = box.copy()
        other.apply_translation(0.4 * box.extents)
        return kind, trimesh.util.concatenate([box, other])
    if kind == "degenerate":
        return kind, trimesh.Trimesh(np.zeros((3, 3)), [[0, 1, 2]], process=False)
    if kind == "flat":
        return kind, trimesh.Trimesh([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], [[0, 1, 2]], process=False)
    if kind == "tiny":
        box.apply_scale(1e-9)
    elif kind == "millimetres":
        box.apply_scale(1000.0)
    elif kind == "empty":
        return kind, trimesh.Trimesh()
    elif kind == "not_a_mesh":
        return kind, draw(st.sampled_from([None, "box.obj", np.zeros((4, 3))]))
    elif kind == "far_1km":
        box.apply_translation((1000.0, 0.0, 0.0))
    elif kind == "nan_vertex":
        v = box.vertices.copy()
        v[0, 0] = np.nan
        return kind, trimesh.Trimesh(v, box.faces, process=False)
    return kind, box


_cams = options({
    "eye": choice([(0.5, 0.0, 0.3), (0.0, -0.4, 0.1)], [("nan", (np.nan, 0, 0)), ("string", "front"),
                                                          ("wrong_shape", (1.0, 0.0)), ("huge", (1e300, 0, 0))]),
    "target": choice([(0.0, 0.0, 0.0), (0.0, 0.0, 0.05)], [("same_as_eye", "same"), ("inf", (np.inf, 0, 0))]),
    "up": choice([(0.0, 0.0, 1.0), (0.0, 1.0, 0.0)], [("zero", (0.0, 0.0, 0.0)), ("nan", (np.nan, 0, 1))]),
    "width": number(st.integers(8, 64)),
    "height": number(st.integers(8, 64)),
    "fov_y_deg": number(st.floats(10.0, 120.0)),
})


@scaled(60)
@given(mesh=_meshes(), cam=_cams,
       opts=options({"voxel": number(st.floats(0.002, 0.05)), "depth_noise_std": number(st.floats(0.0, 0.003)),
                     "rng": choice([np.random.default_rng(0)], [("none", None), ("string", "seed")])}))
def test_partial_cloud(mesh, cam, opts):
    kw = {"eye": (0.5, 0.0, 0.3), "target": (0.0, 0.0, 0.0), "width": 24, "height": 16}
    kw.update({k: v[1] for k, v in cam.items()})
    if isinstance(kw["target"], str):
        kw["target"] = kw["eye"]
    label = f"mesh:{mesh[0]}" + "".join(f" {k}={v[0]}" for k, v in {**cam, **opts}.items() if v[0] != "valid")
    out = attempt("pointclouds.PinholeCamera", label, PinholeCamera, **kw)
    camera = out.value
    if camera is not None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # building the mesh is not under test
            m = mesh[1]
        attempt("pointclouds.partial_cloud", label, partial_cloud, m, camera,
                check=finite_array((None, 3)), **{k: v[1] for k, v in opts.items()})


@scaled(25)
@given(mesh=_meshes(), opts=options({
    "voxel": number(st.floats(0.005, 0.05)),
    "resolution": choice([16, 24], [("zero", 0), ("negative", -5), ("string", "hi"), ("huge", 10**9),
                                    ("fraction", 20.5)]),
    "subdivisions": choice([0, 1], [("negative", -1), ("huge", 50), ("nan", np.nan)]),
}, max_valid=3))
def test_full_cloud_and_surface_distance(mesh, opts):
    opts.setdefault("resolution", ("valid", 16))
    opts.setdefault("subdivisions", ("valid", 0))
    label = f"mesh:{mesh[0]}" + "".join(f" {k}={v[0]}" for k, v in opts.items() if v[0] != "valid")
    out = attempt("pointclouds.full_cloud", label, full_cloud, mesh[1], check=finite_array((None, 3)),
                  **{k: v[1] for k, v in opts.items()})
    pts = out.value if out.value is not None else np.zeros((5, 3))
    attempt("pointclouds.surface_distance", f"mesh:{mesh[0]}", surface_distance, mesh[1], pts,
            check=finite_array((len(pts),)))


@scaled(30)
@given(target=st.sampled_from([("valid", (0, 0, 0)), ("nan", (np.nan, 0, 0)), ("string", "o")]),
       distance=st.one_of(st.floats(0.1, 2.0).map(lambda v: ("valid", v)), st.sampled_from(BAD_NUMBERS)),
       angle=st.one_of(st.floats(-3.0, 3.0).map(lambda v: ("valid", v)), st.sampled_from(BAD_NUMBERS)))
def test_camera_on_sphere(target, distance, angle):
    attempt("pointclouds.camera_on_sphere", f"target:{target[0]} distance:{distance[0]} angle:{angle[0]}",
            camera_on_sphere, target[1], distance[1], angle[1], 0.3, width=8, height=8,
            check=lambda c: finite_array((8 * 8, 3))(c.rays()[1]))


# ----------------------------------------------------------------------------- grasp transfer

@scaled(60)
@given(data=st.data(), category=st.sampled_from(["drill", "spray_bottle", "mug"]))
def test_category_model_transfer(trained_models, data, category):
    model = trained_models[category]
    xl, x = data.draw(latents(model.space.q))
    rng = np.random.default_rng(data.draw(seeds))
    from catgrasp_drake.core.rotations import sample_rotations_within

    R_ok = sample_rotations_within(rng, 1, np.pi)[0]
    opts = data.draw(options({
        "R": choice([R_ok, np.eye(3)], [("nan", np.full((3, 3), np.nan)), ("wrong_shape", np.eye(4)),
                                        ("not_rotation", 2 * np.eye(3)), ("reflection", -np.eye(3)),
                                        ("string", "identity")]),
        "t": choice([np.zeros(3), np.array([0.5, 0.1, 0.02])],
                    [("nan", np.full(3, np.nan)), ("wrong_shape", np.zeros(2)), ("far_1km", np.full(3, 1e3)),
                     ("huge", np.full(3, 1e300)), ("string", "origin")]),
        "s": number(st.floats(0.5, 2.0)),
        "frame": choice(["world", "object"], [("string", "camera"), ("none", None)]),
    }))
    label = f"x:{xl}" + "".join(f" {k}={v[0]}" for k, v in opts.items() if v[0] != "valid")

    def check(m):
        assert isinstance(m, GraspMotion)
        rigid_poses(m.poses)

    attempt("CategoryModel.transfer", label, model.transfer, x, check=check,
            **{k: v[1] for k, v in opts.items()})
