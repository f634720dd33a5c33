"""Session 26 probe: how deep the preshaped spray-bottle hand lies in the bottle when moved forward (no simulation).

    python benchmarks/results/experiments/s26_trigger_gap/hand_fit_forward.py

The hand-written grasp on the large stress copy of committed bottle 03 and on committed bottle 01, moved
forward (+y) by 0-15 mm and down by 0 or 10 mm, checked with ``planning.fit.hand_fit`` against the true mesh:
the deepest hand links and what the planner's object clearance would do. Tuning objects only.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.benchmark.runner import stretched_objects  # noqa: E402
from catgrasp_drake.planning.fit import hand_fit  # noqa: E402
from catgrasp_drake.station.handwritten import load_handwritten_motion, shifted_motion  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402


def main() -> int:
    (_, large_03), = stretched_objects(ROOT / "out" / "benchmark" / "data" / "stress", "spray_bottle",
                                       ["spray_bottle_03"], ["large"])
    for instance, directory in (("spray_bottle_03_large", str(large_03)), ("spray_bottle_01", None)):
        scenario = with_instance(load_scenario("spray_bottle_default"), instance, category="spray_bottle",
                                 model_dir=directory)
        motion = load_handwritten_motion("spray_bottle", instance, annotations_dir=directory)
        for dy in (0.0, 0.005, 0.01, 0.015):
            for dz in (0.0, -0.01):
                moved = shifted_motion(motion, "spray_bottle", instance, (0.0, dy, dz), (0.0, 0.0, 0.0),
                                       annotations_dir=directory)
                print(f"{instance} forward {1000 * dy:.0f} mm, down {1000 * abs(dz):.0f} mm: "
                      f"{hand_fit(scenario, moved).summary()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
