"""Generated objects stand on their own: the tipping-angle rule, and why its threshold is where it is (physics)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from catgrasp_drake.benchmark.runner import VAL_SEED
from catgrasp_drake.data.categories import build_drill, drill_params, generate_instance
from catgrasp_drake.data.dataset import instance_seed, models_dir, write_instance
from catgrasp_drake.data.meshes import MIN_TIPPING_ANGLE_DEG, tipping_angle_deg

from .standing import tilt_after


def test_tipping_angle_of_a_box_and_of_a_leaning_tower():
    box = trimesh.creation.box([0.1, 0.1, 0.2])  # centre of mass 0.1 m above a base 0.05 m from its edge
    assert tipping_angle_deg(box) == pytest.approx(np.degrees(np.arctan(0.5)), abs=1e-6)
    tower = trimesh.creation.box([0.02, 0.02, 0.3])
    tower.apply_transform(trimesh.transformations.shear_matrix(np.radians(5.0), [0, 1, 0], [0, 0, 0], [0, 0, 1]))
    assert tipping_angle_deg(tower) < 0.0  # its top overhangs the base: it falls
    assert tipping_angle_deg(box, [0.0, 0.0, 0.0]) == pytest.approx(np.degrees(np.arctan(0.5)), abs=1e-6)
    assert tipping_angle_deg(box, [0.04, 0.0, 0.0]) == pytest.approx(np.degrees(np.arctan(0.1)), abs=1e-6)


def _first_draw_of_val_drill_09():
    return build_drill(drill_params(np.random.default_rng(instance_seed("drill", 9, VAL_SEED))))


def test_a_draw_that_would_not_stand_is_drawn_again():
    first = _first_draw_of_val_drill_09()
    assert tipping_angle_deg(first.mesh) < MIN_TIPPING_ANGLE_DEG  # 2.5 deg
    kept = generate_instance("drill", np.random.default_rng(instance_seed("drill", 9, VAL_SEED)))
    assert kept.params != first.params and tipping_angle_deg(kept.mesh) >= MIN_TIPPING_ANGLE_DEG
    angles = [tipping_angle_deg(generate_instance("drill", np.random.default_rng([5, 0, i])).mesh) for i in range(40)]
    assert min(angles) >= MIN_TIPPING_ANGLE_DEG


#: The fourth fresh seed's first draw of drill_00 (session 46): 4.05 deg, above the first threshold (4.0); in all 9 of
#: its benchmark trials it fell over by itself before the hand closed.
FOURTH_FRESH_SEED = 2052585530


def _first_draw_of_fourth_seed_drill_00():
    return build_drill(drill_params(np.random.default_rng(instance_seed("drill", 0, FOURTH_FRESH_SEED))))


def test_a_draw_of_4_05_deg_is_drawn_again_and_the_least_stable_committed_drill_is_kept():
    first = _first_draw_of_fourth_seed_drill_00()
    assert tipping_angle_deg(first.mesh) == pytest.approx(4.05, abs=0.01)
    kept = generate_instance("drill", np.random.default_rng(instance_seed("drill", 0, FOURTH_FRESH_SEED)))
    assert kept.params != first.params and tipping_angle_deg(kept.mesh) >= MIN_TIPPING_ANGLE_DEG
    committed = trimesh.load(models_dir() / "objects" / "drill" / "drill_11" / "drill_11.obj", force="mesh")
    assert MIN_TIPPING_ANGLE_DEG <= tipping_angle_deg(committed) < 4.6  # 4.55 deg: it stands (below)


def test_an_import_of_the_rejected_draw_is_said_not_to_stand(tmp_path):
    from catgrasp_drake.data.importer import import_mesh

    first = _first_draw_of_val_drill_09()
    imported = import_mesh(first.mesh, "drill", "d", transform="0 0 0 0 0 0", regions=first.regions, mass_kg=1.0,
                           base_flatten_m=0.0, out=tmp_path / "d")
    rec = imported.record
    assert rec["support_margin_m"] > 0.0 and rec["tipping_angle_deg"] == pytest.approx(2.5, abs=0.1)
    assert not rec["stands"]


@pytest.mark.slow
def test_the_rejected_draw_falls_by_itself_and_the_least_stable_committed_drill_stands(tmp_path):
    """Left alone on the table (the robot at home, nothing touching it): the 2.5 deg draw is over within 1.5 s, the
    4.05 deg one (session 46) within 2 s; committed drill_11 (4.55 deg, the least stable instance the models were
    trained on) leans < 2 deg. The threshold (4.5 deg) lies between the last two."""
    seed = instance_seed("drill", 9, VAL_SEED)
    write_instance(_first_draw_of_val_drill_09(), "drill_09", tmp_path / "drill_09", seed)
    assert tilt_after("drill", "drill_09", tmp_path / "drill_09", 1.5) > 45.0
    write_instance(_first_draw_of_fourth_seed_drill_00(), "drill_00", tmp_path / "drill_00",
                   instance_seed("drill", 0, FOURTH_FRESH_SEED))
    assert tilt_after("drill", "drill_00", tmp_path / "drill_00", 2.0) > 45.0
    assert tilt_after("drill", "drill_11", None, 1.5) < 2.0


@pytest.mark.slow
def test_a_trial_on_the_rejected_draw_is_judged_fell_by_itself(tmp_path):
    """The drill grasp on the 2.5 deg draw: the drill tips over before the hand arrives, and the judge says so
    (``fell_by_itself``: no robot body touched it when it began to move), not ``collision_before_closing``.
    (A robot that knocks an object over stays ``collision_before_closing``: tests/station/test_judge.py.)"""
    from catgrasp_drake.station.handwritten import load_handwritten_motion
    from catgrasp_drake.station.scenario import load_scenario, with_instance
    from catgrasp_drake.trial import run_grasp_trial

    seed = instance_seed("drill", 9, VAL_SEED)
    write_instance(_first_draw_of_val_drill_09(), "drill_09", tmp_path / "drill_09", seed)
    scenario = with_instance(load_scenario("drill_default"), "drill_09", category="drill",
                             model_dir=str(tmp_path / "drill_09"))
    r = run_grasp_trial(scenario, load_handwritten_motion("drill", "drill_09", annotations_dir=tmp_path / "drill_09"))
    assert r.failure_reason == "fell_by_itself" and "no robot body touching it" in r.detail
