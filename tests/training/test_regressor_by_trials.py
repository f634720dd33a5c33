"""The latent -> grasp regressor chosen by leave-one-instance-out grasp trials (``--regressor trials``).

The trials are replaced by a stand-in judge with a known answer (which grasps "hold"), so the test checks the
choice's plumbing -- what is left out, what is predicted, warped and scored, and the one-standard-error rule --
without simulating; the committed mug model supplies a real shape space and training set.
"""

from __future__ import annotations

import numpy as np
import pytest

import catgrasp_drake.training as training
from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.deformation import warp_poses
from catgrasp_drake.core.regression import simplest_within_one_se
from catgrasp_drake.demo import default_model_path
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.descriptor import descriptor_vector, motion_from_descriptor
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.runner import TaskOutcome


def test_the_one_se_rule_keeps_the_simplest_candidate_unless_a_richer_one_is_clearly_better():
    order = ("canonical", "mean", "ridge")
    noisy_best = {"canonical": [1, 1, 1, 0.2], "mean": [1, 1, 1, 1], "ridge": [1, 1, 1, 1]}
    assert simplest_within_one_se(noisy_best, order) == "mean"  # the best is certain (SE 0): 0.8 is not within it
    close = {"canonical": [1, 1, 0.2, 1, 1], "mean": [1, 1, 1, 0.2, 1], "ridge": [1, 1, 1, 1, 0.5]}
    assert simplest_within_one_se(close, order) == "canonical"  # 0.84 vs 0.9 +- 0.1
    assert simplest_within_one_se({"canonical": [0, 0], "mean": [1, 0], "ridge": [1, 0]}, order) == "canonical"
    assert simplest_within_one_se({"canonical": [0, 0, 0], "mean": [1, 1, 0.8], "ridge": [1, 1, 1]}, order) == "ridge"
    with pytest.raises(InputError, match="scores"):
        simplest_within_one_se({"canonical": [1.0], "mean": [np.nan], "ridge": [1.0]}, order)
    with pytest.raises(InputError, match="scores"):
        simplest_within_one_se({"canonical": [1.0]}, order)


@pytest.fixture(scope="module")
def mug_model():
    return CategoryModel.load(default_model_path("mug"), category="mug")


def _choose(model, holds, monkeypatch):
    """The trial choice on ``model``'s stored training set with ``holds(motion, instance) -> bool`` as judge."""
    seen = []

    def fake_run_tasks(fn, specs, **kw):
        out = []
        for spec in specs:
            m = GraspMotion.from_dict(spec["motion"])
            seen.append((spec["instance"], spec["perturbation"]["dx"], m))
            ok = holds(m, spec["instance"])
            out.append(TaskOutcome(key="", spec=spec, result={"functional": ok, "grasp": ok}, cached=False))
        return out

    monkeypatch.setattr(training, "run_tasks", fake_run_tasks)
    g = model.stats["regression"].get("by_loo_error", model.stats["regression"])
    hyper = g.get("hyperparameters_by_family") or {"mean": {}, "ridge": {"alpha": 100.0},
                                                    "kernel_ridge": {"length_scale": 4.0, "alpha": 1.0},
                                                    "nearest": {}}
    reg, record = training.choose_regressor_by_trials(
        "mug", model.space, list(model.instances), model.template, np.asarray(model.grasp_anchor_H),
        model.training_latent, model.training_descriptors, model.training_groups, model.training_weights, hyper,
        training.Robustness(perturbations=2), training.TrainingConfig(cache_dir=None))
    return reg, record, seen


def test_the_canonical_grasp_is_kept_when_only_it_holds(mug_model, monkeypatch):
    canonical_postures = dict(mug_model.template.postures)

    def holds(m, instance):  # the learned grasps average the searched postures: only the canonical's hold
        return all(np.allclose(m.postures[k], v) for k, v in canonical_postures.items())

    reg, record, seen = _choose(mug_model, holds, monkeypatch)
    n = len(mug_model.instances)
    assert record["regressor"] == "canonical" and record["trial_score"] == 1.0
    assert record["trials"] == len(seen) == 5 * n * 2  # 5 candidates x every instance x 2 perturbations
    assert {s[0] for s in seen} == set(mug_model.instances)
    assert all(v == 0.0 for v in record["trial_score_by_candidate"].values() if v != 1.0)
    x = mug_model.space.latent_train[3]
    np.testing.assert_allclose(reg.predict(x), descriptor_vector(mug_model.template))  # shape is ignored
    # the canonical candidate's grasp on instance i is the canonical motion warped by W(x_i), at both placements
    i = 5
    want = _warped(mug_model, descriptor_vector(mug_model.template), i)
    got = [m for inst, dx, m in seen if inst == mug_model.instances[i] and holds(m, inst)]
    assert len(got) == 2 and all(np.allclose(m.poses, want.poses, atol=1e-9) for m in got)


