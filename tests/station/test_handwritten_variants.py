"""``diagrams/handwritten_sweep.py --shift/--rotate`` (``station.handwritten.shifted_motion``): a variant of a
hand-written grasp is a rigid motion of the whole grasp about the anchor region's centre (known answers, no
simulation); ``--mass-scale`` makes the simulated object heavier (two trials)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from catgrasp_drake.data.dataset import load_annotations
from catgrasp_drake.station.handwritten import load_handwritten_motion, shifted_motion


def test_no_variant_is_the_identity():
    motion = load_handwritten_motion("spray_bottle", "spray_bottle_04")
    same = shifted_motion(motion, "spray_bottle", "spray_bottle_04", (0, 0, 0), (0, 0, 0))
    np.testing.assert_allclose(same.poses, motion.poses, atol=1e-15)


def test_a_variant_turns_the_grasp_about_the_trigger_then_shifts_it():
    motion = load_handwritten_motion("drill", "drill_05")
    centre = np.asarray(load_annotations("drill", "drill_05")["regions"]["trigger"]["center"])
    shift, angles = np.array([0.01, -0.02, 0.005]), (5.0, -25.0, 10.0)
    v = shifted_motion(motion, "drill", "drill_05", shift, angles)
    R = Rotation.from_euler("xyz", angles, degrees=True).as_matrix()
    for X, Y in zip(motion.poses, v.poses):
        np.testing.assert_allclose(Y[:3, :3], R @ X[:3, :3], atol=1e-12)
        # the trigger centre, seen from the hand, has moved by the shift only
        np.testing.assert_allclose(Y[:3, 3] - (R @ (X[:3, 3] - centre) + centre), shift, atol=1e-12)
    assert v.pose_names == motion.pose_names and v.frame == "object"


def test_a_posture_override_sets_one_joint_of_one_posture():
    from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS
    from catgrasp_drake.station.handwritten import with_postures

    motion = load_handwritten_motion("mug", "mug_03")
    v = with_postures(motion, {"closed": {"svh_pinky": 0.856}})
    k = HAND_ACTUATED_JOINTS.index("svh_pinky")
    assert v.posture("closed")[k] == 0.856 and motion.posture("closed")[k] == 0.65  # the original is untouched
    others = [i for i in range(len(HAND_ACTUATED_JOINTS)) if i != k]
    np.testing.assert_array_equal(v.posture("closed")[others], motion.posture("closed")[others])
    for name in ("open", "preshape"):
        np.testing.assert_array_equal(v.posture(name), motion.posture(name))
    np.testing.assert_array_equal(v.poses, motion.poses)


def test_a_bad_posture_override_names_the_problem():
    import pytest

    from catgrasp_drake.errors import InputError
    from catgrasp_drake.station.handwritten import with_postures

    motion = load_handwritten_motion("mug", "mug_03")
    for overrides, message in (({"clenched": {"svh_pinky": 0.5}}, "unknown posture 'clenched'"),
                               ({"closed": {"svh_toe": 0.5}}, "unknown joint 'svh_toe'"),
                               ({"closed": {"svh_pinky": "lots"}}, "expected an angle in radians"),
                               ({"closed": {"svh_pinky": 3.0}}, "outside the joint limits")):
        with pytest.raises(InputError, match=message):
            with_postures(motion, overrides)


def test_the_sweep_reads_posture_overrides_from_the_command_line():
    import importlib.util

    import pytest

    from tests.conftest import REPO

    spec = importlib.util.spec_from_file_location("handwritten_sweep", REPO / "diagrams" / "handwritten_sweep.py")
    sweep = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(sweep)

    def error(message):
        raise ValueError(message)

    assert sweep.posture_overrides(["closed.svh_pinky=0.856", "closed.svh_thumb_flexion=0.674",
                                    "preshape.svh_ring=0.1"], error) == {
        "closed": {"svh_pinky": 0.856, "svh_thumb_flexion": 0.674}, "preshape": {"svh_ring": 0.1}}
    for bad in ("closed.svh_pinky", "svh_pinky=0.8", "closed.svh_pinky=much"):
        with pytest.raises(ValueError, match="NAME.JOINT=RAD"):
            sweep.posture_overrides([bad], error)
    # --plan FIELD=VALUE: PlanParams fields, integers kept integers
    assert sweep.plan_overrides(["close_time=1.6", "reach_knots=7"], error) == {"close_time": 1.6, "reach_knots": 7}
    with pytest.raises(ValueError, match="unknown PlanParams field 'closing_time'"):
        sweep.plan_overrides(["closing_time=1.6"], error)
    with pytest.raises(ValueError, match="FIELD=NUMBER"):
        sweep.plan_overrides(["close_time=slow"], error)


@pytest.mark.slow
def test_the_sweeps_mass_scale_makes_the_object_heavier_in_the_simulation():
    """``--mass-scale``: spray_bottle_00 (0.69 kg) is held by its hand-written grasp; 30 times heavier (21 kg, past
    what the hand's effort-limited fingers can hold) it is not held: not lifted, or (the session-16 grasp, whose
    fingers close under the head) lifted on the fingers and then shaken loose."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "diagrams"))
    from handwritten_sweep import sweep_task

    spec = {"category": "spray_bottle", "instance": "spray_bottle_00"}
    assert sweep_task(spec)["grasp"]
    heavy = sweep_task(spec | {"mass_scale": 30.0})
    assert not heavy["grasp"] and heavy["reason"] in ("not_lifted", "lifted_short", "slipped", "shaken_loose"), heavy


