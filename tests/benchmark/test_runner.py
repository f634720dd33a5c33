"""The benchmark's trials: placements, cameras, depth noise, every method in the transfer diagram, a smoke run."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from catgrasp_drake.benchmark.runner import (
    AZIMUTH_RANGE_DEG,
    ELEVATION_RANGE_DEG,
    SHIFT_M,
    YAW_RANGE_DEG,
    BenchmarkConfig,
    run_benchmark,
    trial_placement,
    trial_specs,
)
from catgrasp_drake.errors import CatgraspError, InputError
from catgrasp_drake.perception.object_cloud import _mask_depth
from catgrasp_drake.station.scenario import load_scenario


def _azimuth_elevation(camera):
    d = np.asarray(camera.look_at_eye) - np.asarray(camera.look_at_target)
    return (math.degrees(math.atan2(d[1], d[0])), math.degrees(math.atan2(d[2], math.hypot(d[0], d[1]))),
            float(np.linalg.norm(d)))


def test_placements_vary_within_their_ranges_and_repeat_for_the_same_trial():
    base = load_scenario("drill_default")
    az0, _, dist0 = _azimuth_elevation(base.cameras[0])
    seen_viewpoints, yaws = set(), []
    for trial in range(12):
        s, placement, camera = trial_placement(base, "drill_03", trial, seed=0)
        again = trial_placement(base, "drill_03", trial, seed=0)
        assert again[1] == placement and again[2] == camera  # a pure function of (instance, trial, seed)
        assert abs(s.object.yaw_deg - base.object.yaw_deg) <= YAW_RANGE_DEG
        assert max(abs(s.object.xyz[0] - base.object.xyz[0]), abs(s.object.xyz[1] - base.object.xyz[1])) <= SHIFT_M
        az, el, dist = _azimuth_elevation(s.cameras[0])
        assert ELEVATION_RANGE_DEG[0] - 1e-6 <= el <= ELEVATION_RANGE_DEG[1] + 1e-6
        assert abs((az - az0 + 180) % 360 - 180) <= AZIMUTH_RANGE_DEG + 1e-6
        assert dist == pytest.approx(dist0)
        # the camera follows the object's shift
        shift = np.asarray(s.X_WO()[:3, 3]) - np.asarray(base.X_WO()[:3, 3])
        np.testing.assert_allclose(np.asarray(s.cameras[0].look_at_target) - base.cameras[0].look_at_target, shift,
                                   atol=1e-9)
        assert s.object_cloud.depth_noise_model == "kinect" and s.object_cloud.edge_dropout > 0
        seen_viewpoints.add(camera["viewpoint"])
        yaws.append(s.object.yaw_deg)
    assert seen_viewpoints == {0, 1, 2}
    assert np.ptp(yaws) > 40  # the trials really differ (not one placement for every trial)
    other = trial_placement(base, "drill_04", 0, seed=0)[1]
    assert other != trial_placement(base, "drill_03", 0, seed=0)[1]  # and differ between instances
    quiet = trial_placement(base, "drill_03", 0, seed=0, noise=False)[0]
    assert quiet.object_cloud.depth_noise_std == 0.0


def test_kinect_noise_grows_with_depth_squared_and_drops_a_few_percent_at_edges():
    rng = np.random.default_rng(3)
    label = np.zeros((200, 200), np.int16)
    label[50:150, 50:150] = 7
    for z, expected in ((1.0, 0.0015), (2.0, 0.006)):
        depth = np.full((200, 200), z, np.float32)
        out = _mask_depth(depth, label, 7, 0.0015, rng, noise_model="kinect", edge_dropout=0.0)
        kept = out[np.isfinite(out)]
        assert len(kept) == 100 * 100
        assert np.std(kept - z) == pytest.approx(expected, rel=0.05)
    depth = np.full((200, 200), 1.0, np.float32)
    out = _mask_depth(depth, label, 7, 0.0, rng, noise_model="kinect", edge_dropout=0.5)
    dropped = 1 - np.isfinite(out).sum() / (100 * 100)
    assert 0.01 < dropped < 0.05  # 396 silhouette pixels of 10^4, half of them dropped
    assert np.isfinite(out[60:140, 60:140]).all()  # never inside the silhouette
    with pytest.raises(InputError, match="noise_model"):
        _mask_depth(depth, label, 7, 0.001, rng, noise_model="sonar")


def test_trial_specs_pair_every_method_on_the_same_trials(tmp_path):
    cfg = BenchmarkConfig(split="smoke", methods=("latent", "rigid"), data_dir=str(tmp_path / "data"))
    specs = trial_specs(cfg)
    assert [(s["instance"], s["method"]) for s in specs] == [
        ("drill_00", "latent"), ("drill_00", "rigid"), ("drill_01", "latent"), ("drill_01", "rigid")]
    assert all(s["noise"] and s["physics"] == "default" for s in specs)
    # a copy of the committed model passed as --model keys the same trials (its path is not in the key)
    import shutil

    from catgrasp_drake.demo import default_model_path
    from catgrasp_drake.runner import task_key

    copy = tmp_path / "copy.npz"
    shutil.copy(default_model_path("drill"), copy)
    copied = trial_specs(cfg, {"drill": str(copy)})
    assert [s["_model"] for s in copied] != [s["_model"] for s in specs]
    assert [task_key(s, "v") for s in copied] == [task_key(s, "v") for s in specs]
    with pytest.raises(InputError, match="methods"):
        BenchmarkConfig(methods=("latent", "magic"))
    with pytest.raises(InputError, match="split"):
        BenchmarkConfig(split="train")


def _imported(directory, instance="drill_05", name="my_drill"):
    """An imported object (catgrasp import-object) with a stated alignment and region: no fit, fast."""
    from catgrasp_drake.data.dataset import load_annotations, load_mesh
    from catgrasp_drake.data.importer import import_mesh

    regions = load_annotations("drill", instance)["regions"]
    import_mesh(load_mesh("drill", instance), "drill", name, transform="0 0 0 0 0 0", regions=regions, out=directory)
    return str(directory)


def test_the_objects_split_runs_imported_objects(tmp_path):
    from catgrasp_drake.benchmark.runner import split_objects

    a, b = _imported(tmp_path / "a"), _imported(tmp_path / "b", "drill_06", "other_drill")
    cfg = BenchmarkConfig(split="objects", objects=(a, b), methods=("latent", "rigid"), placements=2)
    objects = split_objects(cfg)
    assert [(o.split, o.category, o.instance, o.model_dir) for o in objects] == [
        ("objects", "drill", "my_drill", a), ("objects", "drill", "other_drill", b)]
    specs = trial_specs(cfg)
    assert len(specs) == 2 * 2 * 2 and {s["model_dir"] for s in specs} == {a, b}
    assert all(len(s["object_sha256"]) == 64 for s in specs)
    assert split_objects(BenchmarkConfig(split="objects", objects=(a,), categories=("mug",))) == []
    # re-imported into the same directory: the trials' cache keys change with the files
    _imported(tmp_path / "a", "drill_07")
    assert trial_specs(cfg)[0]["object_sha256"] != specs[0]["object_sha256"]
    # a generated split's objects too: changed generators make them again, and their trials must not come
    # back from the cache of the objects before (session 37: a drill that could not stand was drawn again)
    smoke = BenchmarkConfig(split="smoke", data_dir=str(tmp_path / "data"))
    key = trial_specs(smoke)[0]["object_sha256"]
    mesh = tmp_path / "data" / "test_seed7919" / "drill" / "drill_00" / "drill_00.obj"
    mesh.write_text(mesh.read_text().replace("v ", "v  ", 1))
    assert trial_specs(smoke)[0]["object_sha256"] != key
    with pytest.raises(InputError, match="directories"):
        BenchmarkConfig(split="objects")
    with pytest.raises(InputError, match="split 'objects'"):
        BenchmarkConfig(split="test", objects=(a,))
    with pytest.raises(InputError, match="both named"):
        split_objects(BenchmarkConfig(split="objects", objects=(a, str(_imported(tmp_path / "c")))))
    with pytest.raises(CatgraspError, match="no such object directory"):
        split_objects(BenchmarkConfig(split="objects", objects=(str(tmp_path / "nothing"),)))


@pytest.mark.slow
def test_smoke_benchmark_runs_the_transfer_diagram_and_records_every_trial(tmp_path):
    from catgrasp_drake.benchmark.report import load_benchmark_records, summary_table, write_benchmark_records

    cfg = BenchmarkConfig(split="smoke", methods=("latent",), data_dir=str(tmp_path / "data"),
                          cache_dir=str(tmp_path / "cache"), workers=0)
    records = run_benchmark(cfg)
    assert len(records) == 2
    for r in records:
        assert r["reason"] not in ("task_error", "worker_died"), r["detail"]
        assert r["plan_status"] == "ok"
        assert r["num_points"] > 300 and 0 < r["confidence"] <= 1
        assert r["timings"]["simulated_s"] > 2.5  # at least to the closing (a failed grasp stops where decided)
        assert r["pose_error_mm"] < 30  # the fit found the drill
        assert abs(r["yaw_error_deg"]) < 20  # ... the right way round
        assert r["posterior"]["hypotheses"] >= 1 and r["posterior"]["tried"] >= 1
    path = tmp_path / "smoke.jsonl"
    write_benchmark_records(path, records)
    assert load_benchmark_records(path) == records
    assert "`smoke` | drill | 2 |" in summary_table(records)
    again = run_benchmark(cfg)  # cached: the same records, nothing re-simulated
    assert [r["grasp"] for r in again] == [r["grasp"] for r in records]
    assert [r["timings"] for r in again] == [r["timings"] for r in records]

    # a record's trial filmed again (catgrasp film --record): the same trial, the same outcome
    from catgrasp_drake.benchmark.runner import film_benchmark_trial

    result, spec = film_benchmark_trial(records[0], tmp_path / "film.png", data_dir=tmp_path / "data")
    assert (result.grasp_success, result.functional_success) == (records[0]["grasp"], records[0]["functional"])
    assert spec["model_sha256"] == records[0]["model_sha256"] and (tmp_path / "film.png").stat().st_size > 1000
    with pytest.raises(InputError, match="not a benchmark trial record"):
        film_benchmark_trial({"instance": "drill_00"}, tmp_path / "x.png")


def test_physics_settings_change_the_station_they_name():
    from pydrake.systems.framework import DiagramBuilder

    from catgrasp_drake.benchmark.runner import SVH_STRENGTH_FACTOR, with_physics
    from catgrasp_drake.station.builder import add_station

    def station(physics):
        h = add_station(DiagramBuilder(), with_physics(load_scenario("drill_default"), physics))
        hand = [h.plant.get_joint_actuator(i).effort_limit() for i in h.plant.GetJointActuatorIndices(h.hand)]
        arm = [h.plant.get_joint_actuator(i).effort_limit() for i in h.plant.GetJointActuatorIndices(h.arm)]
        inspector = h.scene_graph.model_inspector()
        mu = {inspector.GetProximityProperties(g).GetProperty("material", "coulomb_friction").static_friction()
              for g in h.plant.GetCollisionGeometriesForBody(h.object_body)}
        return np.array(hand), np.array(arm), mu, h.plant.time_step()

    hand0, arm0, mu0, dt0 = station("default")
    hand1, arm1, _, _ = station("effort_1.0x")
    np.testing.assert_allclose(hand1, hand0 / SVH_STRENGTH_FACTOR)
    np.testing.assert_array_equal(arm1, arm0)  # the arm is not weakened
    assert station("friction_0.5")[2] == {0.5} and mu0 == {0.9}
    assert station("time_step_1e-3")[3] == 1e-3 and dt0 == 5e-3
    with pytest.raises(InputError, match="physics"):
        with_physics(load_scenario("drill_default"), "zero_gravity")


def test_the_cli_offers_every_benchmark_method():
    """The CLI's literal method lists (it imports no stack at parse time) agree with the runner and predictors."""
    from catgrasp_drake.benchmark.runner import BENCHMARK_METHODS
    from catgrasp_drake.cli import build_parser
    from catgrasp_drake.prediction import METHODS

    action = next(a for a in build_parser()._subparsers._group_actions[0].choices["benchmark"]._actions
                  if a.dest == "methods")
    assert tuple(action.default) == BENCHMARK_METHODS
    assert set(action.choices) == set(METHODS)


