"""Session 48 probe: refine the other shape hypotheses again from the best fit's shape? (tuning splits, no simulation)

    python benchmarks/results/experiments/s48_reseed/probe.py --split val --categories mug drill spray_bottle \
        [--placements 12] [--seed 0] [--data-seed N] --out FILE.jsonl

Each object of the split is placed as the benchmark places it (``--seed``, depth noise on), seen once by the
station camera and fitted as ``latent`` fits (8 yaw starts, visibility-aware, 3 hypotheses), once as today and
once with ``infer_latent_pose(reseed=True)``. One JSON line per view: for each fit, per hypothesis its yaw error
(deg), energy (nats) and uncovered observed points, the hypothesis of the grasp ``prediction.grasp_candidates``
ranks first (the product's ranking for the category) and the estimate's core time (s).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import BenchmarkConfig, observed_views, yaw_error_deg  # noqa: E402
from catgrasp_drake.prediction import POSTERIOR_HYPOTHESES, ShapeHypothesis, grasp_candidates  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402


def fit(model, p_W, X_WT, camera_W, X_WO, reseed: bool) -> dict | None:
    est = estimate_on_table(model.space, p_W, X_WT, camera_W=camera_W, yaw_candidates=8,
                            hypotheses=POSTERIOR_HYPOTHESES, reseed=reseed)
    if not est.ok:
        return None
    fits = [h for h in (est.hypotheses or (est,)) if math.isfinite(h.energy)]
    hyps = [ShapeHypothesis(h.x, h.X_WO, h.scale, h.completed_W, h.energy, uncovered=h.uncovered) for h in fits]
    first = grasp_candidates("latent", model, hyps)[0].hypothesis
    return {"hypotheses": [{"yaw_error_deg": round(yaw_error_deg(h.X_WO, X_WO), 3), "energy": round(h.energy, 3),
                            "uncovered": int(h.uncovered), "latent_norm": round(float((h.x @ h.x) ** 0.5), 3)}
                           for h in fits],
            "first": first, "time_s": round(float(est.result.timing["total"]), 4)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", default="val")
    ap.add_argument("--categories", nargs="+", default=["mug"])
    ap.add_argument("--placements", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--data-seed", type=int, default=None)
    ap.add_argument("--data", default="out/benchmark/data")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    config = BenchmarkConfig(split=args.split, categories=tuple(args.categories), methods=("latent",),
                             views=("single",), placements=args.placements, seed=args.seed,
                             data_seed=args.data_seed, data_dir=args.data)
    with open(args.out, "w") as f:
        for spec, model, scenario, placement, camera, p_W, camera_W in observed_views(config):
            cat = spec["category"]
            X_WT, X_WO = scenario.table.pose.matrix(), scenario.X_WO()
            today = fit(model, p_W, X_WT, camera_W, X_WO, False)
            again = fit(model, p_W, X_WT, camera_W, X_WO, True)
            if today is None or again is None:
                continue
            line = {"category": cat, "instance": spec["instance"], "trial": spec["trial"],
                    "functional_azimuth_deg": round((placement["yaw_deg"] + 90 - camera["azimuth_deg"] + 180) % 360
                                                    - 180, 1), "today": today, "reseed": again}
            f.write(json.dumps(line) + "\n")
            f.flush()
            print(cat, spec["instance"], spec["trial"],
                  [(round(h["yaw_error_deg"]), round(h["energy"])) for h in today["hypotheses"]], today["first"], "->",
                  [(round(h["yaw_error_deg"]), round(h["energy"])) for h in again["hypotheses"]], again["first"],
                  flush=True)
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
