"""Fuzzing the Drake systems through their input ports (FixValue on a context, Eval of an output
port) and the pure function behind the estimator (systems/shape_estimator.py, grasp_regressor.py,
object_cloud.py)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.perception import BaseField, Fields, PointCloud
from pydrake.systems.analysis import Simulator
from pydrake.systems.sensors import CameraInfo, ImageDepth32F, ImageLabel16I

from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.perception.object_cloud import CloudCropVoxel, LabelDepthMask, ObjectCloudSystem
from catgrasp_drake.systems.grasp_regressor import GraspRegressor, predict_motion_W
from catgrasp_drake.systems.shape_estimator import LatentShapeEstimator, ShapeEstimate, estimate_on_table

from .harness import attempt, check_message, finite_array, rigid_poses
from .strategies import BAD_NUMBERS, choice, clouds, latents, number, options, scaled, seeds

X_WT = np.eye(4)
X_WT[:3, 3] = (0.55, 0.0, 0.02)


def _raw_cloud(points) -> PointCloud:
    """A Drake PointCloud holding exactly these values (float32; NaN, inf, huge included)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    cloud = PointCloud(len(p), Fields(BaseField.kXYZs))
    with np.errstate(over="ignore", invalid="ignore"):
        cloud.mutable_xyzs()[:] = p.T.astype(np.float32)
    return cloud


_X_WTs = st.sampled_from([("valid", X_WT), ("nan", np.full((4, 4), np.nan)), ("wrong_shape", np.eye(3)),
                          ("string", "table"), ("scaled", 2 * np.eye(4)),
                          ("far_1km", np.diag([1.0, 1, 1, 1]) + np.pad(np.full((3, 1), 1e3), ((0, 1), (3, 0)))),
                          ("rigid_transform", RigidTransform(X_WT)),
                          ("huge", np.pad(np.eye(3), ((0, 1), (0, 1))) + np.diag([0, 0, 0, 1.0])
                           + 1e300 * np.eye(4, k=3))])


def _check_estimate(q, n_points):
    def check(e):
        assert isinstance(e, ShapeEstimate)
        assert isinstance(e.status, str) and e.status and "\n" not in e.status
        if e.ok:
            finite_array((q,))(e.x)
            rigid_poses(e.X_WO)
            assert np.isfinite(e.scale) and e.scale > 0
            finite_array((n_points, 3))(e.completed_W)
            assert 0.0 <= e.confidence <= 1.0 and np.isfinite(e.energy)
        else:
            assert e.confidence == 0.0 and np.all(e.x == 0)
    return check


def _object_points(space, rng, kind_cloud):
    """World points of the object on the table (a deformed, moved shape) or a bad cloud."""
    label, pts = kind_cloud
    if label == "valid":
        yaw = rng.uniform(0, 2 * np.pi)
        c, s = np.cos(yaw), np.sin(yaw)
        R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        pts = space.deform(rng.normal(size=space.q) * 0.5) @ R.T + X_WT[:3, 3] + [0.05, -0.03, 0.0]
    return label, pts


@scaled(60)
@given(data=st.data())
def test_estimate_on_table(small_space, data):
    rng = np.random.default_rng(data.draw(seeds))
    cl = _object_points(small_space, rng, data.draw(clouds(min_n=1, max_n=150, valid_weight=10)))
    xl, X = data.draw(_X_WTs)
    opts = data.draw(options({
        "camera_W": choice([None, (0.55, -0.6, 0.4)], [("nan", (np.nan, 0, 0)), ("string", "cam"),
                                                       ("wrong_shape", (1.0, 2.0))]),
        "yaw_candidates": choice([None, 2], [("zero", 0), ("string", "all")]),
        "max_iter": number(st.integers(1, 10)),
    }))
    opts.setdefault("yaw_candidates", ("valid", None))
    opts.setdefault("max_iter", ("valid", 10))
    label = f"p_W:{cl[0]} X_WT:{xl}" + "".join(f" {k}={v[0]}" for k, v in opts.items() if v[0] != "valid")
    attempt("shape_estimator.estimate_on_table", label, estimate_on_table, small_space, cl[1], X,
            check=_check_estimate(small_space.q, small_space.n_points), **{k: v[1] for k, v in opts.items()})