def test_yaw_error_is_the_signed_turn_of_the_functional_direction_about_z():
    from catgrasp_drake.benchmark.runner import yaw_error_deg
    from catgrasp_drake.core.rotations import rotz

    def pose(yaw, tilt=0.0):
        X = np.eye(4)
        X[:3, :3] = rotz(yaw) @ np.array([[1, 0, 0], [0, np.cos(tilt), -np.sin(tilt)], [0, np.sin(tilt), np.cos(tilt)]])
        X[:3, 3] = [0.5, 0.1, 0.0]
        return X

    assert yaw_error_deg(pose(0.3), pose(0.3)) == pytest.approx(0.0, abs=1e-9)
    assert yaw_error_deg(pose(0.3 + np.radians(25)), pose(0.3)) == pytest.approx(25.0)
    assert yaw_error_deg(pose(0.3 - np.radians(170)), pose(0.3)) == pytest.approx(-170.0)
    assert yaw_error_deg(pose(1.0, tilt=0.2), pose(1.0)) == pytest.approx(0.0, abs=1e-9)  # a tilt is not a yaw


def test_a_test_split_made_by_other_generators_is_generated_again(tmp_path):
    """The test split on disk is regenerated when its marker names other generators (a widened generator
    must not be measured on the instances of the one before), and kept when it names these."""
    from catgrasp_drake.benchmark.runner import ensure_test_split
    from catgrasp_drake.data.dataset import tree_digest

    root = ensure_test_split(tmp_path)
    fresh = tree_digest(root)
    mesh = root / "drill" / "drill_00" / "drill_00.obj"
    mesh.write_text("stale")  # an instance of some earlier generator ...
    ensure_test_split(tmp_path)
    assert mesh.read_text() == "stale"  # ... is kept while the marker names the current generators
    (root / "COMPLETE").write_text("seed 7919, 45 instances\n")  # the marker an older version wrote
    ensure_test_split(tmp_path)
    assert tree_digest(root) == fresh


