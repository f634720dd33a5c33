"""The transfer LeafSystems through their ports, against the pure functions they wrap (known answers)."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.inference import uncovered_points
from catgrasp_drake.core.regression import fit_ridge
from catgrasp_drake.core.rotations import rotation_angle, rotz
from catgrasp_drake.core.shape_space import build_shape_space
from catgrasp_drake.core.visibility import camera_on_sphere_position, hidden_point_removal
from catgrasp_drake.grasping.descriptor import descriptor_vector
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.perception.object_cloud import cloud_from_points, points_from_cloud
from catgrasp_drake.systems.grasp_execution import refusal_status
from catgrasp_drake.systems.grasp_regressor import GraspRegressor, predict_motion_W
from catgrasp_drake.systems.shape_estimator import LatentShapeEstimator, estimate_on_table

from ..core.test_synthetic_shapes import family

#: The table top frame T in the world: 0.55 m in front of the robot, top at z = 0.02.
X_WT = np.eye(4)
X_WT[:3, 3] = (0.55, 0.0, 0.02)


@pytest.fixture(scope="module")
def space():
    inst = family(np.random.default_rng(10), 8, n=250)
    return build_shape_space(inst, canonical_index=0, beta=0.02, lam=3.0, variance=0.95)


@pytest.fixture(scope="module")
def model(space):
    """A category model whose regressor is linear in x with a known answer (no simulation)."""
    poses = np.tile(np.eye(4), (2, 1, 1))
    poses[:, :3, :3] = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # a proper rotation
    poses[0, :3, 3] = (0.0, -0.12, 0.05)
    poses[1, :3, 3] = (0.0, -0.06, 0.05)
    postures = {k: np.full(9, v) for k, v in (("open", 0.0), ("preshape", 0.2), ("closed", 0.6))}
    template = GraspMotion(poses, ("pregrasp", "grasp"), postures, "object")
    d0 = descriptor_vector(template)
    K = len(space.latent_train)
    Y = np.tile(d0, (K, 1))
    Y[:, 2] += 0.01 * space.latent_train[:, 0]  # grasp z of the first pose moves with x_0
    reg = fit_ridge(space.latent_train, Y, alpha=1e-9)
    return CategoryModel("synthetic", space, reg, template, tuple(f"s{i}" for i in range(K)), "s0",
                         grasp_anchor_H=(0.0, 0.0, 0.03), grasp_rotation_radius=0.05)


def _observation(space, x, yaw, p_T, s=1.0):
    """A shape of latent ``x`` on the table (similarity yaw, p_T, s in T), seen from one camera; world frame."""
    T_pts = s * space.deform(x) @ rotz(yaw).T + p_T
    P_W = T_pts + X_WT[:3, 3]
    cam_W = camera_on_sphere_position(P_W.mean(0), 0.6, np.radians(40), np.radians(30))
    vis = hidden_point_removal(P_W, cam_W)
    return P_W, vis, cam_W


def _estimator_context(est, points_W, cam_W=None):
    ctx = est.CreateDefaultContext()
    est.GetInputPort("object_cloud_W").FixValue(ctx, cloud_from_points(points_W))
    if cam_W is not None:
        est.GetInputPort("X_WC").FixValue(ctx, RigidTransform(cam_W))
    return ctx


def test_estimator_ports_recover_a_known_shape_and_pose(space):
    x_true = 0.8 * space.latent_train[3]
    yaw, p_T = 0.4, np.array([0.1, -0.05, 0.0])
    P_W, vis, cam_W = _observation(space, x_true, yaw, p_T, s=1.1)
    # a known-yaw case: the single start is the true yaw (the unknown-yaw search is the core's, tested there).
    # Exact recovery is asserted for the paper's free similarity: on this synthetic family the yaw-only
    # (upright) fit stops in a nearby local minimum (yaw 0.45 deg off, x off by half its norm); its pose is
    # still checked below.
    est = LatentShapeEstimator(space, X_WT, yaw_candidates=[yaw], max_iter=200, tol=1e-7, prior=0.0, upright=False)
    ctx = _estimator_context(est, P_W[vis], cam_W)
    simulator = Simulator(est, ctx)
    simulator.Initialize()  # the initialization event makes the estimate
    x = est.GetOutputPort("x").Eval(ctx)
    X_WO = est.GetOutputPort("X_WO").Eval(ctx)
    scale = est.GetOutputPort("scale").Eval(ctx)[0]
    assert abs(scale - 1.1) < 0.02
    assert rotation_angle(X_WO.rotation().matrix() @ rotz(yaw).T) < 0.03
    assert np.linalg.norm(X_WO.translation() - (X_WT[:3, 3] + p_T)) < 5e-3
    assert np.linalg.norm(x - x_true) < 0.25 * np.linalg.norm(x_true) + 0.1
    completed = points_from_cloud(est.GetOutputPort("completed_cloud_W").Eval(ctx))
    assert np.linalg.norm(completed - P_W, axis=1)[~vis].mean() < 3e-3  # unseen side completed
    assert 0.6 < est.GetOutputPort("confidence").Eval(ctx)[0] <= 1.0
    # the ports equal the pure function on the same input
    pure = estimate_on_table(space, P_W[vis], X_WT, camera_W=cam_W, yaw_candidates=[yaw], max_iter=200, tol=1e-7,
                             prior=0.0, upright=False)
    assert np.allclose(pure.x, x, atol=1e-6) and np.allclose(pure.X_WO, X_WO.GetAsMatrix4(), atol=1e-6)
    assert np.isclose(pure.energy, est.GetOutputPort("energy").Eval(ctx)[0])
    # the default, upright fit: exactly upright, the pose within a degree and 5 mm, the scale within 2 %
    up = estimate_on_table(space, P_W[vis], X_WT, camera_W=cam_W, yaw_candidates=[yaw], max_iter=200, tol=1e-7,
                           prior=0.0)
    assert np.isclose(up.X_WO[2, 2], 1.0, atol=1e-12)
    assert np.degrees(rotation_angle(up.X_WO[:3, :3] @ rotz(yaw).T)) < 1.0
    assert np.linalg.norm(up.X_WO[:3, 3] - (X_WT[:3, 3] + p_T)) < 5e-3
    assert abs(up.scale - 1.1) < 0.022


def test_estimate_is_state_not_recomputed_as_time_advances(space):
    P_W, vis, cam_W = _observation(space, space.latent_train[1], 0.0, np.zeros(3))
    est = LatentShapeEstimator(space, X_WT, yaw_candidates=[0.0])
    ctx = _estimator_context(est, P_W[vis], cam_W)
    simulator = Simulator(est, ctx)
    simulator.Initialize()
    first = est.GetOutputPort("estimate").Eval(ctx)
    assert first.ok and first.status == "ok"
    simulator.AdvanceTo(0.5)
    # a new cloud on the input does not change the estimate: it was taken at initialization
    est.GetInputPort("object_cloud_W").FixValue(ctx, cloud_from_points(P_W[vis] + [0.1, 0.0, 0.0]))
    assert est.GetOutputPort("estimate").Eval(ctx) is first
    # estimate_now does see it, and set_estimate stores it
    moved = est.estimate_now(ctx)
    assert np.linalg.norm(moved.X_WO[:3, 3] - first.X_WO[:3, 3] - [0.1, 0, 0]) < 2e-3
    est.set_estimate(ctx, moved)
    assert est.GetOutputPort("estimate").Eval(ctx) is moved


def test_estimator_without_object_points_reports_instead_of_raising(space):
    est = LatentShapeEstimator(space, X_WT)
    ctx = _estimator_context(est, np.zeros((5, 3)) + [0.6, 0.0, 0.1])
    Simulator(est, ctx).Initialize()
    e = est.GetOutputPort("estimate").Eval(ctx)
    assert not e.ok and "no object in view" in e.status
    assert est.GetOutputPort("confidence").Eval(ctx)[0] == 0.0
    assert refusal_status(0.0, 0.0).startswith("refused: no shape estimate")


def test_regressor_ports_equal_the_category_models_transfer(model, space):
    reg = GraspRegressor(model)
    ctx = reg.CreateDefaultContext()
    x = space.latent_train[2]
    X_WO = RigidTransform(RotationMatrix(rotz(0.7)), [0.6, -0.1, 0.02])
    reg.GetInputPort("x").FixValue(ctx, x)
    reg.GetInputPort("X_WO").FixValue(ctx, X_WO)
    reg.GetInputPort("scale").FixValue(ctx, [1.2])
    m = reg.GetOutputPort("grasp_motion_W").Eval(ctx)
    assert m.frame == "world"
    ref = model.transfer(x, rotz(0.7), np.array([0.6, -0.1, 0.02]), 1.2)
    assert np.allclose(m.poses, ref.poses)
    assert m == predict_motion_W(model, x, X_WO, 1.2)
    # known answer: the grasp centre is the warped canonical centre, scaled, rotated and moved
    a = np.array(model.grasp_anchor_H)
    warped = model.warped_motion(x)
    centre_O = warped.poses[:, :3, :3] @ a + warped.poses[:, :3, 3]
    centre_W = m.poses[:, :3, :3] @ a + m.poses[:, :3, 3]
    assert np.allclose(centre_W, 1.2 * centre_O @ rotz(0.7).T + [0.6, -0.1, 0.02])
    # and the regressor's known dependence on x_0 shows through the ports
    reg.GetInputPort("x").FixValue(ctx, x + np.eye(len(x))[0])
    m2 = reg.GetOutputPort("grasp_motion_W").Eval(ctx)
    assert not np.allclose(m2.poses[0], m.poses[0])


def test_regressor_output_is_cached_across_time(model, space):
    builder = DiagramBuilder()
    reg = builder.AddSystem(GraspRegressor(model))
    builder.ExportInput(reg.GetInputPort("x"), "x")
    builder.ExportInput(reg.GetInputPort("X_WO"), "X_WO")
    builder.ExportInput(reg.GetInputPort("scale"), "scale")
    diagram = builder.Build()
    ctx = diagram.CreateDefaultContext()
    diagram.GetInputPort("x").FixValue(ctx, space.latent_train[0])
    diagram.GetInputPort("X_WO").FixValue(ctx, RigidTransform())
    diagram.GetInputPort("scale").FixValue(ctx, [1.0])
    sub = reg.GetMyContextFromRoot(ctx)
    first = reg.GetOutputPort("grasp_motion_W").Eval(sub)
    ctx.SetTime(3.0)
    assert reg.GetOutputPort("grasp_motion_W").Eval(sub) is first


def test_fit_voxel_grid_is_matched_to_the_model_and_selectable(space):
    from catgrasp_drake.core.inference import LEGACY_SEARCH, model_spacing
    from catgrasp_drake.errors import InputError
    from catgrasp_drake.perception.object_cloud import voxel_grid
    from catgrasp_drake.systems.shape_estimator import AUTO_VOXEL_FACTOR, fit_voxel_size

    assert fit_voxel_size(space) == pytest.approx(AUTO_VOXEL_FACTOR * model_spacing(space))
    assert fit_voxel_size(space, None) == 0.0 and fit_voxel_size(space, 0.004) == 0.004
    for bad in ("fine", -0.01, 5.0, float("nan")):
        with pytest.raises(InputError):
            fit_voxel_size(space, bad)
    P_W, vis, cam_W = _observation(space, space.latent_train[2], 0.3, np.array([0.01, 0.0, 0.0]))
    dense = np.vstack([P_W[vis], P_W[vis] + 1e-3])  # twice the points, 1 mm apart
    v = fit_voxel_size(space)
    auto = estimate_on_table(space, dense, X_WT, camera_W=cam_W, yaw_candidates=[0.3])
    # the same as voxelising the cloud in the table frame by hand and fitting it as given
    R, p = X_WT[:3, :3], X_WT[:3, 3]
    by_hand = voxel_grid((dense - p) @ R, v) @ R.T + p
    given = estimate_on_table(space, by_hand, X_WT, camera_W=cam_W, yaw_candidates=[0.3], voxel_size=None)
    np.testing.assert_allclose(auto.X_WO, given.X_WO, atol=1e-9)
    np.testing.assert_allclose(auto.x, given.x, atol=1e-7)
    assert auto.result.diagnostics["n_observed"] < len(dense)
    assert len(auto.observed_W) == len(dense)  # the estimate keeps the cloud as given
    # its uncovered count is taken on every point of the cloud as given, not on the voxelised one the fit saw
    stray = dense.mean(0) + np.array([0.0, 0.0, 0.4]) + np.random.default_rng(3).normal(scale=1e-3, size=(30, 3))
    with_stray = estimate_on_table(space, np.vstack([dense, stray]), X_WT, camera_W=cam_W, yaw_candidates=[0.3])
    assert with_stray.uncovered == uncovered_points(with_stray.completed_W, np.vstack([dense, stray])) >= 30
    assert auto.uncovered == uncovered_points(auto.completed_W, dense)
    # the old settings stay selectable
    old = LatentShapeEstimator(space, X_WT, yaw_candidates=[0.3], voxel_size=None, **LEGACY_SEARCH)
    ctx = _estimator_context(old, dense, cam_W)
    e = old.estimate_now(ctx)
    assert e.ok and e.result.diagnostics["n_observed"] == len(dense)
