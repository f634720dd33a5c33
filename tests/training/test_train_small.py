"""End to end: a small training run gives a loadable model that reproduces its training grasps."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.training import TrainingConfig, train_category

from ..reliability import tiny_runs as tiny

#: The reliability tests' tiny training: three trials, two of them functional successes (tiny_runs.TRAIN_SEED).
INSTANCES = list(tiny.TRAIN_INSTANCES)


@pytest.fixture(scope="module")
def small_model(tmp_path_factory):
    cache = tmp_path_factory.mktemp("trial_cache")
    config = TrainingConfig(samples_per_instance=tiny.TRAIN_SAMPLES, seed=tiny.TRAIN_SEED, workers=2,
                            cache_dir=str(cache), ridge_alpha=1e-9)
    return train_category("drill", INSTANCES, config), config


@pytest.mark.slow
def test_small_training_learns_from_functional_successes(small_model):
    model, _ = small_model
    st = model.stats
    assert st["instances"] == 2 and st["trials_functional"] >= 1
    per = st["per_instance"]
    assert sum(p["sampled"] for p in per.values()) == 4
    for p in per.values():
        assert p["sampled"] == p["rejected_constraint"] + p["rejected_plan"] + p["simulated"] + p["errors"]


def test_model_round_trips_and_rejects_another_category(small_model, tmp_path):
    model, _ = small_model
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


def test_regressor_predicts_grasps_within_the_sampled_neighbourhood(small_model):
    model, _ = small_model
    grasp = model.template.pose_names.index("grasp")
    for i, name in enumerate(INSTANCES):
        if model.stats["per_instance"][name]["functional"] == 0:
            continue
        # every success was sampled within 4 cm / 0.2 rad of the canonical grasp (in canonical space,
        # after the inverse warp); the interpolating regressor must stay in that neighbourhood
        pred = model.canonical_motion(model.space.latent_train[i]).poses[grasp]
        ref = model.template.poses[grasp]
        assert np.linalg.norm(pred[:3, 3] - ref[:3, 3]) < 0.045
        cos = (np.trace(ref[:3, :3].T @ pred[:3, :3]) - 1) / 2
        assert np.arccos(np.clip(cos, -1, 1)) < 0.25


def test_transfer_with_identity_pose_equals_the_warped_motion(small_model):
    model, _ = small_model
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