@scaled(50)
@given(data=st.data())
def test_latent_shape_estimator_ports(small_space, data):
    rng = np.random.default_rng(data.draw(seeds))
    cl = _object_points(small_space, rng, data.draw(clouds(min_n=1, max_n=150, valid_weight=10,
                                                           exclude=("wrong_dtype", "none", "wrong_shape"))))
    cam = data.draw(st.sampled_from([("none", None), ("valid", (0.55, -0.6, 0.4)), ("nan", (np.nan, 0.0, 0.0)),
                                     ("far_1km", (1000.0, 0.0, 0.0)), ("at_object", (0.55, 0.0, 0.1))]))
    xl, X = data.draw(_X_WTs)
    label = f"object_cloud_W:{cl[0]} X_WC:{cam[0]} X_WT:{xl}"
    built = attempt("LatentShapeEstimator", f"X_WT:{xl}", LatentShapeEstimator, small_space, X, yaw_candidates=None,
                    max_iter=10)
    if built.rejected:
        return
    est = built.value

    def run():
        ctx = est.CreateDefaultContext()
        est.GetInputPort("object_cloud_W").FixValue(ctx, _raw_cloud(cl[1]))
        if cam[1] is not None:
            est.GetInputPort("X_WC").FixValue(ctx, RigidTransform(RotationMatrix(), np.asarray(cam[1])))
        Simulator(est, ctx).Initialize()  # the initialization event makes the estimate
        out = {name: est.GetOutputPort(name).Eval(ctx) for name in ("x", "scale", "energy", "confidence")}
        out["X_WO"] = est.GetOutputPort("X_WO").Eval(ctx).GetAsMatrix4()
        out["completed"] = np.asarray(est.GetOutputPort("completed_cloud_W").Eval(ctx).xyzs()).T
        out["estimate"] = est.GetOutputPort("estimate").Eval(ctx)
        return out

    def check(out):
        e = out["estimate"]
        _check_estimate(small_space.q, small_space.n_points)(e)
        finite_array((small_space.q,))(out["x"])
        rigid_poses(out["X_WO"])
        assert 0.0 <= out["confidence"][0] <= 1.0
        finite_array((None, 3))(out["completed"])
        if cl[0] in ("empty", "one_point", "two_points"):
            assert not e.ok  # too few finite points: "no object in view", never an exception

    attempt("LatentShapeEstimator.ports", label, run, check=check)


@pytest.fixture(scope="module")
def drill(trained_models):
    return trained_models["drill"]


@scaled(60)
@given(data=st.data())
def test_grasp_regressor_ports(drill, data):
    q = drill.space.q
    xl, x = data.draw(latents(q).filter(lambda t: t[0] in ("valid", "zero", "large", "huge", "nan", "inf")))
    rng = np.random.default_rng(data.draw(seeds))
    Xl, X_WO = data.draw(st.sampled_from([
        ("valid", RigidTransform(RotationMatrix.MakeZRotation(rng.uniform(0, 6)), [0.6, 0.0, 0.02])),
        ("nan_translation", RigidTransform(RotationMatrix(), [np.nan, 0.0, 0.0])),
        ("nan_rotation", RigidTransform(RotationMatrix(np.full((3, 3), np.nan)), [0.6, 0.0, 0.0])),
        ("far_1km", RigidTransform(RotationMatrix(), [1000.0, 0.0, 0.0])),
        ("huge", RigidTransform(RotationMatrix(), [1e300, 0.0, 0.0])),
        ("not_rotation", RigidTransform(RotationMatrix(2.0 * np.eye(3)), [0.6, 0.0, 0.0]))]))
    sl, s = data.draw(st.one_of(st.floats(0.5, 2.0).map(lambda v: ("valid", v)), st.sampled_from(
        [b for b in BAD_NUMBERS if isinstance(b[1], float)] + [("unconnected", None)])))
    reg = GraspRegressor(drill)

    def run():
        ctx = reg.CreateDefaultContext()
        reg.GetInputPort("x").FixValue(ctx, np.asarray(x, dtype=float))
        reg.GetInputPort("X_WO").FixValue(ctx, X_WO)
        if s is not None:
            reg.GetInputPort("scale").FixValue(ctx, [s])
        return reg.GetOutputPort("grasp_motion_W").Eval(ctx)

    def check(m):
        assert isinstance(m, GraspMotion) and m.frame == "world"
        rigid_poses(m.poses)

    attempt("GraspRegressor.ports", f"x:{xl} X_WO:{Xl} scale:{sl}", run, check=check)


@scaled(40)
@given(data=st.data())
def test_predict_motion_W(drill, data):
    xl, x = data.draw(latents(drill.space.q))
    Xl, X = data.draw(st.sampled_from([("valid", np.eye(4)), ("rigid_transform", RigidTransform([0.6, 0, 0])),
                                       ("string", "pose"), ("wrong_shape", np.eye(3)), ("nan", np.full((4, 4), np.nan)),
                                       ("none", None)]))
    sl, s = data.draw(st.one_of(st.floats(0.5, 2.0).map(lambda v: ("valid", v)), st.sampled_from(BAD_NUMBERS)))

    def check(m):
        assert isinstance(m, GraspMotion) and m.frame == "world"
        rigid_poses(m.poses)

    attempt("grasp_regressor.predict_motion_W", f"x:{xl} X_WO:{Xl} scale:{sl}", predict_motion_W, drill, x, X, s,
            check=check)


