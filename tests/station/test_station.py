"""Station builder, camera cloud, trajectory planning and the grasp trial (Drake)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pydrake")

from catgrasp_drake.data.dataset import load_mesh  # noqa: E402
from catgrasp_drake.data.open3d_import import import_open3d  # noqa: E402
from catgrasp_drake.errors import InputError  # noqa: E402
from catgrasp_drake.perception.object_cloud import (  # noqa: E402
    _crop_and_voxelize,
    _mask_depth,
    _voxel_downsample,
    points_from_cloud,
)
from catgrasp_drake.station.builder import make_station  # noqa: E402
from catgrasp_drake.station.handwritten import motion_from_spec  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, load_scenarios  # noqa: E402
from catgrasp_drake.trial import run_grasp_trial  # noqa: E402

#: A side power grasp on the 4 cm test cylinder (object frame).
CYLINDER_GRASP = {"grasp": {"position": [-0.04, 0.135, 0.08], "fingers": [0, -1, 0], "palm": [1, 0, 0]},
                  "pregrasp_distance": 0.08, "postures": "cylinder", "lift_height": 0.12}


def _mesh_distance(points_W, category, instance, X_WO):
    o3d = import_open3d()
    mesh = load_mesh(category, instance)
    mesh.apply_transform(X_WO)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(mesh.vertices.astype(np.float32)),
                        o3d.core.Tensor(mesh.faces.astype(np.uint32)))
    return scene.compute_distance(o3d.core.Tensor(points_W.astype(np.float32))).numpy()


@pytest.mark.parametrize("name", sorted(load_scenarios()))
def test_station_builds_from_every_scenario(name):
    scenario = load_scenario(name)
    station = make_station(scenario)
    inputs = {station.get_input_port(i).get_name() for i in range(station.num_input_ports())}
    outputs = {station.get_output_port(i).get_name() for i in range(station.num_output_ports())}
    assert {"ur10.desired_state", "svh.desired_state", "ur10.actuation", "svh.actuation"} <= inputs
    assert {"ur10.state_estimated", "svh.state_estimated", "plant.contact_results", "object.X_WO"} <= outputs
    for cam in scenario.cameras:
        assert {f"{cam.name}.depth_image", f"{cam.name}.label_image", f"{cam.name}.object_cloud_W"} <= outputs
    context = station.CreateDefaultContext()
    X_WO = station.GetOutputPort("object.X_WO").Eval(context).GetAsMatrix4()
    np.testing.assert_allclose(X_WO, scenario.X_WO(), atol=1e-9)
    assert station.GetInputPort("svh.desired_state").size() == 18
    assert station.GetInputPort("ur10.desired_state").size() == 12


@pytest.mark.parametrize("name", ["drill_default", "spray_bottle_default", "mug_default"])
def test_camera_cloud_lies_on_the_object_surface(name):
    scenario = load_scenario(name)
    station = make_station(scenario)
    context = station.CreateDefaultContext()
    cam = scenario.cameras[0].name
    points = points_from_cloud(station.GetOutputPort(f"{cam}.object_cloud_W").Eval(context))
    assert len(points) > 300
    d = _mesh_distance(points, scenario.object.category, scenario.object.instance, scenario.X_WO())
    assert d.mean() < 0.003, f"mean distance {d.mean() * 1e3:.2f} mm"
    assert np.percentile(d, 99) < 0.005


def test_camera_cloud_noise_is_seeded():
    base = load_scenario("drill_default")
    noisy = base.replace(object_cloud=base.object_cloud.__class__(
        **{**base.object_cloud.__dict__, "depth_noise_std": 0.002, "seed": 7}))
    clouds = []
    for _ in range(2):
        station = make_station(noisy)
        ctx = station.CreateDefaultContext()
        clouds.append(points_from_cloud(station.GetOutputPort("camera0.object_cloud_W").Eval(ctx)))
    np.testing.assert_array_equal(clouds[0], clouds[1])
    d = _mesh_distance(clouds[0], "drill", "drill_00", noisy.X_WO())
    assert 0.0005 < d.mean() < 0.004


def test_cloud_helpers():
    depth = np.array([[1.0, 2.0], [3.0, np.inf]], np.float32)
    label = np.array([[5, 4], [5, 5]])
    m = _mask_depth(depth, label, 5)
    assert np.isnan(m[0, 1]) and m[0, 0] == 1.0 and m[1, 0] == 3.0
    with pytest.raises(InputError):
        _mask_depth(depth, label, 5, noise_std=0.01)  # noise needs an explicit generator
    p = np.array([[0.001, 0.001, 0.001], [0.002, 0.002, 0.002], [0.5, 0.5, 0.5], [np.nan, 0, 0], [2.0, 0, 0]])
    out = _crop_and_voxelize(p, np.zeros(3), np.ones(3), 0.01)
    np.testing.assert_allclose(out, [[0.0015] * 3, [0.5] * 3])
    assert len(_voxel_downsample(np.zeros((0, 3)), 0.01)) == 0


def test_unreachable_pose_is_reported_not_raised():
    scenario = load_scenario("cylinder_test")
    spec = {**CYLINDER_GRASP, "grasp": {**CYLINDER_GRASP["grasp"], "position": [3.0, 0.0, 0.08]}}
    result = run_grasp_trial(scenario, motion_from_spec(spec, None))
    assert not result.grasp_success and not result.functional_success
    assert result.failure_reason == "unreachable"
    assert result.plan_status.startswith("unreachable: ")
    assert result.sim_time_s == 0.0


def test_below_table_pose_is_reported():
    scenario = load_scenario("cylinder_test")
    spec = {**CYLINDER_GRASP, "grasp": {**CYLINDER_GRASP["grasp"], "position": [-0.04, 0.135, -0.15]}}
    result = run_grasp_trial(scenario, motion_from_spec(spec, None))
    assert result.failure_reason in ("unreachable", "collision_before_closing")
    assert result.plan_status != "ok"


def test_motion_must_be_in_object_frame():
    motion = motion_from_spec(CYLINDER_GRASP, None)
    with pytest.raises(Exception, match="object frame"):
        run_grasp_trial(load_scenario("cylinder_test"), motion.in_world(np.eye(4)).__class__(
            motion.poses, motion.pose_names, dict(motion.postures), "world"))


@pytest.mark.slow
def test_cylinder_trial_is_deterministic_and_lifts():
    scenario = load_scenario("cylinder_test")
    motion = motion_from_spec(CYLINDER_GRASP, None)
    a = run_grasp_trial(scenario, motion)
    b = run_grasp_trial(scenario, motion)
    assert a.outcome() == b.outcome()
    assert a.plan_status == "ok"
    assert a.grasp_success, a.detail
    assert a.object_rise_m > 0.08
    assert a.timeline["end"] - a.timeline["hold"] >= 2.0
    assert a.sim_time_s >= a.timeline["end"] - 1e-6
    assert any("svh::" in pair[1] for pair in a.contacts_end)