def test_the_fresh_split_draws_instances_nobody_has_seen_from_its_own_seed(tmp_path):
    """``--split fresh --data-seed N``: the category's instances generated from N (not the test split's, not the
    committed ones), N carried by every spec and record so the trial can be run again; the two seeds the
    project has looked at are refused, and records of two fresh seeds are two objects under one name."""
    from catgrasp_drake.benchmark.report import merged_records
    from catgrasp_drake.benchmark.runner import TEST_SEED, ensure_test_split, spec_from_record, trial_identity
    from catgrasp_drake.data.dataset import DATASET_SEED, read_annotations

    cfg = BenchmarkConfig(split="fresh", data_seed=31, categories=("mug",), methods=("latent", "rigid"),
                          instances_per_category=2, placements=2, data_dir=str(tmp_path))
    specs = trial_specs(cfg)
    assert len(specs) == 2 * 2 * 2 and {s["data_seed"] for s in specs} == {31}
    assert {s["instance"] for s in specs} == {"mug_00", "mug_01"}
    fresh = read_annotations(tmp_path / "fresh_seed31" / "mug" / "mug_00" / "annotations.json")
    test = read_annotations(ensure_test_split(tmp_path) / "mug" / "mug_00" / "annotations.json")
    assert fresh["seed"] != test["seed"]  # another object under the same name
    again = spec_from_record(trial_identity(specs[3]), data_dir=tmp_path)
    assert again == specs[3]
    for bad in (None, TEST_SEED, DATASET_SEED, -1, 1.5):
        with pytest.raises(InputError, match="seed"):
            BenchmarkConfig(split="fresh", data_seed=bad)
    with pytest.raises(InputError, match="only for the split 'fresh'"):
        BenchmarkConfig(split="test", data_seed=31)
    base = {"split": "fresh", "category": "mug", "instance": "mug_00", "trial": 0, "view": "single",
            "method": "latent", "physics": "default", "seed": 0, "grasp": True, "functional": True}
    two_seeds = merged_records([base | {"data_seed": 31}], [base | {"data_seed": 32}])  # the same name, two objects
    assert [r["data_seed"] for r in two_seeds] == [31, 32]


