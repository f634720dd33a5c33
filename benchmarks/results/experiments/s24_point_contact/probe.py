"""Point contact on convex pieces (issue 17's speed lever, session 24): real-time rate and outcome against the default.

    pip install coacd
    python benchmarks/results/experiments/s23_convex_pieces/make_pieces.py --out PIECES
    python benchmarks/results/experiments/s24_point_contact/probe.py PIECES [--allowances 1e-3 1e-4] [--out FILE]

Drake's point contact meets a non-convex mesh as its convex hull (docs/design.md), which closes a drill's
trigger gap and a mug's handle. The probe therefore gives point contact the objects' convex pieces (``rigid``
mode of make_pieces.py), at each ``PlantSpec.penetration_allowance``. The default runs beside it: today's
rigid-hydroelastic mesh against the hand's compliant capsules. Each trial is the hand-written grasp at
placements 0 and 1, simulated to its end, one at a time.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(REPO))

from catgrasp_drake.core.fileio import atomic_write_text  # noqa: E402
from catgrasp_drake.station.handwritten import handwritten_trial  # noqa: E402
from catgrasp_drake.trial import run_grasp_trial  # noqa: E402

OBJECTS = ["drill/drill_00", "drill/drill_03", "spray_bottle/spray_bottle_00", "mug/mug_00"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pieces", type=Path, help="the --out directory of make_pieces.py")
    ap.add_argument("--allowances", type=float, nargs="+", default=[1e-3, 1e-4])
    ap.add_argument("--out", type=Path, default=Path(__file__).with_name("results.jsonl"))
    args = ap.parse_args(argv)
    settings = [("mesh", {})] + [("rigid", {"contact_model": "point", "penetration_allowance": a})
                                 for a in args.allowances]
    rows = []
    for obj in OBJECTS:
        for seed in (0, 1):
            for mode, plant in settings:
                scenario, motion = handwritten_trial(object_dir=args.pieces / mode / obj, seed=seed)
                scenario = dataclasses.replace(scenario, plant=dataclasses.replace(scenario.plant, **plant))
                r = run_grasp_trial(scenario, motion, stop_when_decided=False)
                row = {"object": obj, "seed": seed, "geometry": "mesh" if mode == "mesh" else "convex pieces",
                       "contact_model": plant.get("contact_model", "hydroelastic_with_fallback"),
                       "penetration_allowance": scenario.plant.penetration_allowance,
                       "realtime_rate": round(r.sim_time_s / r.wall_time_s, 3), "grasp": r.grasp_success,
                       "functional": r.functional_success, "reason": r.failure_reason, "detail": r.detail}
                rows.append(row)
                print(json.dumps(row), flush=True)
    atomic_write_text(args.out, "".join(json.dumps(r) + "\n" for r in rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
