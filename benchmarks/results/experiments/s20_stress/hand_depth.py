"""Where the preshaped hand of the hand-written grasp meets each drill: the deepest hand links (no simulation).

    python benchmarks/results/experiments/s20_stress/hand_depth.py [--objects DIR ...] [--no-committed]

For each drill -- the committed ones, and any object directories given (the stress split's stretched drills
under out/benchmark/data/stress/drill/, the AIS imports under out/benchmark/data/ais/drill/, the YCB drill) --
the category's hand-written grasp is anchored on the drill's own annotated trigger (as
``diagrams/handwritten_sweep.py`` does) and the preshaped hand's collision geometry, sampled every 3 mm, is
compared with the drill's true mesh (its signed-distance grid, the planner's object clearance's own). Printed:
the deepest point of the whole hand (mm; positive = inside the drill, the clearance moves hands deeper than
4 mm) and the three hand links that come closest, each with its depth.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.data.dataset import imported_object, list_instances  # noqa: E402
from catgrasp_drake.planning.model import make_planning_model, object_mesh_path, true_object_field  # noqa: E402
from catgrasp_drake.planning.scene import hand_surface_samples_H, planning_scene  # noqa: E402
from catgrasp_drake.station.handwritten import load_handwritten_motion  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402


def hand_points_by_link(scenario, q_pre) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) points on the preshaped hand's collision geometry in the hand base frame H, and each one's link."""
    pm = make_planning_model(scenario)
    ctx = pm.diagram.CreateDefaultContext()
    c = planning_scene(pm.plant, pm.plant.GetMyMutableContextFromRoot(ctx), pm.scene_graph,
                       pm.scene_graph.GetMyMutableContextFromRoot(ctx), arm=pm.arm, hand=pm.hand,
                       object_instance=None, table=pm.table, q_arm_start=pm.q_arm_start, q_hand=q_pre)
    inspector = c.scene_graph.model_inspector()
    samples = hand_surface_samples_H(c)
    links = [inspector.GetName(inspector.GetFrameId(g)).split("::")[-1] for g, _ in samples]
    return np.vstack([p for _, p in samples]), np.repeat(links, [len(p) for _, p in samples])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", type=Path, nargs="*", default=[])
    ap.add_argument("--no-committed", action="store_true")
    args = ap.parse_args()
    items = [] if args.no_committed else [(name, None) for name in list_instances("drill")]
    items += [(imported_object(d)[1], d) for d in args.objects]
    base = load_scenario("drill_default")
    p_H = links = None
    print(f"{'drill':22s} {'deepest (mm)':>12s}   closest links (depth, mm)")
    for name, model_dir in items:
        scenario = with_instance(base, name, category="drill", model_dir=model_dir)
        motion = load_handwritten_motion("drill", name, annotations_dir=model_dir)
        if p_H is None:
            p_H, links = hand_points_by_link(scenario, motion.posture("preshape"))
        field = true_object_field(str(object_mesh_path(scenario.object)))
        X = motion.pose("grasp")
        depth = field(p_H @ X[:3, :3].T + X[:3, 3])
        per_link = sorted(((float(depth[links == k].max()), k) for k in dict.fromkeys(links)), reverse=True)
        print(f"{name:22s} {1000 * depth.max():12.1f}   "
              + ", ".join(f"{k.removeprefix('svh_')} {1000 * d:.1f}" for d, k in per_link[:3]))


if __name__ == "__main__":
    main()