def test_the_validation_split_is_its_own_seeds_novel_draws_and_no_fresh_seed_may_reuse_it(tmp_path):
    """``--split val``: the categories' instances generated from :data:`VAL_SEED` into ``val_seed<VAL_SEED>``,
    other objects than the test split's under the same names; a fresh split may not take its seed."""
    from catgrasp_drake.benchmark.runner import VAL_SEED, ensure_test_split
    from catgrasp_drake.data.dataset import read_annotations

    cfg = BenchmarkConfig(split="val", categories=("mug",), methods=("latent",), instances_per_category=2,
                          placements=1, data_dir=str(tmp_path))
    specs = trial_specs(cfg)
    assert {(s["split"], s["instance"]) for s in specs} == {("val", "mug_00"), ("val", "mug_01")}
    assert all(f"val_seed{VAL_SEED}" in s["model_dir"] for s in specs) and "data_seed" not in specs[0]
    val = read_annotations(tmp_path / f"val_seed{VAL_SEED}" / "mug" / "mug_00" / "annotations.json")
    test = read_annotations(ensure_test_split(tmp_path) / "mug" / "mug_00" / "annotations.json")
    assert val["seed"][0] == VAL_SEED and test["seed"][0] != VAL_SEED  # [data-set seed, category, index]
    with pytest.raises(InputError, match="validation"):
        BenchmarkConfig(split="fresh", data_seed=VAL_SEED)


