"""Scratch scan (session 22, no simulation): thumb and little-finger preshapes of the hand-written spray grasp against
the committed bottles and their large / deep stress copies -- per posture and family, how many the planner's object
clearance leaves as written ("asis"), refuses ("ref"), and the median move (mm; inf when most are refused).

    python benchmarks/results/experiments/s22_spray_large/posture_scan.py [STRESS_DIR]

STRESS_DIR holds the stress split's spray bottles (default out/benchmark/data/stress/spray_bottle, written by
``catgrasp benchmark --split stress``). The written preshape (thumb flexion 0.97, opposition 0, little finger 0.98)
is the first row; no other of the 27 fits the large or deep bottles better (docs/benchmark.md, session 22).
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.core.clearance import clearance_shift  # noqa: E402
from catgrasp_drake.data.dataset import list_instances  # noqa: E402
from catgrasp_drake.planning.model import make_planning_model, object_mesh_path, true_object_field  # noqa: E402
from catgrasp_drake.planning.scene import hand_surface_samples_H, planning_scene  # noqa: E402
from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS  # noqa: E402
from catgrasp_drake.station.handwritten import handwritten_trial  # noqa: E402

CATEGORY = "spray_bottle"
JOINTS = list(HAND_ACTUATED_JOINTS)


def hand_points_H(pm, q_hand) -> np.ndarray:
    """Surface points (N, 3) of the hand in posture ``q_hand``, frame H."""
    ctx = pm.diagram.CreateDefaultContext()
    c = planning_scene(pm.plant, pm.plant.GetMyMutableContextFromRoot(ctx), pm.scene_graph,
                       pm.scene_graph.GetMyMutableContextFromRoot(ctx), arm=pm.arm, hand=pm.hand, object_instance=None,
                       table=pm.table, q_arm_start=pm.q_arm_start, q_hand=q_hand)
    return np.vstack([p for _, p in hand_surface_samples_H(c)])


def main() -> None:
    stress = Path(sys.argv[1] if len(sys.argv) > 1 else "out/benchmark/data/stress/spray_bottle")
    trials = [handwritten_trial(CATEGORY, name) for name in list_instances(CATEGORY)]
    trials += [handwritten_trial(object_dir=d) for family in ("large", "deep")
               for d in sorted(stress.glob(f"*_{family}"))]
    objects = [(s.object.instance, true_object_field(str(object_mesh_path(s.object))), m.pose("grasp"))
               for s, m in trials]
    pm = make_planning_model(trials[0][0])
    q_written = trials[0][1].posture("preshape")
    for thumb_flexion, opposition, pinky in itertools.product([0.97, 0.5, 0.2], [0.0, 0.5, 0.9], [0.98, 0.6, 0.3]):
        q = q_written.copy()
        q[JOINTS.index("svh_thumb_flexion")] = thumb_flexion
        q[JOINTS.index("svh_thumb_opposition")] = opposition
        q[JOINTS.index("svh_pinky")] = pinky
        P = hand_points_H(pm, q)
        moves = {"committed": [], "large": [], "deep": []}
        for name, field, X in objects:
            r = clearance_shift(P @ X[:3, :3].T + X[:3, 3], field, 0.004, 0.02)
            family = name.rsplit("_", 1)[-1] if name.endswith(("_large", "_deep")) else "committed"
            moves[family].append(1000 * np.linalg.norm(r.shift) if r.ok else np.inf)
        cells = [f"{f}: asis {sum(v == 0 for v in m)} ref {sum(np.isinf(m))} med {np.median(m):.1f}"
                 for f, m in moves.items()]
        print(f"thumb flexion {thumb_flexion} opposition {opposition} pinky {pinky}: " + " | ".join(cells))


if __name__ == "__main__":
    main()
