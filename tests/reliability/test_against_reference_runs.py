"""Runs compared with an uninterrupted reference run of the same seed: kill -9 and resume, and the same run twice;
and what the small training learnt (its model, loaded, predicting and transferring).

The kill tests run the real ``catgrasp`` command line in a subprocess, SIGKILL its whole process
group (the CLI and its worker processes) once some but not all trials are cached, run the same
command again, and compare with an uninterrupted run of the same seed: the model array by array,
bit for bit; the evaluation records field by field except the named timing fields. The
reproducibility tests run the same training (a library call with worker processes) and the same
evaluation trial (in this process) again and compare with the same references.

The reference runs (``tiny_runs``) are made once per process; these tests share one file so that
``pytest -n auto --dist loadfile`` runs them in one worker and the references are made once.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.runner import TaskCache, task_key

from . import tiny_runs as tiny

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _check_cache_files(cache: Path) -> dict[str, dict]:
    """Every cached trial is a whole, checksummed file named by its spec's key; returns key -> record."""
    out = {}
    for f in tiny.cached_files(cache):
        record = json.loads(f.read_text())  # raises on a half-written file
        assert f.stem == record["key"]
        assert task_key(record["spec"], record["code_version"]) == record["key"]
        assert TaskCache(cache, record["code_version"]).get(record["key"]) == record["result"]  # checksum ok
        out[record["key"]] = record
    return out


# ----------------------------------------------------------------------------- kill -9: training
@pytest.mark.slow
def test_kill_minus_9_during_training_then_resume_gives_the_uninterrupted_model(tmp_path):
    tiny.start_reference_training()  # in the background, one worker: runs beside the interrupted run
    cache, model = tmp_path / "cache", tmp_path / "model.npz"
    cmd = tiny.train_command(cache, model, workers=2)

    run = tiny.Run(cmd, tmp_path / "killed")
    at_kill = tiny.kill_after(run, cache, at_least=1)
    assert not model.exists()
    before = _check_cache_files(cache)
    ids_before = tiny.file_ids(tiny.cached_files(cache))
    tiny.Run(cmd, tmp_path / "resumed").wait()

    ref_model, ref_cache, _ = tiny.reference_training()
    tiny.skip_if_code_changed(cache, ref_cache)
    ref = _check_cache_files(ref_cache)
    after = _check_cache_files(cache)
    assert 1 <= at_kill < len(ref), f"killed with {at_kill} of {len(ref)} trials cached: not in the middle"
    # every trial once: the same specs (keys) as the uninterrupted run, none lost, none extra
    assert set(after) == set(ref) and set(before) <= set(after)
    # the trials finished before the kill were read back, not recomputed (an atomic rewrite changes the inode)
    assert {k: v for k, v in tiny.file_ids(tiny.cached_files(cache)).items() if k in ids_before} == ids_before
    # identical outcomes, trial by trial (wall-clock timings aside)
    for k in ref:
        a = {f: v for f, v in after[k]["result"].items() if f not in tiny.TRIAL_TIMING_FIELDS}
        b = {f: v for f, v in ref[k]["result"].items() if f not in tiny.TRIAL_TIMING_FIELDS}
        assert a == b, k
    # the model: every array bit for bit, every statistic but the wall-clock ones
    assert tiny.model_differences(model, ref_model) == []
    _, header = tiny.model_contents(model)
    stats = header["meta"]["stats"]
    assert tiny.trial_count(stats) == len(ref)  # trials counted = specs run: none lost, none counted twice
    assert sum(p["sampled"] for p in stats["per_instance"].values()) == tiny.TRAIN_SAMPLES * len(tiny.TRAIN_INSTANCES)