def test_benchmark_merge_rewrites_only_the_rerun_trials(tmp_path, monkeypatch):
    """``catgrasp benchmark --merge`` (a category re-run after retraining it) keeps the file's other trials;
    without it the file holds this run's trials only. The trials themselves are stubbed: this is the CLI's
    bookkeeping, the records are the report's."""
    import catgrasp_drake.benchmark.runner as runner
    from catgrasp_drake.benchmark.report import load_benchmark_records, write_benchmark_records
    from catgrasp_drake.cli import main

    def record(category, trial, functional):
        return {"split": "test", "category": category, "instance": f"{category}_00", "trial": trial,
                "view": "single", "method": "latent", "physics": "default", "seed": 0, "grasp": functional,
                "functional": functional, "reason": None if functional else "not_lifted", "detail": ""}

    out = tmp_path / "test.jsonl"
    write_benchmark_records(out, [record("drill", 0, True), record("mug", 0, False), record("mug", 1, False)])
    rerun = [record("mug", 0, True), record("mug", 1, True), record("mug", 2, True)]
    monkeypatch.setattr(runner, "trial_specs",
                        lambda config, **kw: [{"category": "mug", "instance": "mug_00", "trial": 0}])
    monkeypatch.setattr(runner, "run_benchmark", lambda config, **kw: list(rerun))
    args = ["benchmark", "--categories", "mug", "--methods", "latent", "--out", str(out)]
    assert main(args + ["--merge"]) == 0
    assert load_benchmark_records(out) == [record("drill", 0, True)] + rerun
    assert main(args) == 0
    assert load_benchmark_records(out) == rerun


def test_the_ais_split_imports_the_real_drills_once(tmp_path, monkeypatch, ais_drill_paths):
    """The split 'ais': each real drill cloud imported (its own normals, the stated identity alignment, the
    pinned trigger), prepared once and kept while the import code and the pinned triggers are the same."""
    from catgrasp_drake.benchmark.runner import split_objects

    cfg = BenchmarkConfig(split="ais", instances=("ais_drill_4",), data_dir=str(tmp_path), placements=2,
                          methods=("latent",))
    (obj,) = split_objects(cfg)
    assert (obj.split, obj.category, obj.instance) == ("ais", "drill", "ais_drill_4")
    ann = json.loads((tmp_path / "ais" / "drill" / "ais_drill_4" / "annotations.json").read_text())
    rec = ann["import"]
    assert rec["source"]["reconstruction"]["normals"] == "the cloud's own"
    # the stated identity, levelled on the reconstructed base by less than a degree
    assert not rec["transform"]["automatic"] and max(map(abs, rec["transform"]["rpy_deg"])) < 1.0
    # the pinned trigger (tools/pin_ais_triggers.py), not the drill model's transfer: the box sessions 18-20 judged
    # ais_drill_4 with, levelled and cut as then
    assert rec["region_source"] == "given"
    np.testing.assert_allclose(ann["regions"]["trigger"]["center"], [0.001071, 0.020419, 0.147188], atol=2e-6)
    np.testing.assert_allclose(ann["regions"]["trigger"]["half_extents"], [0.009758, 0.010256, 0.023597])
    assert 0.18 < ann["bbox_max"][2] < 0.24  # drill_4 stands 0.21 m tall (the cloud's own height)
    sdf = tmp_path / "ais" / "drill" / "ais_drill_4" / "ais_drill_4.sdf"
    mtime = sdf.stat().st_mtime_ns
    specs = trial_specs(cfg)
    assert len(specs) == 2 and all(len(s["object_sha256"]) == 64 for s in specs)
    assert sdf.stat().st_mtime_ns == mtime  # prepared once
    assert split_objects(BenchmarkConfig(split="ais", categories=("mug",), data_dir=str(tmp_path))) == []
    # drill_3, a corded drill whose narrow handle end is its base, falls over by itself: left out
    assert split_objects(replace(cfg, instances=("ais_drill_3",))) == []
    rec3 = json.loads((tmp_path / "ais" / "drill" / "ais_drill_3" / "annotations.json").read_text())["import"]
    assert not rec3["stands"] and rec3["support_margin_m"] < -0.02 and rec["stands"]
    monkeypatch.setenv("CATGRASP_AIS_DRILLS", str(tmp_path / "nowhere"))
    with pytest.raises(InputError, match="no drill_<n>.pcd clouds in .*CATGRASP_AIS_DRILLS"):
        split_objects(BenchmarkConfig(split="ais", data_dir=str(tmp_path)))


