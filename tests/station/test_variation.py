"""Grasp variations: applied to a motion, written back into a grasp file, and the robustness score."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from catgrasp_drake.data.dataset import load_annotations
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasp_search import apply_variation_to_spec
from catgrasp_drake.grasping.robustness import Robustness, perturbation, trial_score
from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS, hand_joint_limits, load_hand_postures
from catgrasp_drake.station.handwritten import GRASPS_DIR, load_handwritten_motion, motion_from_spec
from catgrasp_drake.station.variation import VARIATION_NAMES, variation_vector, vary_motion


@pytest.mark.parametrize("category,instance", [("drill", "drill_04"), ("mug", "mug_02"),
                                               ("spray_bottle", "spray_bottle_07")])
def test_a_variation_written_into_the_grasp_file_gives_the_varied_motion(category, instance):
    v = variation_vector({"dx": 0.004, "dy": -0.007, "dz": 0.002, "roll": 3.0, "pitch": -5.0, "yaw": 7.0,
                          "index_distal": 0.3, "middle": -0.2, "spread": 0.1, "thumb_opposition": 0.4})
    motion = load_handwritten_motion(category, instance)
    varied = vary_motion(motion, category, instance, v)
    spec = yaml.safe_load((GRASPS_DIR / f"{category}_handwritten.yaml").read_text())
    written = apply_variation_to_spec(spec, dict(zip(VARIATION_NAMES, v)), category,
                                      load_hand_postures(spec["postures"]))
    again = motion_from_spec(written, load_annotations(category, instance))
    np.testing.assert_allclose(again.poses, varied.poses, atol=2e-5)  # the file rounds to 10 um
    for name in ("open", "preshape", "closed"):
        np.testing.assert_allclose(again.posture(name), varied.posture(name), atol=1e-4)
    # and the variation did something: the hand moved by about |d| and the index distal flexed
    shift = np.linalg.norm(varied.poses[1][:3, 3] - motion.poses[1][:3, 3])
    assert 0.003 < shift < 0.05
    i = HAND_ACTUATED_JOINTS.index("svh_index_distal")
    lo, hi = hand_joint_limits()["svh_index_distal"]
    assert varied.posture("closed")[i] == pytest.approx(min(hi, motion.posture("closed")[i] + 0.3))
    np.testing.assert_array_equal(varied.posture("preshape"), motion.posture("preshape"))


def test_the_zero_variation_is_the_grasp_itself_and_postures_stay_in_their_limits():
    motion = load_handwritten_motion("drill", "drill_00")
    same = vary_motion(motion, "drill", "drill_00", np.zeros(len(VARIATION_NAMES)))
    np.testing.assert_allclose(same.poses, motion.poses, atol=1e-12)
    big = vary_motion(motion, "drill", "drill_00", variation_vector({n: 5.0 for n in VARIATION_NAMES[6:]}))
    limits = hand_joint_limits()
    assert all(big.posture("closed")[k] == limits[j][1] for k, j in enumerate(HAND_ACTUATED_JOINTS))
    with pytest.raises(InputError, match="unknown parameters"):
        variation_vector({"twist": 1.0})


def test_perturbations_are_seeded_within_their_ranges_and_the_first_is_nominal():
    r = Robustness(perturbations=20, seed=3)
    assert perturbation(r, "mug_00", 0) == {"dx": 0.0, "dy": 0.0, "dyaw_deg": 0.0, "friction": None,
                                            "mass_scale": 1.0}
    ps = [perturbation(r, "mug_00", k) for k in range(1, 20)]
    assert ps == [perturbation(r, "mug_00", k) for k in range(1, 20)]
    assert ps != [perturbation(r, "mug_01", k) for k in range(1, 20)]
    assert all(np.hypot(p["dx"], p["dy"]) <= 0.01 and abs(p["dyaw_deg"]) <= 5 for p in ps)
    assert all(0.5 <= p["friction"] <= 1.0 and 0.7 <= p["mass_scale"] <= 1.3 for p in ps)
    assert trial_score({"grasp": True, "functional": True}, 0.2) == 1.0
    assert trial_score({"grasp": True, "functional": False}, 0.2) == 0.2
    assert trial_score({"grasp": False, "functional": False}, 0.2) == 0.0


def test_a_height_error_is_drawn_after_the_other_perturbations_and_moves_the_grasp_vertically():
    from dataclasses import replace

    from catgrasp_drake.grasping.robustness import object_offset

    flat = Robustness(perturbations=20, seed=3)
    tall = replace(flat, height_m=0.004)
    assert perturbation(tall, "drill_00", 0) == perturbation(flat, "drill_00", 0) | {"dz": 0.0}
    for k in range(1, 20):
        p, q = perturbation(tall, "drill_00", k), perturbation(flat, "drill_00", k)
        assert {n: v for n, v in p.items() if n != "dz"} == q  # the other draws keep their values
        assert abs(p["dz"]) <= 0.004 and object_offset(p)[2, 3] == p["dz"]
        np.testing.assert_array_equal(object_offset(p)[:2], object_offset(q)[:2])
    assert len({perturbation(tall, "drill_00", k)["dz"] for k in range(1, 20)}) == 19
    assert "dz" not in perturbation(flat, "drill_00", 1) and object_offset(perturbation(flat, "drill_00", 1))[2, 3] == 0
    with pytest.raises(InputError, match="height_m"):
        Robustness(height_m=0.2)


def test_a_height_error_of_15_mm_moves_the_drill_grasp_off_what_holds():
    """Physics: drill_00's hand-written grasp is functional as planned (diagrams/handwritten_sweep.py); with the
    object 15 mm lower than planned the hand lands 15 mm high on the handle and does not lift the drill.
    (Session 28's grasp, searched for height errors, is still functional 15 and 20 mm low: the other side.)"""
    from catgrasp_drake.station.handwritten import handwritten_trial
    from catgrasp_drake.trial import run_perturbed_trial

    scenario, motion = handwritten_trial("drill", "drill_00")
    p = perturbation(Robustness(height_m=0.02), "drill_00", 0) | {"dz": -0.015}
    r = run_perturbed_trial(scenario, motion, p)
    assert not r["grasp"] and r["reason"] == "not_lifted", r


def test_the_search_scores_candidates_by_their_trials_and_keys_a_given_grasp_file_by_its_content(tmp_path,
                                                                                                 monkeypatch):
    import hashlib
    import shutil
    from types import SimpleNamespace

    import catgrasp_drake.runner as runner
    from catgrasp_drake.grasp_search import search_grasp
    from catgrasp_drake.grasping.search import CemParams

    seen = []

    def fake_run_tasks(fn, specs, **kw):  # functional exactly when the hand is moved up (dz > 0)
        seen.extend(specs)
        return [SimpleNamespace(result={"grasp": True, "functional": s["variation"][2] > 0}) for s in specs]

    monkeypatch.setattr(runner, "run_tasks", fake_run_tasks)
    grasp = tmp_path / "mine.yaml"
    shutil.copy(GRASPS_DIR / "mug_handwritten.yaml", grasp)
    result = search_grasp("mug", ["mug_00", "mug_02"], cem=CemParams(rounds=2, population=6, elite=2, seed=1),
                          robustness=Robustness(perturbations=2), grasp_file=str(grasp), cache_dir=None)
    assert result.start_score == pytest.approx(0.2)  # the grasp as written: held, not functional, 4 of 4 trials
    assert result.best["dz"] > 0 and result.best_score == pytest.approx(1.0)
    assert result.trials == 2 * 6 * 4 == len(seen)
    assert {s["grasp_sha256"] for s in seen} == {hashlib.sha256(grasp.read_bytes()).hexdigest()}
    for entry in result.rounds[0]:  # every candidate's score is the mean of its own trials
        assert entry["score"] == pytest.approx(1.0 if entry["variation"]["dz"] > 0 else 0.2)
    seen.clear()
    search_grasp("mug", ["mug_00"], cem=CemParams(rounds=1, population=2, elite=1), cache_dir=None)
    assert all("grasp_sha256" not in s and "grasp_file" not in s for s in seen)  # the default: in the fingerprint


def test_candidates_the_planner_refuses_on_a_screen_object_are_drawn_again_and_never_simulated(monkeypatch,
                                                                                               capsys):
    from types import SimpleNamespace

    import catgrasp_drake.runner as runner
    from catgrasp_drake.grasp_search import SCREEN_TASK, search_grasp
    from catgrasp_drake.grasping.search import CemParams

    trials, screened = [], []
    refuse_all = [False]

    def fake_run_tasks(fn, specs, **kw):  # the planner refuses a hand moved up > 5 mm on mug_05 only
        if specs and specs[0]["task"] == SCREEN_TASK:
            screened.extend((s["instance"], tuple(v)) for s in specs for v in s["variations"])
            return [SimpleNamespace(result={"status": "ok", "plannable": [
                not (s["instance"] == "mug_05" and (v[2] > 0.005 or refuse_all[0])) for v in s["variations"]]})
                for s in specs]
        trials.extend(specs)
        return [SimpleNamespace(result={"grasp": True, "functional": s["variation"][2] > 0}) for s in specs]

    monkeypatch.setattr(runner, "run_tasks", fake_run_tasks)
    result = search_grasp("mug", ["mug_00"], cem=CemParams(rounds=2, population=8, elite=2, seed=3),
                          robustness=Robustness(perturbations=1), cache_dir=None,
                          screen={"mug_05": None, "mug_07": None})
    assert {i for i, _ in screened} == {"mug_05", "mug_07"}
    assert len(screened) == len(set(screened))  # each candidate is screened once on each object
    entries = [e for r in result.rounds for e in r]
    assert len(entries) == 2 * 8 and all(e["screen_refused"] == [] for e in entries)  # full, accepted rounds
    assert all(v["variation"][2] <= 0.005 for v in trials) and result.trials == len(trials) == 16
    refused_draws = {v for i, v in screened if i == "mug_05" and v[2] > 0.005}
    assert [d["infeasible"] for d in result.screened] and sum(d["infeasible"] for d in result.screened) == len(
        refused_draws) > 0  # the refused draws were drawn again
    assert 0 < result.best["dz"] <= 0.005 and result.best_score == pytest.approx(1.0)
    # a screen that refuses every draw: after the round's draws (40 x population) the refused candidates are
    # kept (the start among them), score 0 and are not simulated
    trials.clear()
    refuse_all[0] = True
    result = search_grasp("mug", ["mug_00"], cem=CemParams(rounds=1, population=3, elite=1, seed=4),
                          robustness=Robustness(perturbations=1), cache_dir=None, screen={"mug_05": None},
                          screen_max_refused=0)
    assert result.screened == [{"drawn": 120, "infeasible": 120}]
    assert [e["screen_refused"] for e in result.rounds[0]] == [["mug_05"]] * 3
    assert all(e["score"] == 0.0 and e["trials"] == [] for e in result.rounds[0]) and trials == []
    from catgrasp_drake.cli import main

    assert main(["search-grasp", "--category", "mug", "--screen", "drill_00"]) == 2
    assert "--screen: unknown mug instance(s) ['drill_00']" in capsys.readouterr().err


def test_the_screen_refuses_the_s42_searched_spray_grasp_on_bottle_05_and_accepts_the_landed_one():
    """Known answer (kinematic, session 42): the grasp searched with shrouded bottles, 5 mm lower, is refused by the
    planner on spray_bottle_05, where it collided before closing in both check trials; the landed grasp is not."""
    from catgrasp_drake.grasp_search import screen_task

    searched = variation_vector({"dx": -0.003, "dy": 0.0057, "dz": -0.0051, "roll": 1.7457, "pitch": -1.4835,
                                 "yaw": 0.6598, "thumb_flexion": -0.2746, "thumb_opposition": 0.1356,
                                 "index_proximal": 0.1853, "index_distal": 0.0412, "middle": 0.1169,
                                 "ring_pinky": 0.2036, "spread": 0.0025})
    landed = Path(__file__).resolve().parents[1] / "fixtures" / "spray_bottle_grasp_s39.yaml"
    out = screen_task({"category": "spray_bottle", "instance": "spray_bottle_05", "grasp_file": str(landed),
                       "variations": [[0.0] * len(searched), list(searched)]})
    assert out == {"status": "ok", "plannable": [True, False]}


def test_a_variation_about_the_annotated_centre_is_the_variation_of_the_grasp_file():
    from catgrasp_drake.grasping.constraints import load_constraint
    from catgrasp_drake.station.variation import vary_motion_about

    v = variation_vector({"dx": 0.003, "roll": 4.0, "yaw": -6.0, "thumb_flexion": 0.2})
    motion = load_handwritten_motion("drill", "drill_03")
    centre = load_annotations("drill", "drill_03")["regions"][load_constraint("drill").region]["center"]
    a, b = vary_motion(motion, "drill", "drill_03", v), vary_motion_about(motion, centre, v)
    np.testing.assert_array_equal(a.poses, b.poses)
    np.testing.assert_array_equal(a.posture("closed"), b.posture("closed"))


def test_the_search_runs_on_imported_objects_keyed_by_their_files(tmp_path, monkeypatch, capsys):
    """``search_grasp(object_dirs=...)``: an imported object's trials carry its directory and a hash of its
    files (a re-import changes the key), and ``catgrasp search-grasp --objects`` refuses another category's."""
    from types import SimpleNamespace

    import catgrasp_drake.runner as runner
    from catgrasp_drake.cli import main
    from catgrasp_drake.data.stretch import STRESS_FAMILIES, stretch_instance
    from catgrasp_drake.grasp_search import search_grasp
    from catgrasp_drake.grasping.search import CemParams

    seen = []
    monkeypatch.setattr(runner, "run_tasks", lambda fn, specs, **kw: seen.extend(specs) or [
        SimpleNamespace(result={"grasp": True, "functional": True}) for _ in specs])
    big = stretch_instance("mug", "mug_03", STRESS_FAMILIES["large"], tmp_path / "big", "mug_03_large").directory
    cem = CemParams(rounds=1, population=2, elite=1)
    search_grasp("mug", ["mug_00", "mug_03_large"], cem=cem, object_dirs={"mug_03_large": big}, cache_dir=None)
    mine = [s for s in seen if s["instance"] == "mug_03_large"]
    assert mine and 2 * len(mine) == len(seen) and all(s["model_dir"] == str(big) for s in mine)
    assert all("model_dir" not in s and "object_sha256" not in s for s in seen if s["instance"] == "mug_00")
    key = mine[0]["object_sha256"]
    ann = big / "annotations.json"
    ann.write_text(ann.read_text().replace('"mass_kg"', '"mass_kg" ', 1))  # the same object, re-imported
    seen.clear()
    search_grasp("mug", ["mug_03_large"], cem=cem, object_dirs={"mug_03_large": big}, cache_dir=None)
    assert {s["object_sha256"] for s in seen} != {key}
    assert main(["search-grasp", "--category", "spray_bottle", "--objects", str(big)]) == 2
    assert f"--objects: {big} is a mug, not a spray_bottle" in capsys.readouterr().err


@pytest.mark.slow
def test_a_search_trial_on_a_stretched_bottle_is_the_hand_written_grasp_on_that_bottle(tmp_path):
    """The task the search runs, on an imported object: the committed bottle 03 at 1.2x has a trigger gap
    (18.8 mm) wider than the index finger's distal phalanx (17.2 mm), and the session-17 spray grasp's index
    ends in it, on the neck (benchmarks/results/experiments/s26_trigger_gap; the grasp pinned as a fixture)."""
    from catgrasp_drake.data.stretch import STRESS_FAMILIES, stretch_instance
    from catgrasp_drake.grasp_search import search_trial_task
    from tests.conftest import S17_SPRAY_GRASP

    big = stretch_instance("spray_bottle", "spray_bottle_03", STRESS_FAMILIES["large"], tmp_path / "b",
                           "spray_bottle_03_large").directory
    nominal = perturbation(Robustness(), "spray_bottle_03_large", 0)
    r = search_trial_task({"category": "spray_bottle", "instance": "spray_bottle_03_large", "model_dir": str(big),
                           "perturbation": nominal, "variation": [0.0] * len(VARIATION_NAMES),
                           "grasp_file": str(S17_SPRAY_GRASP)})
    assert r["grasp"] and not r["functional"] and r["reason"] == "trigger_missed"