# ----------------------------------------------------------------------------- kill -9: evaluation
@pytest.mark.slow
def test_kill_minus_9_during_evaluation_then_resume_gives_the_uninterrupted_records(tmp_path):
    from catgrasp_drake.evaluation import TIMING_FIELDS, load_records, load_report

    assert set(TIMING_FIELDS) == {"inference_s", "observe_s", "trial_wall_s"}  # the fields allowed to differ
    tiny.start_reference_evaluation()
    out = tiny.prepare_eval_dir(tmp_path / "eval")
    cmd = tiny.eval_command(out, workers=1)  # one worker: trials in sequence, the kill lands between them
    at_kill = tiny.kill_after(tiny.Run(cmd, tmp_path / "killed"), tiny.eval_cache(out), at_least=1)
    assert at_kill == 1 and not tiny.records_path(out).exists()
    ids_before = tiny.file_ids(tiny.cached_files(tiny.eval_cache(out)))
    tiny.Run(cmd, tmp_path / "resumed").wait()

    ref_out, _ = tiny.reference_evaluation()
    tiny.skip_if_code_changed(tiny.eval_cache(out), tiny.eval_cache(ref_out))
    records, ref_records = load_records(tiny.records_path(out)), load_records(tiny.records_path(ref_out))
    keys = [(r["instance"], r["view"], r["method"]) for r in records]
    assert sorted(keys) == sorted((tiny.EVAL_INSTANCE, tiny.EVAL_VIEW, m) for m in tiny.EVAL_METHODS)  # each once
    assert all(r.get("status") == "ok" for r in records)  # real trials, not errors

    def outcome(r):
        return {k: v for k, v in r.items() if k not in TIMING_FIELDS}

    assert [outcome(r) for r in records] == [outcome(r) for r in ref_records]
    assert len(tiny.cached_files(tiny.eval_cache(out))) == len(records)
    assert {k: v for k, v in tiny.file_ids(tiny.cached_files(tiny.eval_cache(out))).items()
            if k in ids_before} == ids_before
    report, ref_report = load_report(out / "drill" / "report.json"), load_report(ref_out / "drill" / "report.json")
    assert report["table"] == ref_report["table"]


# ----------------------------------------------------------------------------- same seed, same results
@pytest.fixture(scope="module")
def library_training(tmp_path_factory):
    """``(model, cache dir)``: the reference training's seed run again as a library call with worker processes
    (started beside the reference CLI run, which runs in the background with one worker)."""
    from catgrasp_drake.training import TrainingConfig, train_category

    tiny.start_reference_training()
    cache = tmp_path_factory.mktemp("library_training") / "cache"
    config = TrainingConfig(samples_per_instance=tiny.TRAIN_SAMPLES, seed=tiny.TRAIN_SEED, workers=2,
                            cache_dir=str(cache))
    return train_category(tiny.TRAIN_CATEGORY, list(tiny.TRAIN_INSTANCES), config), cache


@pytest.mark.slow
def test_training_twice_with_the_same_seed_gives_a_bit_identical_model(library_training, tmp_path):
    """A library call with worker processes vs the reference CLI run with one worker (other process, other
    scheduling, other trial order per process): every array bit for bit, every statistic but timings."""
    model, cache = library_training
    model.save(tmp_path / "model.npz")
    ref_model, ref_cache, _ = tiny.reference_training()
    tiny.skip_if_code_changed(cache, ref_cache)
    assert tiny.model_differences(tmp_path / "model.npz", ref_model) == []
    assert model.stats["trials_functional"] >= 1  # a model learnt from real successes
    # trial by trial, too
    mine = {f.name: json.loads(f.read_text())["result"] for f in tiny.cached_files(cache)}
    ref = {f.name: json.loads(f.read_text())["result"] for f in tiny.cached_files(ref_cache)}
    assert sorted(mine) == sorted(ref)

    def outcome(r):
        return {k: v for k, v in r.items() if k not in tiny.TRIAL_TIMING_FIELDS}

    assert all(outcome(mine[k]) == outcome(ref[k]) for k in ref)


