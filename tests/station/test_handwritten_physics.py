"""PHYSICS: the hand-written grasps lift the default drill, spray bottle and mug and hold them 2 s.

Must-have figures of the station issue: functional success (index distal link
on the trigger) for drill_00 and spray_bottle_00, grasp success for mug_00.
The mug's functional criterion (tilt <= 15 deg) is not reached yet (the mug
turns ~20 deg in the handle grasp): marked xfail.
"""

from __future__ import annotations

import pytest

pytest.importorskip("pydrake")

from catgrasp_drake.station.handwritten import load_handwritten_motion  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario  # noqa: E402
from catgrasp_drake.station.trial import run_grasp_trial  # noqa: E402


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
    over backwards (tilt 65-90 deg, not lifted). The rolled palm, set further back, holds them."""
    from catgrasp_drake.station.scenario import with_instance

    scenario = with_instance(load_scenario(f"{category}_default"), instance)
    r = run_grasp_trial(scenario, load_handwritten_motion(category, instance))
    assert r.functional_success, f"{r.failure_reason}: {r.detail}"
    assert r.object_tilt_deg < 15.0


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
@pytest.mark.xfail(strict=False, reason="the mug turns ~20 deg in the handle grasp (limit 15 deg)")
def test_handwritten_mug_grasp_is_functional():
    r = _trial("mug_default")
    assert r.functional_success, f"{r.failure_reason}: {r.detail}"
