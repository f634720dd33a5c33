"""Every method as a predictor system with the regressor's ports, swapped into the transfer diagram."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.demo import default_model_path
from catgrasp_drake.errors import InputError
from catgrasp_drake.perception.object_cloud import cloud_from_points
from catgrasp_drake.prediction import METHODS, predict_motion
from catgrasp_drake.station.scenario import load_scenario, with_instance
from catgrasp_drake.systems.predictors import GraspPredictor
from catgrasp_drake.transfer import make_transfer_diagram


@pytest.fixture(scope="module")
def drill():
    return CategoryModel.load(default_model_path("drill"), category="drill")


def _pose():
    return RigidTransform(RollPitchYaw(0.0, 0.0, 0.4), [0.6, 0.05, 0.0]).GetAsMatrix4()


def test_cpd_on_an_observation_equal_to_the_aligned_canonical_shape_is_the_rigid_grasp(drill):
    X_WO, s = _pose(), 1.1
    canonical_W = s * drill.space.canonical @ X_WO[:3, :3].T + X_WO[:3, 3]
    rigid, _ = predict_motion("rigid", drill, np.zeros(drill.space.q), X_WO, s)
    cpd, _ = predict_motion("cpd", drill, np.zeros(drill.space.q), X_WO, s, observed_W=canonical_W,
                            completed_W=canonical_W)
    np.testing.assert_allclose(cpd.poses, rigid.poses, atol=2e-4)  # no deformation to find: the same grasp
    with pytest.raises(InputError, match="cpd method needs"):
        predict_motion("cpd", drill, np.zeros(drill.space.q), X_WO, s)


def test_cpd_keeps_the_pregrasp_offset_from_the_warped_grasp(drill):
    X_WO, s = _pose(), 1.0
    canonical_W = drill.space.canonical @ X_WO[:3, :3].T + X_WO[:3, 3]
    stretched = canonical_W.copy()
    stretched[:, 2] = (stretched[:, 2] - X_WO[2, 3]) * 1.15 + X_WO[2, 3]  # a taller drill
    cpd, _ = predict_motion("cpd", drill, np.zeros(drill.space.q), X_WO, s, observed_W=stretched,
                            completed_W=canonical_W)
    rigid, _ = predict_motion("rigid", drill, np.zeros(drill.space.q), X_WO, s)
    names = list(cpd.pose_names)
    pre, grasp = names.index("pregrasp"), names.index("grasp")
    offset_cpd = np.linalg.solve(cpd.poses[grasp], cpd.poses[pre])
    offset_rigid = np.linalg.solve(rigid.poses[grasp], rigid.poses[pre])
    np.testing.assert_allclose(offset_cpd, offset_rigid, atol=1e-9)
    assert cpd.poses[grasp][2, 3] > rigid.poses[grasp][2, 3] + 0.005  # the grasp rose with the taller handle


@pytest.mark.parametrize("method", [m for m in METHODS if m != "cpd"])
def test_predictor_ports_give_the_pure_function(drill, method):
    sys = GraspPredictor(drill, method)
    ctx = sys.CreateDefaultContext()
    x = np.linspace(-0.5, 0.5, drill.space.q)
    X_WO = _pose()
    sys.GetInputPort("x").FixValue(ctx, x)
    sys.GetInputPort("X_WO").FixValue(ctx, RigidTransform(X_WO))
    sys.GetInputPort("scale").FixValue(ctx, [0.95])
    got = sys.GetOutputPort("grasp_motion_W").Eval(ctx)
    want, _ = predict_motion(method, drill, x, X_WO, 0.95)
    np.testing.assert_array_equal(got.poses, want.poses)
    assert got.frame == "world"


def test_cpd_predictor_reads_its_clouds(drill):
    sys = GraspPredictor(drill, "cpd")
    ctx = sys.CreateDefaultContext()
    X_WO = _pose()
    canonical_W = drill.space.canonical @ X_WO[:3, :3].T + X_WO[:3, 3]
    sys.GetInputPort("x").FixValue(ctx, np.zeros(drill.space.q))
    sys.GetInputPort("X_WO").FixValue(ctx, RigidTransform(X_WO))
    sys.GetInputPort("scale").FixValue(ctx, [1.0])
    sys.GetInputPort("observed_cloud_W").FixValue(ctx, cloud_from_points(canonical_W))
    sys.GetInputPort("completed_cloud_W").FixValue(ctx, cloud_from_points(canonical_W))
    got = sys.GetOutputPort("grasp_motion_W").Eval(ctx)
    want, _ = predict_motion("rigid", drill, np.zeros(drill.space.q), X_WO, 1.0)
    np.testing.assert_allclose(got.poses, want.poses, atol=2e-4)


def test_every_method_builds_the_transfer_diagram_with_its_own_estimator(drill):
    scenario = with_instance(load_scenario("drill_default"), "drill_12")
    for method in METHODS:
        td = make_transfer_diagram(scenario, drill, method=method)
        assert td.regressor.method == method
        ctx = td.diagram.CreateDefaultContext()
        est_ctx = td.estimator.GetMyContextFromRoot(ctx)
        visibility = td.estimator.GetInputPort("X_WC").HasValue(est_ctx)
        assert visibility == (method != "paper")  # the paper's fit has no visibility model
        rigid = not np.any(td.estimator.space.components)
        assert rigid == (method in ("rigid", "cpd"))
    with pytest.raises(InputError, match="unknown method"):
        make_transfer_diagram(scenario, drill, method="oracle")


def test_the_plan_is_made_once_for_every_method_while_the_simulation_steps(drill):
    """Moving the object (what the camera sees) and time passing after the estimate must not re-run
    prediction or planning."""
    from catgrasp_drake.transfer import run_transfer  # noqa: F401  (the diagram is the product's)

    scenario = with_instance(load_scenario("drill_default"), "drill_12")
    for method in ("latent", "cpd", "true_object"):
        td = make_transfer_diagram(scenario, drill, method=method)
        ctx = td.diagram.CreateDefaultContext()
        est_ctx = td.estimator.GetMyMutableContextFromRoot(ctx)
        td.estimator.set_estimate(est_ctx, td.estimator.estimate_now(est_ctx))
        gen_ctx = td.generator.GetMyContextFromRoot(ctx)
        plan = td.generator.GetOutputPort("plan").Eval(gen_ctx)
        plant_ctx = td.station.plant.GetMyMutableContextFromRoot(ctx)
        X = td.station.plant.GetFreeBodyPose(plant_ctx, td.station.object_body)
        td.station.plant.SetFreeBodyPose(plant_ctx, td.station.object_body,
                                         RigidTransform(X.rotation(), X.translation() + [0.0, 0.05, 0.0]))
        ctx.SetTime(1.0)  # and time passes, as in the simulation
        again = td.generator.GetOutputPort("plan").Eval(gen_ctx)
        assert again is plan, f"{method}: the plan was recomputed after the scene changed"


def _moved(X, dx):
    X = X.copy()
    X[0, 3] += dx
    return X


def test_grasp_candidates_rank_by_the_posterior_mass_that_agrees_with_them(drill):
    """Two hypotheses put the object 5 cm from where the MAP fit does: at T = 15 nats their joint weight (0.58)
    outweighs the MAP's (0.42), so their grasp comes first; at T = 1 the MAP's weight (0.99) wins."""
    from catgrasp_drake.prediction import ShapeHypothesis, grasp_candidates, hypothesis_weights

    q = drill.space.q
    X0 = _pose()
    hyps = [ShapeHypothesis(np.zeros(q), X0, 1.0, np.zeros((4, 3)), -100.0),
            ShapeHypothesis(np.zeros(q), _moved(X0, 0.05), 1.0, np.ones((4, 3)), -95.0),
            ShapeHypothesis(np.zeros(q), _moved(X0, 0.05), 1.0, 2 * np.ones((4, 3)), -94.0)]
    w = np.exp([0.0, -5.0 / 15.0, -6.0 / 15.0])
    np.testing.assert_allclose(hypothesis_weights([-100.0, -95.0, -94.0]), w / w.sum())
    ranked = grasp_candidates("latent", drill, hyps)
    assert [c.hypothesis for c in ranked] == [1, 2, 0]
    assert ranked[0].support == pytest.approx((w[1] + w[2]) / w.sum())
    assert ranked[2].support == pytest.approx(w[0] / w.sum())
    np.testing.assert_array_equal(ranked[0].object_points_W, hyps[1].completed_W)  # its own shape to plan around
    np.testing.assert_allclose(ranked[0].functional_point_W - ranked[2].functional_point_W, [0.05, 0, 0], atol=1e-12)
    map_motion, _ = predict_motion("latent", drill, np.zeros(q), X0, 1.0)
    np.testing.assert_array_equal(ranked[2].motion.poses, map_motion.poses)
    assert [c.hypothesis for c in grasp_candidates("latent", drill, hyps, temperature=1.0)] == [0, 1, 2]
    with pytest.raises(InputError, match="at least one"):
        grasp_candidates("latent", drill, [])
    with pytest.raises(InputError, match="temperature"):
        hypothesis_weights([1.0], temperature=0.0)


def test_latent_plain_weights_the_hypotheses_by_their_plain_energy_and_latent_by_the_fit(drill):
    """The MAP fit by the visibility-aware energy (-100) is 80 nats behind the other hypothesis by the plain energy:
    ``latent_plain`` puts the other hypothesis' grasp first, ``latent`` the MAP fit's; ``latent_plain`` without a
    plain energy for every hypothesis is a one-line error."""
    from catgrasp_drake.prediction import ShapeHypothesis, grasp_candidates, ranking_energies

    q = drill.space.q
    X0 = _pose()
    hyps = [ShapeHypothesis(np.zeros(q), X0, 1.0, np.zeros((4, 3)), -100.0, -300.0),
            ShapeHypothesis(np.zeros(q), _moved(X0, 0.05), 1.0, np.ones((4, 3)), -90.0, -380.0)]
    assert ranking_energies("latent_plain", hyps) == [-300.0, -380.0]
    assert ranking_energies("latent", hyps) == [-100.0, -90.0]
    assert [c.hypothesis for c in grasp_candidates("latent_plain", drill, hyps)] == [1, 0]
    assert [c.hypothesis for c in grasp_candidates("latent", drill, hyps)] == [0, 1]
    unknown = [hyps[0], ShapeHypothesis(np.zeros(q), _moved(X0, 0.05), 1.0, np.ones((4, 3)), -90.0)]
    assert ranking_energies("latent", unknown) == [-100.0, -90.0]
    with pytest.raises(InputError, match="plain_energies=True"):
        grasp_candidates("latent_plain", drill, unknown)


def test_drill_hypotheses_are_ranked_by_energy_plus_their_uncovered_observed_points(drill):
    """On drills (``COVERAGE_RANKED_CATEGORIES``) a hypothesis pays UNCOVERED_NATS per observed point its completed
    shape leaves uncovered: the MAP fit (-100 nats) leaving 40 points is ranked behind one at -90 leaving 2; for
    another category, or ``latent_plain``, the same hypotheses keep their energies."""
    import dataclasses

    from catgrasp_drake.prediction import UNCOVERED_NATS, ShapeHypothesis, grasp_candidates, ranking_energies

    q = drill.space.q
    X0 = _pose()
    hyps = [ShapeHypothesis(np.zeros(q), X0, 1.0, np.zeros((4, 3)), -100.0, -300.0, 40),
            ShapeHypothesis(np.zeros(q), _moved(X0, 0.05), 1.0, np.ones((4, 3)), -90.0, -380.0, 2)]
    assert ranking_energies("latent", hyps, "drill") == [-100.0 + 40 * UNCOVERED_NATS, -90.0 + 2 * UNCOVERED_NATS]
    assert ranking_energies("latent", hyps, "mug") == ranking_energies("latent", hyps) == [-100.0, -90.0]
    assert ranking_energies("latent_plain", hyps, "drill") == [-300.0, -380.0]
    assert [c.hypothesis for c in grasp_candidates("latent", drill, hyps)] == [1, 0]
    mug_like = dataclasses.replace(drill, category="mug")
    assert [c.hypothesis for c in grasp_candidates("latent", mug_like, hyps)] == [0, 1]


def test_mug_hypotheses_are_reseeded_from_the_best_shape_and_no_other_category_or_method_is(drill):
    """``RESEEDED_CATEGORIES`` (mugs): the methods that keep several shape hypotheses fit a mug with
    ``reseed=True``; a drill, or a mug by a method with one hypothesis, is fitted as before. The transfer
    diagram's estimator carries exactly those options, and the caller's own win."""
    from catgrasp_drake.prediction import RESEEDED_CATEGORIES, estimator_kwargs

    assert RESEEDED_CATEGORIES == ("mug",)
    assert estimator_kwargs("latent", "mug") == {"hypotheses": 3, "reseed": True}
    assert estimator_kwargs("latent", "drill") == estimator_kwargs("latent") == {"hypotheses": 3}
    assert "reseed" not in estimator_kwargs("paper", "mug") and "reseed" not in estimator_kwargs("latent_map", "mug")
    mug = CategoryModel.load(default_model_path("mug"), category="mug")
    scenario = with_instance(load_scenario("mug_default"), "mug_12")
    assert make_transfer_diagram(scenario, mug, method="latent").estimator.inference_kwargs["reseed"] is True
    assert make_transfer_diagram(scenario, mug, method="latent", reseed=False).estimator.inference_kwargs[
        "reseed"] is False
    drill_scenario = with_instance(load_scenario("drill_default"), "drill_12")
    assert "reseed" not in make_transfer_diagram(drill_scenario, drill, method="latent").estimator.inference_kwargs