# ----------------------------------------------------------------------------- what the small training learnt
@pytest.mark.slow
def test_small_training_learns_from_functional_successes(library_training):
    model, _ = library_training
    st = model.stats
    assert st["instances"] == 2 and st["trials_functional"] >= 1
    per = st["per_instance"]
    assert sum(p["sampled"] for p in per.values()) == tiny.TRAIN_SAMPLES * len(tiny.TRAIN_INSTANCES)
    for p in per.values():
        assert p["sampled"] == p["rejected_constraint"] + p["rejected_plan"] + p["simulated"] + p["errors"]


@pytest.mark.slow
def test_model_round_trips_and_rejects_another_category(library_training, tmp_path):
    model, _ = library_training
    path = tmp_path / "drill.npz"
    model.save(path)
    loaded = CategoryModel.load(path, category="drill")
    x = loaded.space.latent_train[0]
    assert np.allclose(loaded.regressor.predict(x), model.regressor.predict(x))
    assert loaded.template == model.template
    with pytest.raises(InputError, match="not 'mug'"):
        CategoryModel.load(path, category="mug")
    path.write_bytes(path.read_bytes()[:200])
    with pytest.raises(ModelFileError):
        CategoryModel.load(path)


@pytest.mark.slow
def test_regressor_predicts_grasps_within_the_sampled_neighbourhood(library_training):
    model, _ = library_training
    grasp = model.template.pose_names.index("grasp")
    for i, name in enumerate(tiny.TRAIN_INSTANCES):
        if model.stats["per_instance"][name]["functional"] == 0:
            continue
        # every success was sampled within 4 cm / 0.2 rad of the canonical grasp (in canonical space,
        # after the inverse warp); the regressor must stay in that neighbourhood
        pred = model.canonical_motion(model.space.latent_train[i]).poses[grasp]
        ref = model.template.poses[grasp]
        assert np.linalg.norm(pred[:3, 3] - ref[:3, 3]) < 0.045
        cos = (np.trace(ref[:3, :3].T @ pred[:3, :3]) - 1) / 2
        assert np.arccos(np.clip(cos, -1, 1)) < 0.25


@pytest.mark.slow
def test_transfer_with_identity_pose_equals_the_warped_motion(library_training):
    model, _ = library_training
    x = model.space.latent_train[1]
    warped = model.warped_motion(x)
    moved = model.transfer(x, np.eye(3), np.zeros(3), 1.0, frame="object")
    assert np.allclose(warped.poses, moved.poses)
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    world = model.transfer(x, R, np.array([0.5, 0.0, 0.0]), 1.1)
    assert np.allclose(world.poses[:, :3, :3], R @ warped.poses[:, :3, :3])
    # the grasp centre (anchor) is scaled with the object; the hand stays rigid about it
    a = np.asarray(model.grasp_anchor_H)
    centre = lambda P: P[:, :3, 3] + P[:, :3, :3] @ a  # noqa: E731
    assert np.allclose(centre(world.poses), 1.1 * centre(warped.poses) @ R.T + [0.5, 0, 0])
    dist = np.linalg.norm(world.poses[:, :3, 3] - centre(world.poses), axis=1)
    assert np.allclose(dist, np.linalg.norm(a))


@pytest.mark.slow
def test_one_evaluation_trial_twice_gives_the_same_record():
    """The reference evaluation's latent trial (a CLI subprocess) run again in this process: same record,
    the named timing fields aside."""
    from catgrasp_drake.evaluation import TIMING_FIELDS, eval_trial_task

    ref_out, _ = tiny.reference_evaluation()
    cached = [json.loads(f.read_text()) for f in tiny.cached_files(tiny.eval_cache(ref_out))]
    (ref,) = [c for c in cached if c["spec"]["method"] == "latent"]
    again = eval_trial_task(ref["spec"])
    again.setdefault("status", "ok")
    assert ref["result"]["status"] == "ok" and ref["result"]["sim_s"] > 0  # an executed trial, not an error

    def outcome(r):
        return {k: v for k, v in r.items() if k not in TIMING_FIELDS}

    assert outcome(again) == outcome(ref["result"])
    assert set(again) - set(outcome(again)) == set(TIMING_FIELDS)
