"""Session 45 probe: rank the latent fit's shape hypotheses by the plain likelihood? (tuning splits, no simulation)

    python benchmarks/results/experiments/s45_yaw_rank/probe.py --split val --categories drill \
        [--placements 12] [--seed 0] [--data-seed N] --out FILE.jsonl

Each object of the split is placed as the benchmark places it (``--seed``, depth noise on), seen once by the
station camera and fitted as ``latent`` fits (8 yaw starts, visibility-aware, 3 hypotheses). One JSON line per
view: per hypothesis its yaw error (deg), visibility-aware energy and plain energy (:func:`plain_energy`);
the hypothesis of the first-ranked grasp under each (``prediction.grasp_candidates``) and under the
``latent_plain`` method's ranking (``first_product``: the fit's own plain energies, ``core.inference.plain_energy``);
and the yaw error of the paper's plain fit (no camera) on the same view.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial.distance import cdist
from scipy.special import logsumexp

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import BenchmarkConfig, trial_scenario, trial_specs, yaw_error_deg  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.prediction import ShapeHypothesis, grasp_candidates  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402

#: The fit's outlier weight and prior (``infer_latent_pose`` defaults) and the sigma^2 grid profiled (m^2).
W_OUTLIER, PRIOR = 0.05, 1.0
SIGMA2_GRID = np.geomspace(1e-6, 1e-3, 31)
MAX_POINTS = 600


def plain_energy(completed_W, observed_W, x, w=W_OUTLIER, prior=PRIOR) -> float:
    """Eq. 15 with every model point a mixture centre: -sum_n log((1-w)/M sum_m N(o_n; T_m, s2) + w/V)
    minimised over s2 on SIGMA2_GRID, plus 0.5 prior |x|^2 (nats). V: the observation's box + 2 cm per side."""
    T, O = np.asarray(completed_W, float), np.asarray(observed_W, float)
    d2 = cdist(O, T, "sqeuclidean")
    M = len(T)
    log_v = float(np.log(np.prod(O.max(0) - O.min(0) + 0.02)))
    best = np.inf
    for s2 in SIGMA2_GRID:
        gauss = logsumexp(-d2 / (2 * s2), axis=1) - np.log(M) - 1.5 * np.log(2 * np.pi * s2) + np.log(1 - w)
        nll = -float(np.logaddexp(gauss, np.log(w) - log_v).sum())
        best = min(best, nll)
    return best + 0.5 * prior * float(np.asarray(x) @ np.asarray(x))


def first_hypothesis(model, hyps, energies) -> int:
    """The hypothesis of the first-ranked grasp with the hypotheses weighted by ``energies`` (no plain energies:
    ``grasp_candidates`` then weights by the given ones, whatever the category)."""
    ranked = grasp_candidates("latent", model, [dataclasses.replace(h, energy=e, plain_energy=float("nan"))
                                                for h, e in zip(hyps, energies)])
    return ranked[0].hypothesis


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", default="val")
    ap.add_argument("--categories", nargs="+", default=["drill"])
    ap.add_argument("--placements", type=int, default=12)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--data-seed", type=int, default=None, help="with --split fresh: its data-set seed")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    config = BenchmarkConfig(split=args.split, categories=tuple(args.categories), methods=("latent",),
                             placements=args.placements, seed=args.seed, data_seed=args.data_seed)
    specs = trial_specs(config)
    models = {}
    rng = np.random.default_rng(0)
    with open(args.out, "w") as f:
        for spec in specs:
            cat = spec["category"]
            if cat not in models:
                models[cat] = CategoryModel.load(spec["_model"], category=cat)
            model = models[cat]
            t0 = time.perf_counter()
            scenario, _, _ = trial_scenario(spec)
            X_WT, X_WO = scenario.table.pose.matrix(), scenario.X_WO()
            p_W, camera_W = observe(scenario)
            est = estimate_on_table(model.space, p_W, X_WT, camera_W=camera_W, yaw_candidates=8, hypotheses=3,
                                    plain_energies=True)
            paper = estimate_on_table(model.space, p_W, X_WT, camera_W=None, yaw_candidates=8)
            if not est.ok:
                continue
            fits = [h for h in (est.hypotheses or (est,)) if np.isfinite(h.energy)]
            O = p_W if len(p_W) <= MAX_POINTS else p_W[rng.choice(len(p_W), MAX_POINTS, replace=False)]
            hyps = [ShapeHypothesis(h.x, h.X_WO, h.scale, h.completed_W, h.energy, h.result.plain_energy)
                    for h in fits]
            vis_e = [h.energy for h in fits]
            plain_e = [plain_energy(h.completed_W, O, h.x) for h in fits]
            row = {"split": spec["split"], "category": cat, "instance": spec["instance"], "trial": spec["trial"],
                   "n_observed": len(p_W),
                   "hypotheses": [{"yaw_error_deg": yaw_error_deg(h.X_WO, X_WO), "energy": e, "plain_energy": pe,
                                   "scale": h.scale} for h, e, pe in zip(fits, vis_e, plain_e)],
                   "first_today": first_hypothesis(model, hyps, vis_e) if len(hyps) > 1 else 0,
                   "first_plain": first_hypothesis(model, hyps, plain_e) if len(hyps) > 1 else 0,
                   # the latent_plain method's ranking (prediction.grasp_candidates on the fit's own plain energies)
                   "first_product": grasp_candidates("latent_plain", model, hyps)[0].hypothesis if len(hyps) > 1 else 0,
                   "product_plain_energy": [h.plain_energy for h in hyps],
                   "paper_yaw_error_deg": yaw_error_deg(paper.X_WO, X_WO) if paper.ok else None,
                   "paper_plain_energy": plain_energy(paper.completed_W, O, paper.x) if paper.ok else None,
                   "seconds": round(time.perf_counter() - t0, 2)}
            f.write(json.dumps(row) + "\n")
            f.flush()
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
