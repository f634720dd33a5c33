"""Probe a hand-written spray-bottle trial at its phases: hand joints, hand place, index contacts (session 17).

    python benchmarks/results/experiments/s17_windex/probe.py --object out/ycb/spray_bottle/ycb_022 \
        [--index-target 0.7227 0.496]
    python benchmarks/results/experiments/s17_windex/probe.py --instance spray_bottle_11 [--index-target ...]

Scratch experiment behind docs/station.md, "Why the Windex bottle turned in the hand" (session 17): the
category's hand-written grasp (seed 0 placement, true-object planner, default physics) with, optionally,
the index finger's closed posture set to ``--index-target`` (proximal, distal; rad; session 16's grasp:
0.7227 0.496). At the start of the closing, the start of the lift, mid-hold and the end it prints the 9
actuated hand joints, the hand frame's origin relative to the trigger centre (mm, object frame) and the
index distal link's contact points (mm, object frame); then the verdict and the in-hand shift and turn.
"""
import argparse

import numpy as np

from catgrasp_drake.data.dataset import load_annotations, read_annotations
from catgrasp_drake.robot.specs import SVH_ACTUATED_JOINTS
from catgrasp_drake.station.handwritten import handwritten_trial, with_postures
from catgrasp_drake.station.judge import in_hand_pose
from catgrasp_drake.trial import plan_for, run_grasp_trial, station_snapshot, trial_diagram

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--object", help="an imported object's directory")
ap.add_argument("--instance", help="a committed spray bottle")
ap.add_argument("--index-target", type=float, nargs=2, metavar=("PROXIMAL", "DISTAL"))
args = ap.parse_args()
if args.object:
    scenario, motion = handwritten_trial(None, None, object_dir=args.object, seed=0)
    ann = read_annotations(f"{args.object}/annotations.json")
else:
    scenario, motion = handwritten_trial("spray_bottle", args.instance, seed=0)
    ann = load_annotations("spray_bottle", args.instance)
if args.index_target:
    index_closed = dict(zip(("svh_index_proximal", "svh_index_distal"), args.index_target))
    motion = with_postures(motion, {"closed": index_closed})
trigger_O = np.array(ann["regions"]["trigger"]["center"])
td = trial_diagram(scenario)
plan = plan_for(td, motion.in_world(scenario.X_WO()))
t = plan.timeline.as_dict()
plant, hand, name = td.station.plant, td.station.hand, scenario.object.instance
closed = zip(SVH_ACTUATED_JOINTS, motion.posture("closed"))
print("closed posture target:", " ".join(f"{j[4:]}={q:.3f}" for j, q in closed))


def probe(label, context):
    s = station_snapshot(td.station, context)
    pc = plant.GetMyContextFromRoot(context)
    q = [plant.GetJointByName(j, hand).get_angle(pc) for j in SVH_ACTUATED_JOINTS]
    X_OH = np.linalg.inv(in_hand_pose(s))
    R, p = s.X_WO[:3, :3], s.X_WO[:3, 3]
    index = [np.round(1000 * ((np.asarray(c.points_W) - p) @ R).mean(axis=0), 1) for c in s.contacts
             if c.involves(name) and c.other(name).endswith("svh_index_distal_link")]
    print(f"{label:6s} t {context.get_time():5.2f} s | joints " + " ".join(f"{a:.3f}" for a in q)
          + f" | H - trigger (mm, O) {np.round(1000 * (X_OH[:3, 3] - trigger_O), 1)}"
          + f" | index distal contacts (mm, O) {index}")


r = run_grasp_trial(scenario, motion, on_phase=probe, instants=[
    ("close", t["close"]), ("lift", t["lift"]), ("hold", 0.5 * (t["hold"] + t["shake"])), ("end", t["end"] - 0.01)])
print(f"{name}: {r.failure_reason or 'functional'} {r.detail}; in-hand shift {1000 * r.in_hand_shift_m:.1f} mm, "
      f"turn {r.in_hand_turn_deg:.1f} deg")
