"""Station build time and grasp-trial real-time rate at several time steps, with the outcome at each.

    python benchmarks/bench_station.py [--repeats 2] [--time-steps 0.005 0.01 0.02 0.001]

A trial is each category's hand-written grasp (drill, spray bottle, mug,
about 8.5 s simulated) on its ``<category>_default`` scenario, without
Meshcat. "build" is ``make_station`` (plant, robot + object parsing,
cameras); "trial" is ``run_grasp_trial`` on a warm (cached) trial diagram:
IK planning + simulation + judging, on one core. The rate is simulated
seconds per wall second of the whole trial (best of ``--repeats``).
"outcome" is (grasped, functional); "same" compares it with the first time
step given (5 ms: the physics the station was tuned with). The larger
agreement check (>= 60 trials) is ``benchmarks/bench_fidelity.py``.
"""

from __future__ import annotations

import argparse
import logging
import os
import platform
import time
from dataclasses import replace

from catgrasp_drake.station.builder import make_station
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.station.scenario import load_scenario
from catgrasp_drake.trial import run_grasp_trial, trial_diagram

log = logging.getLogger("bench_station")

CATEGORIES = ("drill", "spray_bottle", "mug")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--time-steps", type=float, nargs="+", default=[5e-3, 1e-2, 2e-2, 1e-3])
    parser.add_argument("--categories", nargs="+", default=list(CATEGORIES))
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")

    base = load_scenario(f"{args.categories[0]}_default")
    builds = []
    for _ in range(args.repeats):
        t = time.perf_counter()
        make_station(base)
        builds.append(time.perf_counter() - t)
    rows = [("station build (make_station)", "", f"{min(builds):.3f} s", "", "", "")]
    for category in args.categories:
        scenario0 = load_scenario(f"{category}_default")
        motion = load_handwritten_motion(category, scenario0.object.instance)
        first = None
        for dt in args.time_steps:
            scenario = scenario0.replace(plant=replace(scenario0.plant, time_step=dt))
            trial_diagram(scenario)
            best = None
            for _ in range(args.repeats):
                r = run_grasp_trial(scenario, motion)
                if best is None or r.wall_time_s < best.wall_time_s:
                    best = r
            outcome = (best.grasp_success, best.functional_success)
            first = outcome if first is None else first
            rows.append((f"{category} trial", f"{dt * 1e3:g} ms",
                         f"{best.sim_time_s:.2f} s sim / {best.wall_time_s:.2f} s wall",
                         f"{best.realtime_rate:.2f}x (plan {best.plan_time_s * 1e3:.0f} ms)",
                         f"{outcome[0]}/{outcome[1]} ({best.failure_reason or 'ok'})",
                         "yes" if outcome == first else "NO"))
    log.info("machine: %s, %d CPUs, Python %s", platform.processor() or platform.machine(), os.cpu_count(),
             platform.python_version())
    log.info("| what | time step | time | real-time rate | grasped/functional | same as %g ms |",
             args.time_steps[0] * 1e3)
    log.info("|---|---:|---|---:|---|---|")
    for row in rows:
        log.info("| %s | %s | %s | %s | %s | %s |", *row)
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
