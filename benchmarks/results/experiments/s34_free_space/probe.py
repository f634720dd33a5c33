"""Session 34 probe: does a free-space check pick the right shape hypothesis? (COMMITTED instances, no simulation.)

    python benchmarks/results/experiments/s34_free_space/probe.py --category mug [--placements 3] [--seed 4242]
                                                                   [--hypotheses 4] --out FILE.jsonl

Each committed instance is placed as the benchmark places it (``--seed``, depth noise on), seen once by the
station camera and fitted as the ``latent`` method fits (8 yaw starts, visibility-aware), keeping
``--hypotheses`` refined fits. Per hypothesis, written as one JSON line per view: its yaw error (deg), energy
(nats) and, for its model points the camera would see (hidden-point removal), how many have no observed point
within 10, 15 and 20 mm: model surface where the camera saw none, i.e. free space the fit fills.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import trial_placement, yaw_error_deg  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.data.dataset import INSTANCE_COUNTS, instance_name  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402

RADII = (0.010, 0.015, 0.020)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", default="mug")
    ap.add_argument("--placements", type=int, default=3)
    ap.add_argument("--seed", type=int, default=4242)
    ap.add_argument("--hypotheses", type=int, default=4)
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    model = CategoryModel.load(default_model_path(args.category), category=args.category)
    with open(args.out, "w") as f:
        for i in range(INSTANCE_COUNTS[args.category]):
            name = instance_name(args.category, i)
            base = with_instance(load_scenario(f"{args.category}_default"), name, category=args.category)
            for k in range(args.placements):
                scenario, _, _ = trial_placement(base, name, k, args.seed, noise=True)
                X_WT, X_WO = scenario.table.pose.matrix(), scenario.X_WO()
                p_W, camera_W = observe(scenario)
                est = estimate_on_table(model.space, p_W, X_WT, camera_W=camera_W, yaw_candidates=8,
                                        hypotheses=args.hypotheses)
                tree = cKDTree(p_W)
                rows = []
                for h in est.hypotheses or (est,):
                    vis = h.result.visible
                    d, _ = tree.query(h.completed_W[vis])
                    rows.append({"yaw_error_deg": yaw_error_deg(h.X_WO, X_WO), "energy": h.energy,
                                 "n_visible": int(vis.sum()),
                                 "unsupported": [int((d > r).sum()) for r in RADII]})
                f.write(json.dumps({"instance": name, "placement": k, "n_observed": len(p_W),
                                    "hypotheses": rows}) + "\n")
                f.flush()
                print(name, k, [(round(r["yaw_error_deg"]), round(r["energy"], 1), r["unsupported"]) for r in rows])
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
