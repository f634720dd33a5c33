"""PHYSICS: the hand-written grasps lift the default drill, spray bottle and mug, hold them 2 s, survive
the shake (1 s, 2 m/s^2 at 2 Hz) and the index finger's press (DESIGN.md section 6, the stricter judge).

Must-have figures of the station issue: functional success (index distal link
on the trigger's own surface pressing it with >= 5 N along its travel) for
drill_00 and spray_bottle_00, grasp success for mug_00, and (since the mug's
grasp was searched, session 6) functional success for mug_00 too: it stays
within 15 deg (10 deg measured).
"""

from __future__ import annotations

import pytest

pytest.importorskip("pydrake")

from catgrasp_drake.station.handwritten import load_handwritten_motion  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario  # noqa: E402
from catgrasp_drake.trial import run_grasp_trial  # noqa: E402


def _trial(name):
    scenario = load_scenario(name)
    motion = load_handwritten_motion(scenario.object.category, scenario.object.instance)
    return run_grasp_trial(scenario, motion)


def test_handwritten_motion_loads_for_every_instance():
    from catgrasp_drake.data.dataset import list_instances

    for category in ("drill", "spray_bottle", "mug"):
        for instance in list_instances(category):
            m = load_handwritten_motion(category, instance)
            assert m.frame == "object" and m.lift_height >= 0.10 and m.hold_time >= 2.0


@pytest.mark.slow
def test_handwritten_drill_grasp_is_functional():
    r = _trial("drill_default")
    assert r.plan_status == "ok"
    assert r.grasp_success, f"{r.failure_reason}: {r.detail}"
    assert r.functional_success, f"{r.failure_reason}: {r.detail}"
    assert r.object_rise_m >= 0.08


@pytest.mark.slow
def test_handwritten_spray_bottle_grasp_is_functional():
    r = _trial("spray_bottle_default")
    assert r.plan_status == "ok"
    assert r.grasp_success, f"{r.failure_reason}: {r.detail}"
    assert r.functional_success, f"{r.failure_reason}: {r.detail}"
    assert r.object_rise_m >= 0.08


@pytest.mark.slow
@pytest.mark.parametrize("category, instance", [("spray_bottle", "spray_bottle_03"), ("drill", "drill_02")])
def test_handwritten_grasp_holds_instances_the_upright_palm_knocked_over(category, instance):
    """Before session 4 the palm stood upright beside the handle/neck: closing fingers pushed these two
    over backwards (tilt 65-90 deg, not lifted). The rolled palm, set further back, holds them.

    (Under the old judge both were also functional; with the trigger's own surface required,
    spray_bottle_03's index finger ends a few mm beside its trigger: ``trigger_missed``. Since session 15
    spray_bottle_03 is one of the deep-bodied, thin-necked bottles, which the grasp moved 15 mm toward the
    neck holds: grasped, trigger missed, tilt 11 deg. Since session 16 its neck is long and capped and its
    head Windex-like, and the grasp, moved 6 mm forward, 8 mm up and 4 mm in, is functional on it: tilt 6 deg.
    Session 17: its shoulder slightly domed (2.1 cm) and the index squeezing, functional, tilt 2.7 deg.)"""
    from catgrasp_drake.station.scenario import with_instance

    scenario = with_instance(load_scenario(f"{category}_default"), instance)
    r = run_grasp_trial(scenario, load_handwritten_motion(category, instance))
    assert r.grasp_success, f"{r.failure_reason}: {r.detail}"
    assert r.object_tilt_deg < 15.0


@pytest.mark.slow
def test_handwritten_drill_grasp_on_drill_02_survives_the_shake_and_presses_the_trigger():
    """The stricter judge on drill_02: lifted >= 10 cm, held 2 s, shaken, pressed; still in the hand
    within 2 cm / 10 deg. Measured (session of the stricter judge): functional, 45.9 N along the trigger's
    travel at the end of the press, 1.8 mm / 1.3 deg in-hand motion. The hand's contact forces on the
    object at the end balance its weight (the sign convention of ``ContactRecord.force_on_a_W``)."""
    import numpy as np

    from catgrasp_drake.station.scenario import with_instance
    from catgrasp_drake.trial import judge_spec, plan_for, simulate_and_judge, trial_diagram

    scenario = with_instance(load_scenario("drill_default"), "drill_02")
    motion = load_handwritten_motion("drill", "drill_02")
    td = trial_diagram(scenario)
    plan = plan_for(td, motion.in_world(scenario.X_WO()))
    assert plan.ok, plan.status
    assert plan.timeline.press - plan.timeline.shake == pytest.approx(1.0)
    context = td.diagram.CreateDefaultContext()
    td.generator.set_plan(td.generator.GetMyMutableContextFromRoot(context), plan)
    spec = judge_spec(td.station, motion.lift_height)
    verdict, _, end, sim_time = simulate_and_judge(td.diagram, context, td.station, plan.timeline, spec)
    assert sim_time == pytest.approx(plan.timeline.end)
    assert verdict.grasp_success, f"{verdict.failure_reason}: {verdict.detail}"
    assert verdict.object_rise_m >= 0.10
    assert verdict.in_hand_shift_m < 0.02 and verdict.in_hand_turn_deg < 10.0
    assert verdict.functional_success, f"{verdict.failure_reason}: {verdict.detail}"
    assert verdict.trigger_force_N >= 5.0
    # the hand holds the object still at the end: its contact forces on the object carry the weight
    plant = td.station.plant
    weight = plant.CalcTotalMass(plant.CreateDefaultContext(), [td.station.object_instance]) * 9.81
    hand_on_object = sum(c.force_on(spec.object_model) for c in end.contacts
                         if c.involves(spec.object_model) and c.involves(spec.hand_model))
    assert np.allclose(hand_on_object, [0.0, 0.0, weight], atol=0.05 * weight)


@pytest.mark.slow
def test_handwritten_spray_bottle_grasp_lifts_and_holds():
    r = _trial("spray_bottle_default")
    assert r.grasp_success, f"{r.failure_reason}: {r.detail}"
    assert r.object_rise_m >= 0.10
    assert r.timeline["end"] - r.timeline["hold"] >= 2.0


@pytest.mark.slow
def test_handwritten_mug_grasp_lifts_and_holds():
    r = _trial("mug_default")
    assert r.plan_status == "ok"
    assert r.grasp_success, f"{r.failure_reason}: {r.detail}"
    assert r.object_rise_m >= 0.10
    assert "svh_middle_distal_link" in r.hand_links_on_object


@pytest.mark.slow
def test_handwritten_mug_grasp_is_functional():
    r = _trial("mug_default")
    assert r.functional_success, f"{r.failure_reason}: {r.detail}"
