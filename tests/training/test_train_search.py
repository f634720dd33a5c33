"""Training with a per-instance robustness search, and the regressor chosen by leave-one-instance-out."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.descriptor import descriptor_vector, functional_point
from catgrasp_drake.grasping.robustness import Robustness
from catgrasp_drake.grasping.search import CemParams
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.training import InstanceSearch, TrainingConfig, fit_grasp_regressor, train_category

ANCHOR_H = np.array([0.0, 0.05, 0.1])


def _descriptors(x, shift_per_unit):
    """Descriptors of the drill's hand-written grasp moved by ``shift_per_unit @ x`` (m)."""
    template = load_handwritten_motion("drill", "drill_00")
    rows = []
    for xi in x:
        poses = template.poses.copy()
        poses[:, :3, 3] += shift_per_unit @ xi
        rows.append(descriptor_vector(type(template)(poses, template.pose_names, dict(template.postures), "object",
                                                     template.lift_height, template.hold_time)))
    return template, np.array(rows)


def test_auto_regression_finds_a_shape_dependent_grasp_and_beats_the_mean():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(10, 2))
    shift = np.array([[0.01, 0.0], [0.0, -0.008], [0.004, 0.0]])  # 1 cm per latent unit
    template, Y = _descriptors(x, shift)
    reg, selection = fit_grasp_regressor(x, Y, np.arange(10), np.ones(10), TrainingConfig(regressor="auto"),
                                         template, ANCHOR_H)
    by_family = selection["loo_error_mm_by_family"]
    assert selection["regressor"] in ("ridge", "kernel_ridge")
    assert selection["loo_error_mm"] < 0.5 * by_family["mean"]
    x_new = np.array([0.5, -1.0])
    truth = functional_point(_descriptors(x_new[None], shift)[1][0], template, ANCHOR_H)
    got = functional_point(reg.predict(x_new), template, ANCHOR_H)
    assert np.linalg.norm(got - truth) < 0.003  # the grasp moves by ~1.1 cm; predicted within 3 mm


def test_auto_regression_with_two_instances_falls_back_to_ridge_and_says_so():
    template, Y = _descriptors(np.zeros((2, 2)), np.zeros((3, 2)))
    reg, selection = fit_grasp_regressor(np.eye(2), Y, [0, 1], None, TrainingConfig(regressor="auto"), template,
                                         ANCHOR_H)
    assert reg.kind == "ridge" and "only 2 instances" in selection["note"]
    with pytest.raises(InputError, match="regressor"):
        TrainingConfig(regressor="forest")


@pytest.mark.slow
def test_a_small_search_keeps_scored_grasps_and_the_model_file_carries_them(tmp_path):
    instances = ["drill_00", "drill_05", "drill_07"]
    # one trial per candidate and drill (the nominal placement; scores 0, 0.2 or 1): the perturbed trials'
    # scoring is tests/station/test_variation.py's
    search = InstanceSearch(cem=CemParams(rounds=1, population=2, elite=1), robustness=Robustness(perturbations=1),
                            keep=2)
    config = TrainingConfig(search=search, regressor="auto", workers=2, cache_dir=str(tmp_path / "cache"))
    model = train_category("drill", instances, config)
    st = model.stats
    for name in instances:
        s = st["per_instance"][name]
        assert s["sampled"] == 2  # candidates
        trials = (s["sampled"] - s["rejected_constraint"]) * search.robustness.perturbations
        assert s["rejected_plan"] + s["simulated"] + s["errors"] == trials
        kept = st["search"][name]["kept"]
        assert len(kept) <= 2 and all(0 < k <= 1 for k in kept)
        assert st["search"][name]["best_score"] >= st["search"][name]["start_score"]
    assert st["trials_functional"] >= 1  # the warped canonical grasp works on these drills
    weights = np.concatenate([st["search"][n]["kept"] for n in instances])
    np.testing.assert_allclose(np.sort(model.training_weights), np.sort(weights), atol=1e-4)
    sel = st["regression"]  # chosen by the one-SE rule: never below the least error, never below its family's best
    assert sel["rule"] == "one_se"
    assert sel["loo_error_mm"] >= min(sel["loo_error_mm_by_family"].values())
    assert sel["loo_error_mm_by_family"][sel["regressor"]] <= sel["loo_error_mm"]
    path = tmp_path / "drill.npz"
    model.save(path)
    loaded = CategoryModel.load(path)
    assert loaded.regressor.kind == model.regressor.kind
    np.testing.assert_array_equal(loaded.training_weights, model.training_weights)
    x = loaded.space.latent_train[1]
    np.testing.assert_array_equal(loaded.regressor.predict(x), model.regressor.predict(x))


def test_refitting_a_committed_model_reproduces_its_regressor_under_the_same_choice():
    """The committed drill model's regressor is the mean under either rule: refitted from its stored training set
    (no simulation), it predicts the same grasp, and the file's stats say it was refitted."""
    from catgrasp_drake.demo import default_model_path
    from catgrasp_drake.training import refit_regressor

    model = CategoryModel.load(default_model_path("drill"), category="drill")
    again = refit_regressor(model)
    x = model.space.latent_train[:4]
    np.testing.assert_allclose(again.regressor.predict(x), model.regressor.predict(x), atol=1e-9)
    assert again.stats["regression"]["refitted"] and again.stats["regression"]["rule"] == "one_se"
    assert again.stats["search"] == model.stats["search"]  # the rest of the record is kept