def test_the_sweep_runs_a_grasp_file_in_place_of_the_hand_written_one(tmp_path, monkeypatch, capsys):
    """``--grasp FILE``: every trial of the file's category runs the file's grasp (and the file's hash keys the
    cache); a file of another category than --objects, or with --model, is refused in one line."""
    import sys
    from pathlib import Path

    import yaml

    import catgrasp_drake.runner
    import catgrasp_drake.trial
    from catgrasp_drake.station.handwritten import GRASPS_DIR, load_handwritten_motion

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "diagrams"))
    import handwritten_sweep

    spec = yaml.safe_load((GRASPS_DIR / "drill_handwritten.yaml").read_text())
    spec["grasp"]["position"][2] += 0.004
    grasp = tmp_path / "drill_up.yaml"
    grasp.write_text(yaml.safe_dump(spec))
    seen = []
    monkeypatch.setattr(catgrasp_drake.runner, "run_tasks", lambda task, specs, **kw: seen.extend(specs) or [])
    assert handwritten_sweep.main(["--grasp", str(grasp), "--instances", "drill_00", "drill_03",
                                   "--json", str(tmp_path / "rows.json")]) == 0
    assert [(s["category"], s["instance"]) for s in seen] == [("drill", "drill_00"), ("drill", "drill_03")]
    assert seen[0]["grasp_file"] == str(grasp.resolve()) and len(seen[0]["grasp_sha256"]) == 64

    ran = []

    def record_and_stop(scenario, motion, params):  # the motion the trial would run; no simulation
        ran.append(motion)
        raise RuntimeError("stop")

    monkeypatch.setattr(catgrasp_drake.trial, "run_grasp_trial", record_and_stop)
    with pytest.raises(RuntimeError, match="stop"):
        handwritten_sweep.sweep_task(seen[0])
    as_written = load_handwritten_motion("drill", "drill_00").pose("grasp")
    assert np.allclose(ran[0].pose("grasp")[:3, 3] - as_written[:3, 3], [0, 0, 0.004], atol=1e-9)

    from catgrasp_drake.benchmark.runner import stretched_objects

    not_yaml = tmp_path / "broken.yaml"
    not_yaml.write_text("grasp: [0.1, 0.2\n")
    [(_, mug)] = stretched_objects(tmp_path / "stretched", "mug", ["mug_00"], ["deep"])
    for argv, message in [(["--grasp", str(tmp_path / "none.yaml")], "--grasp: no such grasp file"),
                          (["--grasp", str(grasp), "--model", "models/trained/drill.npz", "--categories", "drill"],
                           "--grasp and --model"),
                          (["--grasp", str(grasp), "--objects", str(mug)], "a drill grasp, but --objects holds mug"),
                          (["--grasp", str(not_yaml)], "not valid YAML")]:
        with pytest.raises(SystemExit):
            handwritten_sweep.main(argv)
        assert message in capsys.readouterr().err
