"""``planning.fit.hand_fit``: the preshaped hand against an object's mesh, with known answers from the planner."""

from __future__ import annotations

import json

import numpy as np
import pytest

from catgrasp_drake.data.stretch import STRESS_FAMILIES, stretch_instance
from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.planning.fit import hand_fit
from catgrasp_drake.station.handwritten import handwritten_trial, load_handwritten_motion
from catgrasp_drake.station.scenario import load_scenario, with_instance
from catgrasp_drake.trial import plan_for, trial_diagram
from tests.conftest import S17_SPRAY_GRASP


def _fit(category, name, directory=None, grasp_file=None):
    scenario, motion = handwritten_trial(category, name, object_dir=directory, grasp_file=grasp_file)
    return scenario, motion, hand_fit(scenario, motion)


@pytest.fixture(scope="module")
def deep_bottles(tmp_path_factory):
    """spray_bottle_00 and _02 stretched 1.3x along y (the stress split's deep family)."""
    root = tmp_path_factory.mktemp("deep")
    return {name: stretch_instance("spray_bottle", name, STRESS_FAMILIES["deep"], root / name, f"{name}_deep").directory
            for name in ("spray_bottle_00", "spray_bottle_02")}


def test_the_committed_drill_grasp_fits_its_drill_as_written():
    _, _, fit = _fit("drill", "drill_00")  # 13/13 committed drills lifted by it (docs/station.md)
    assert fit.plannable and not fit.shift_m.any()
    assert fit.depth_m < 0.0  # clear of the drill everywhere
    assert {"svh_thumb_middle_link", "svh_index_distal_link", "svh_base_link"} <= set(fit.link_depths_m)
    assert "executed as written" in fit.summary()


def test_a_deep_bottle_moves_the_grasp_as_the_planner_does(deep_bottles):
    scenario, motion, fit = _fit("spray_bottle", "spray_bottle_00_deep", deep_bottles["spray_bottle_00"])
    _, _, plain = _fit("spray_bottle", "spray_bottle_00")
    assert fit.depth_m > plain.depth_m + 0.005  # the deeper body meets the tucked thumb
    assert fit.deepest_links(1)[0][0].startswith(("svh_thumb", "svh_pinky"))
    assert fit.plannable and 0.004 < np.linalg.norm(fit.shift_m) < 0.020
    plan = plan_for(trial_diagram(scenario), motion.in_world(scenario.X_WO()))
    # the planner's own move of the grasp (world frame) has the same length
    assert np.linalg.norm(plan.object_shift) == pytest.approx(np.linalg.norm(fit.shift_m), abs=2e-4)


def test_a_hand_no_move_clears_is_refused_as_the_planner_refuses_it(deep_bottles):
    scenario, motion, fit = _fit("spray_bottle", "spray_bottle_02_deep", deep_bottles["spray_bottle_02"],
                                 S17_SPRAY_GRASP)
    assert not fit.plannable and fit.depth_m > 0.015
    assert "refuses the grasp" in fit.summary()
    plan = plan_for(trial_diagram(scenario), motion.in_world(scenario.X_WO()))
    assert not plan.ok and plan.status.startswith("collision: grasp")


def test_a_primitive_object_or_a_world_frame_motion_is_refused():
    scenario = load_scenario("cylinder_test")
    motion = load_handwritten_motion("drill", "drill_00")
    with pytest.raises(InputError, match="no object mesh"):
        hand_fit(scenario, motion)
    drill = with_instance(load_scenario("drill_default"), "drill_00")
    with pytest.raises(InputError, match="object frame"):
        hand_fit(drill, motion.in_world(drill.X_WO()))


def test_import_object_reports_the_fit_and_warns_when_the_grasp_cannot_fit(deep_bottles, tmp_path, capsys):
    from catgrasp_drake.cli import main

    directory = deep_bottles["spray_bottle_02"]  # in the canonical frame: the stated trigger is its annotated one
    trigger = json.loads((directory / "annotations.json").read_text())["regions"]["trigger"]["center"]
    argv = ["import-object", str(directory / "spray_bottle_02_deep.obj"), "--category", "spray_bottle",
            "--region", "trigger", *map(str, trigger), "--grasp", str(S17_SPRAY_GRASP), "--out", str(tmp_path / "obj")]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    line = next(ln for ln in out.splitlines() if ln.strip().startswith("hand fit"))
    assert "grasp spray_bottle_grasp_s17.yaml" in line
    assert "inside the object" in line and "refuses the grasp" in line
    assert "expect collision_before_closing" in err


