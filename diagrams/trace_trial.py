"""Trace one hand-written grasp trial: the object's tilt, rise and hand contacts every few hundredths of a second.

    python diagrams/trace_trial.py --category mug --instance mug_09 [--every 0.1] [--start reach] [--stop end]
    python diagrams/trace_trial.py --object out/ycb/spray_bottle/ycb_022 [--shift DX DY DZ] [--seed N] ...

Where ``catgrasp film`` shows a trial at its phases in pictures, this prints,
every ``--every`` seconds of simulated time from the start of the phase
``--start`` to the start of ``--stop``, the phase, the object's tilt (deg,
against its pose at the start), its rise (cm) and the hand links touching it
-- so one can read *when* a grasp goes wrong and which finger did it (e.g. a
mug that tilts while the fingers close, before anything is lifted). The
trial is the category's hand-written grasp on the instance (or on an imported
object, ``--object DIR``; moved by ``--shift``, placed by ``--seed`` as
``catgrasp film`` does) at the category's default scenario, true-object
planner, default physics, run by
``trial.run_grasp_trial`` (the same motion as an untraced trial's: the
plant's updates are periodic); its verdict ends the trace.
"""

from __future__ import annotations

import argparse

import numpy as np

from catgrasp_drake.station.handwritten import handwritten_trial
from catgrasp_drake.station.judge import tilt_deg
from catgrasp_drake.trial import plan_for, run_grasp_trial, station_snapshot, trial_diagram

PHASES = ("approach", "reach", "close", "lift", "hold", "shake", "press", "end")


def _short(link: str) -> str:
    return link.split("::")[-1].removeprefix("svh_").removesuffix("_link")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--category", choices=("drill", "spray_bottle", "mug"),
                        help="the hand-written grasp's category (or give --object)")
    parser.add_argument("--instance", help="embedded instance (default: the scenario's)")
    parser.add_argument("--object", metavar="DIR", help="an imported object's directory (catgrasp import-object)")
    parser.add_argument("--shift", type=float, nargs=3, metavar=("DX", "DY", "DZ"),
                        help="move the grasp by this much (m, object frame)")
    parser.add_argument("--seed", type=int, help="a seeded random placement (default: the scenario's pose)")
    parser.add_argument("--every", type=float, default=0.1, help="print interval (s of simulated time)")
    parser.add_argument("--start", default="reach", choices=PHASES)
    parser.add_argument("--stop", default="end", choices=PHASES)
    args = parser.parse_args(argv)
    if not args.every > 0:
        parser.error("--every: expected > 0")

    if args.category is None and args.object is None:
        parser.error("give --category (with --instance) or --object DIR")
    scenario, motion = handwritten_trial(args.category, args.instance, object_dir=args.object, seed=args.seed,
                                         shift_O=args.shift)
    instance = scenario.object.instance
    td = trial_diagram(scenario)  # cached: the trial below runs on this diagram
    plan = plan_for(td, motion.in_world(scenario.X_WO()))  # the trial's own plan, for its timeline
    if not plan.ok:
        print(f"{instance}: plan refused ({plan.status})")
        return 1
    timeline = plan.timeline.as_dict()
    grid = np.arange(timeline[args.start], timeline[args.stop] + 1e-9, args.every)
    instants = [(max((k for k in timeline if timeline[k] <= t + 1e-9), key=timeline.get), float(t)) for t in grid]
    print(f"{instance}: phases " + ", ".join(f"{k} {v:.2f} s" for k, v in timeline.items()))
    print(f"{'t (s)':>6s} {'phase':8s} {'tilt':>6s} {'rise':>7s}  hand links on the object")
    start = {}

    def trace(label, context):
        s = station_snapshot(td.station, context)
        if label == "start":
            start["X_WO"] = s.X_WO
            return
        links = sorted({_short(c.other(instance)) for c in s.contacts
                        if c.involves(instance) and c.other(instance).startswith("svh")})
        rise_cm = 100 * (s.X_WO[2, 3] - start["X_WO"][2, 3])
        print(f"{s.time:6.2f} {label:8s} {tilt_deg(start['X_WO'], s.X_WO):5.1f}° {rise_cm:5.1f}cm  "
              f"{', '.join(links) or '-'}")

    r = run_grasp_trial(scenario, motion, on_phase=trace, instants=instants)
    verdict = "functional" if r.functional_success else "grasped, not functional" if r.grasp_success else "failed"
    print(f"{instance}: {verdict} ({r.failure_reason or 'ok'}); tilt {r.object_tilt_deg:.1f}° at the end")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
