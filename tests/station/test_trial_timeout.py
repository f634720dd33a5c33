"""A simulated grasp that runs past its wall-clock limit ends as a failed trial, not a stalled run."""

from __future__ import annotations

import pytest

from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.station.scenario import load_scenario
from catgrasp_drake.trial import judge_spec, plan_for, simulate_and_judge, trial_diagram


def test_wall_clock_limit_gives_a_timeout_verdict():
    scenario = load_scenario("drill_default")
    td = trial_diagram(scenario)
    motion = load_handwritten_motion("drill", "drill_00")
    plan = plan_for(td, motion.in_world(scenario.X_WO()))
    context = td.diagram.CreateDefaultContext()
    td.generator.set_plan(td.generator.GetMyMutableContextFromRoot(context), plan)
    verdict, _, end, sim_time = simulate_and_judge(td.diagram, context, td.station, plan.timeline,
                                                   judge_spec(td.station, 0.12), max_wall_s=0.3)
    assert verdict.failure_reason == "simulation_timeout" and "wall-clock limit" in verdict.detail
    assert not verdict.grasp_success and end is None
    assert 0.0 < sim_time < plan.timeline.end


@pytest.mark.slow
def test_a_trial_stops_where_its_failure_is_decided_with_the_full_runs_verdict():
    """The spray bottle's hand-written grasp pulled 3 cm back closes in front of the bottle: not lifted. The
    default run stops at the end of the lift (the judge's verdict is decided there) with the same flags,
    reason and detail as the run simulated to its end, 3.6 s of simulation sooner; a film sees it all."""
    from catgrasp_drake.station.handwritten import shifted_motion
    from catgrasp_drake.trial import run_grasp_trial

    scenario = load_scenario("spray_bottle_default")
    instance = scenario.object.instance
    motion = shifted_motion(load_handwritten_motion("spray_bottle", instance), "spray_bottle", instance,
                            (0.0, -0.03, 0.0))
    stopped = run_grasp_trial(scenario, motion)
    full = run_grasp_trial(scenario, motion, stop_when_decided=False)
    verdict = ("grasp_success", "functional_success", "failure_reason", "detail")
    assert full.failure_reason == "not_lifted"
    assert [getattr(stopped, k) for k in verdict] == [getattr(full, k) for k in verdict]
    assert stopped.sim_time_s == pytest.approx(full.timeline["hold"], abs=0.01)  # the end of the lift
    assert full.sim_time_s == pytest.approx(full.timeline["end"], abs=0.01)
    seen = []
    filmed = run_grasp_trial(scenario, motion, on_phase=lambda label, _ctx: seen.append(label))
    assert filmed.sim_time_s == pytest.approx(full.sim_time_s) and seen[-1] == "end"