# ----------------------------------------------------------------------------- closing_contacts
def test_closing_contacts_say_which_finger_arrives_first_and_whether_on_the_trigger():
    from catgrasp_drake.planning.fit import FINGER_LINKS, closing_contacts

    scenario, motion = handwritten_trial("spray_bottle", "spray_bottle_01")
    contacts = closing_contacts(scenario, motion, region=scenario.object.annotations()["regions"]["trigger"])
    assert sorted(c.finger for c in contacts) == sorted(FINGER_LINKS)
    touching = [c.fraction for c in contacts if c.fraction is not None]
    assert touching == sorted(touching) and all(0.0 <= f <= 1.0 for f in touching)
    index = next(c for c in contacts if c.finger == "index")
    # the spray grasp's index sweeps onto the trigger early in the closing (14/17 committed bottles pressed)
    assert index.in_region is True and index.fraction <= 0.2
    assert index.link.startswith("svh_index_") and "on the functional region" in index.summary()
    assert all(c.in_region is None for c in closing_contacts(scenario, motion))  # no region: not judged


def test_backing_the_hand_away_delays_every_first_contact():
    from catgrasp_drake.planning.fit import closing_contacts
    from catgrasp_drake.station.handwritten import moved_about

    scenario, motion = handwritten_trial("spray_bottle", "spray_bottle_01", grasp_file=S17_SPRAY_GRASP)
    palm_O = motion.pose("grasp")[:3, 1]  # H +y: the approach direction, into the object
    near = {c.finger: c.fraction for c in closing_contacts(scenario, motion)}
    far = {c.finger: c.fraction for c in closing_contacts(scenario, moved_about(motion, np.zeros(3), -0.03 * palm_O))}
    for finger, f in far.items():
        assert f is None or (near[finger] is not None and f >= near[finger]), finger
    assert far["palm"] is None and near["palm"] == 0.0  # the palm rests on the neck only when the hand is there


def test_closing_contacts_refuse_bad_input():
    from catgrasp_drake.planning.fit import closing_contacts

    scenario, motion = handwritten_trial("spray_bottle", "spray_bottle_01")
    with pytest.raises(InputError, match="steps"):
        closing_contacts(scenario, motion, steps=0)
    with pytest.raises(InputError, match="region"):
        closing_contacts(scenario, motion, region={"center": [0, 0]})
    with pytest.raises(InputError, match="no object mesh"):
        closing_contacts(load_scenario("cylinder_test"), motion)


def test_the_hand_fit_script_checks_a_given_grasp_file_in_place_of_the_categorys(deep_bottles, tmp_path, capsys):
    import importlib.util

    from tests.conftest import REPO

    spec = importlib.util.spec_from_file_location("hand_fit_script", REPO / "diagrams" / "hand_fit.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    directory = deep_bottles["spray_bottle_02"]
    rows = {}
    for label, extra in (("committed", []), ("s17", ["--grasp", str(S17_SPRAY_GRASP)])):
        out = tmp_path / f"{label}.json"
        assert script.main(["--objects", str(directory), "--json", str(out), *extra]) == 0
        rows[label] = json.loads(out.read_text())[0]
    _, _, s17 = _fit("spray_bottle", "spray_bottle_02_deep", directory, S17_SPRAY_GRASP)
    _, _, committed = _fit("spray_bottle", "spray_bottle_02_deep", directory)
    # each row is the fit of its own grasp: the session-17 grasp is refused on this bottle (test above)
    assert rows["s17"]["plannable"] is False and rows["s17"]["depth_mm"] == pytest.approx(1000 * s17.depth_m, abs=0.01)
    assert rows["committed"]["depth_mm"] == pytest.approx(1000 * committed.depth_m, abs=0.01)
    assert rows["committed"]["depth_mm"] != rows["s17"]["depth_mm"]
    with pytest.raises(ModelFileError, match="cannot read hand-written grasp"):
        script.main(["--objects", str(directory), "--grasp", str(tmp_path / "missing.yaml")])
