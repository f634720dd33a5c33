"""Station build time and grasp-trial real-time rate (time_step 5e-3 and 1e-3).

    python benchmarks/bench_station.py [--repeats 2]

Prints a table; a trial is the hand-written drill grasp (≈ 7 s simulated)
on ``drill_default`` without Meshcat. "build" is ``make_station`` (plant,
robot + object parsing, cameras); "trial" is ``run_grasp_trial`` on a warm
(cached) trial diagram: IK planning + simulation + judging.
"""

from __future__ import annotations

import argparse
import logging
import os
import platform
import time

from catgrasp_drake.station.builder import make_station
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.station.scenario import PlantSpec, load_scenario
from catgrasp_drake.trial import run_grasp_trial, trial_diagram

log = logging.getLogger("bench_station")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--scenario", default="drill_default")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    base = load_scenario(args.scenario)
    motion = load_handwritten_motion(base.object.category, base.object.instance)

    builds = []
    for _ in range(args.repeats):
        t = time.perf_counter()
        make_station(base)
        builds.append(time.perf_counter() - t)
    rows = [("station build (make_station)", f"{min(builds):.3f} s", "")]
    for dt in (5e-3, 1e-3):
        scenario = base.replace(plant=PlantSpec(time_step=dt))
        t = time.perf_counter()
        trial_diagram(scenario)
        rows.append((f"trial diagram build, dt={dt:g}", f"{time.perf_counter() - t:.3f} s", ""))
        best = None
        for _ in range(args.repeats):
            r = run_grasp_trial(scenario, motion)
            if best is None or r.wall_time_s < best.wall_time_s:
                best = r
        rows.append((f"grasp trial, dt={dt:g}",
                     f"{best.sim_time_s:.2f} s sim / {best.wall_time_s:.2f} s wall",
                     f"{best.realtime_rate:.2f}x real time (plan {best.plan_time_s * 1e3:.0f} ms)"))
    log.info("machine: %s, %d CPUs, Python %s", platform.processor() or platform.machine(), os.cpu_count(),
             platform.python_version())
    log.info("| %-32s | %-28s | %-36s |", "what", "time", "rate")
    log.info("|%s|%s|%s|", "-" * 34, "-" * 30, "-" * 38)
    for row in rows:
        log.info("| %-32s | %-28s | %-36s |", *row)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
