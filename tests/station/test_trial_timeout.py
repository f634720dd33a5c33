"""A simulated grasp that runs past its wall-clock limit ends as a failed trial, not a stalled run."""

from __future__ import annotations

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