def test_a_learned_regressor_is_chosen_when_the_canonical_grasp_fails(mug_model, monkeypatch):
    canonical_postures = dict(mug_model.template.postures)

    def holds(m, instance):
        return not all(np.allclose(m.postures[k], v) for k, v in canonical_postures.items())

    reg, record, _ = _choose(mug_model, holds, monkeypatch)
    assert record["trial_score_by_candidate"]["canonical"] == 0.0
    assert record["regressor"] == "mean"  # every learned candidate holds: the simplest of them
    x = mug_model.space.latent_train
    pred = reg.predict(x)
    assert np.abs(pred - pred[0]).max() < 1e-5  # the mean ignores x (up to its 1e12 ridge penalty)


def test_left_out_instances_never_see_their_own_grasps(mug_model, monkeypatch):
    """The nearest-instance candidate, trained without instance i, must not return i's own grasp."""
    own = {name: mug_model.instance_descriptor(k) for k, name in enumerate(mug_model.instances)
           if k in set(mug_model.training_groups.tolist())}
    template = mug_model.template
    violations = []

    def holds(m, instance):
        k = list(mug_model.instances).index(instance)
        if instance in own:
            mine = _warped(mug_model, own[instance], k)
            if np.allclose(m.poses, mine.poses, atol=1e-9) and not np.allclose(own[instance],
                                                                                 descriptor_vector(template)):
                violations.append(instance)
        return True

    _choose(mug_model, holds, monkeypatch)
    assert violations == []


def _warped(model, descriptor, k):
    """The canonical ``descriptor`` warped onto training instance ``k`` by W(x_k) (instance frame)."""
    m = motion_from_descriptor(descriptor, model.template)
    poses = warp_poses(model.space.canonical, model.space.decode(model.space.latent_train[k]), model.space.beta,
                       m.poses, **model.warp_options())
    return GraspMotion(poses, m.pose_names, dict(m.postures), "object", m.lift_height, m.hold_time)


def test_refit_by_trials_records_both_choices_and_the_cli_writes_the_model(mug_model, monkeypatch, tmp_path, capsys):
    """``refit_regressor(..., regressor="trials")`` runs the choice with the robustness the model was searched with
    and keeps the functional-point choice it replaced; ``catgrasp refit`` writes the result where asked."""
    calls = []

    def fake_run_tasks(fn, specs, **kw):
        calls.append(specs)
        return [TaskOutcome(key="", spec=s, result={"functional": True, "grasp": True}, cached=False) for s in specs]

    monkeypatch.setattr(training, "run_tasks", fake_run_tasks)
    again = training.refit_regressor(mug_model, training.TrainingConfig(regressor="trials", cache_dir=None))
    reg = again.stats["regression"]
    assert reg["chosen_by"] == "trials" and reg["refitted"] and reg["regressor"] == "canonical"  # all tie: simplest
    assert reg["by_loo_error"]["regressor"] == "mean" and "loo_error_mm" in reg["by_loo_error"]
    searched = mug_model.params["search"]["robustness"]["perturbations"]
    assert len(calls[0]) == 5 * len(mug_model.instances) * searched
    assert again.params["regressor"] == "trials"
    # the CLI, choosing by the functional-point error (no trials), on a copy of the committed model
    from catgrasp_drake.cli import main

    out = tmp_path / "mug.npz"
    assert main(["refit", "mug", "--regressor", "auto", "--out", str(out)]) == 0
    assert "leave-one-instance-out error at the functional point: mean" in capsys.readouterr().out
    refitted = CategoryModel.load(out, category="mug")
    assert refitted.stats["regression"]["regressor"] == "mean" and refitted.regressor.kind == "ridge"
    assert main(["refit", "drill", "--model", str(out)]) == 2  # a mug model is not a drill model