def test_the_stress_split_stretches_every_committed_instance_once(tmp_path):
    from catgrasp_drake.benchmark.runner import split_objects
    from catgrasp_drake.data.dataset import list_instances, read_annotations
    from catgrasp_drake.data.stretch import STRESS_FAMILIES

    config = BenchmarkConfig(split="stress", categories=("mug",), methods=("latent",), data_dir=str(tmp_path))
    objects = split_objects(config)
    assert len(objects) == len(STRESS_FAMILIES) * len(list_instances("mug"))
    assert {o.split for o in objects} == {"stress"} and objects[0].instance == "mug_00_small"
    deep = [o for o in objects if o.instance == "mug_04_deep"][0]
    ann = read_annotations(tmp_path / "stress" / "mug" / "mug_04_deep" / "annotations.json")
    assert ann["stretched_from"] == "mug_04" and ann["stretch"] == list(STRESS_FAMILIES["deep"])
    mtime = (tmp_path / "stress" / "mug" / "mug_04_deep" / "mug_04_deep.obj").stat().st_mtime_ns
    assert split_objects(config) == objects  # prepared once: the second call reads what the first wrote
    assert (tmp_path / "stress" / "mug" / "mug_04_deep" / "mug_04_deep.obj").stat().st_mtime_ns == mtime
    specs = trial_specs(replace(config, placements=1))
    assert len(specs) == len(objects) and all("object_sha256" in s for s in specs)
    assert deep.model_dir == str(tmp_path / "stress" / "mug" / "mug_04_deep")


def test_observed_views_see_each_trial_of_a_split_once_without_simulating(tmp_path):
    """``observed_views``: one view per trial spec (the smoke split: 2 drills, 1 placement), each the trial's own
    scenario and camera, a cloud of the object in W around its true position; several views or methods are
    refused with a one-line error."""
    from catgrasp_drake.benchmark.runner import observed_views, trial_scenario

    cfg = BenchmarkConfig(split="smoke", methods=("latent",), data_dir=str(tmp_path / "data"))
    views = list(observed_views(cfg))
    assert [v[0]["instance"] for v in views] == [s["instance"] for s in trial_specs(cfg)] == ["drill_00", "drill_01"]
    for spec, model, scenario, placement, camera, p_W, camera_W in views:
        assert model.category == "drill" and scenario.object.instance == spec["instance"]
        assert (placement, camera) == trial_scenario(spec)[1:] and "yaw_deg" in placement and "azimuth_deg" in camera
        assert p_W.shape[1] == 3 and len(p_W) > 200
        assert np.linalg.norm(p_W.mean(axis=0)[:2] - scenario.X_WO()[:2, 3]) < 0.1  # the object, not the table
        assert np.linalg.norm(camera_W - p_W.mean(axis=0)) > 0.3  # the camera stands back from it
    for bad in (replace(cfg, views=("single", "full")), replace(cfg, methods=("latent", "rigid"))):
        with pytest.raises(InputError, match="observed_views"):
            next(observed_views(bad))