@st.composite
def _images(draw, w, h):
    rng = np.random.default_rng(draw(seeds))
    kind = draw(st.sampled_from(["valid", "valid", "nan", "inf", "negative", "zero", "huge", "no_object",
                                 "wrong_size", "label_wrong_size", "all_object"]))
    dw, dh = (w + 3, h) if kind == "wrong_size" else (w, h)
    lw, lh = (w, h + 2) if kind == "label_wrong_size" else (w, h)
    depth = rng.uniform(0.4, 0.9, (dh, dw)).astype(np.float32)
    label = np.zeros((lh, lw), dtype=np.int16)
    label[lh // 4: 3 * lh // 4, lw // 4: 3 * lw // 4] = 3
    if kind == "nan":
        depth[rng.random(depth.shape) < 0.3] = np.nan
    elif kind == "inf":
        depth[rng.random(depth.shape) < 0.3] = np.inf
    elif kind == "negative":
        depth = -depth
    elif kind == "zero":
        depth[:] = 0.0
    elif kind == "huge":
        depth[:] = 3e38
    elif kind == "no_object":
        label[:] = 0
    elif kind == "all_object":
        label[:] = 3
    d, lab = ImageDepth32F(dw, dh), ImageLabel16I(lw, lh)
    d.mutable_data[:, :, 0] = depth
    lab.mutable_data[:, :, 0] = label
    return kind, d, lab


@scaled(50)
@given(data=st.data())
def test_object_cloud_system_ports(data):
    w, h = data.draw(st.sampled_from([(16, 12), (24, 18)]))
    kind, depth, label = data.draw(_images(w, h))
    opts = data.draw(options({
        "voxel_size": number(st.floats(0.0, 0.02)),
        "noise_std": number(st.floats(0.0, 0.003)),
        "crop_min": choice([(-10.0,) * 3, (-1.0, -1.0, -0.1)], [("nan", (np.nan,) * 3), ("wrong_shape", (0.0, 0.0)),
                                                               ("string", "low")]),
        "crop_max": choice([(10.0,) * 3], [("below_min", (-20.0,) * 3), ("inf", (np.inf,) * 3)]),
    }))
    cam = data.draw(st.sampled_from([("valid", RigidTransform([0.0, 0.0, 0.5])),
                                     ("nan", RigidTransform(RotationMatrix(), [np.nan, 0.0, 0.0])),
                                     ("huge", RigidTransform(RotationMatrix(), [1e30, 0.0, 0.0]))]))
    label_str = f"images:{kind} camera_pose:{cam[0]}" + "".join(
        f" {k}={v[0]}" for k, v in opts.items() if v[0] != "valid")
    built = attempt("ObjectCloudSystem", label_str, ObjectCloudSystem, CameraInfo(w, h, 0.8), 3,
                    **{k: v[1] for k, v in opts.items()})
    if built.rejected:
        return
    system = built.value

    def run():
        ctx = system.CreateDefaultContext()
        system.GetInputPort("depth_image").FixValue(ctx, depth)
        system.GetInputPort("label_image").FixValue(ctx, label)
        system.GetInputPort("camera_pose").FixValue(ctx, cam[1])
        return np.asarray(system.GetOutputPort("object_cloud_W").Eval(ctx).xyzs()).T

    attempt("ObjectCloudSystem.ports", label_str, run, check=finite_array((None, 3)),
            expect="reject" if "wrong_size" in kind else None)


@scaled(20)
@given(args=st.sampled_from([
    ("valid", (16, 12, 3), {}), ("negative_noise", (16, 12, 3), {"noise_std": -1.0}),
    ("nan_noise", (16, 12, 3), {"noise_std": float("nan")}), ("zero_width", (0, 12, 3), {}),
    ("string_label", (16, 12, "drill"), {}), ("huge_label", (16, 12, 10**6), {}),
    ("float_seed", (16, 12, 3), {"seed": 1.5}), ("negative_seed", (16, 12, 3), {"seed": -1}),
]), crop=st.sampled_from([("valid", ((-1.0,) * 3, (1.0,) * 3, 0.01)), ("nan_voxel", ((-1.0,) * 3, (1.0,) * 3, np.nan)),
                          ("negative_voxel", ((-1.0,) * 3, (1.0,) * 3, -0.01)), ("short", ((0.0,), (1.0,) * 3, 0.01))]))
def test_system_constructors(args, crop):
    label, a, kw = args
    attempt("LabelDepthMask", f"args:{label}", LabelDepthMask, *a, **kw)
    attempt("CloudCropVoxel", f"args:{crop[0]}", CloudCropVoxel, *crop[1])


def test_failed_estimate_status_is_one_line(small_space):
    """The estimator's status for a rejected observation is the core's one-line message."""
    e = estimate_on_table(small_space, np.full((50, 3), 1000.0) + np.random.default_rng(0).normal(0, 1, (50, 3)),
                          X_WT, yaw_candidates=None)
    assert not e.ok
    check_message(ValueError(e.status))
