"""Session 34 probe: stop refining shape hypotheses far behind the best (COMMITTED instances, no simulation).

    python benchmarks/results/experiments/s34_hypothesis_drop/probe.py [--categories drill spray_bottle mug]
                                                                        [--placements 3] [--seed 4242]
                                                                        [--drop-energy NATS] [--drop-after K]

Each committed instance is placed as the benchmark places it (``--seed``, depth noise on), seen once by the
station camera and fitted as the ``latent`` method fits (8 yaw starts, 3 hypotheses), twice: with every
hypothesis refined to the end (``drop_energy=None``, the earlier behaviour) and with the default
(``core.inference.DROP_ENERGY`` / ``DROP_AFTER``). Printed per category: views; hypotheses dropped; views whose
MAP fit is identical to the bit; views whose grasp candidates (``prediction.grasp_candidates``, the order the
planner tries them in) have the same order and the same motions to the bit; for every dropped hypothesis, its
energy gap to the best in the full run (nats) and how much of the gap at the pause the full refine closed; the
median fit time of both.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import trial_placement  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.inference import DROP_AFTER, DROP_ENERGY  # noqa: E402
from catgrasp_drake.data.dataset import INSTANCE_COUNTS, instance_name  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.prediction import ESTIMATORS, ShapeHypothesis, grasp_candidates  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402


def candidates(model, est):
    hyps = [ShapeHypothesis(h.x, h.X_WO, h.scale, h.completed_W, h.energy) for h in est.hypotheses]
    return grasp_candidates("latent", model, hyps) if len(hyps) > 1 else []


def is_dropped(h, after: int) -> bool:
    """A hypothesis stopped at the pause (``after`` iterations, not converged)."""
    return h.result.iterations <= after and not h.result.converged


def same_candidates(a, b) -> bool:
    if len(a) != len(b):
        return False
    return all(np.array_equal(ca.motion.poses, cb.motion.poses) and ca.hypothesis == cb.hypothesis
               for ca, cb in zip(a, b))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--categories", nargs="+", default=["drill", "spray_bottle", "mug"])
    ap.add_argument("--placements", type=int, default=3)
    ap.add_argument("--seed", type=int, default=4242)
    ap.add_argument("--drop-energy", type=float, default=DROP_ENERGY, help="nats (default: the library's)")
    ap.add_argument("--drop-after", type=int, default=DROP_AFTER, help="iterations (default: the library's)")
    args = ap.parse_args(argv)
    setting = dict(drop_energy=args.drop_energy, drop_after=args.drop_after)
    hyp = ESTIMATORS["latent"].hypotheses
    for category in args.categories:
        model = CategoryModel.load(default_model_path(category), category=category)
        n = dropped = same_map = same_first = same_cands = same_kept = merged = 0
        pairs = []
        gaps, closed, t_full, t_drop = [], [], [], []
        for i in range(INSTANCE_COUNTS[category]):
            name = instance_name(category, i)
            base = with_instance(load_scenario(f"{category}_default"), name, category=category)
            for k in range(args.placements):
                scenario, _, _ = trial_placement(base, name, k, args.seed, noise=True)
                X_WT = scenario.table.pose.matrix()
                p_W, camera_W = observe(scenario)
                kw = dict(camera_W=camera_W, yaw_candidates=8, hypotheses=hyp)
                t0 = time.perf_counter()
                full = estimate_on_table(model.space, p_W, X_WT, drop_energy=None, **kw)
                t_full.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                drop = estimate_on_table(model.space, p_W, X_WT, **setting, **kw)
                t_drop.append(time.perf_counter() - t0)
                n += 1
                same_map += bool(np.array_equal(full.x, drop.x) and np.array_equal(full.X_WO, drop.X_WO))
                cf, cd = candidates(model, full), candidates(model, drop)
                same_cands += same_candidates(cf, cd)
                same_first += same_candidates(cf[:1], cd[:1])
                kept = [c for c in cd if not is_dropped(drop.hypotheses[c.hypothesis], args.drop_after)]
                same_kept += same_candidates([c for c in cf if c.weight > 1e-3], [c for c in kept if c.weight > 1e-3])
                by_rank = {h.result.diagnostics["search_rank"]: h for h in full.hypotheses}
                for h in drop.hypotheses:
                    if is_dropped(h, args.drop_after):
                        dropped += 1
                        g = by_rank.get(h.result.diagnostics["search_rank"])
                        if g is None:  # the full refine took it into another hypothesis' mode
                            merged += 1
                            continue
                        gaps.append(g.energy - full.energy)
                        closed.append((h.energy - drop.energy) - (g.energy - full.energy))
                        pairs.append((round(h.energy - drop.energy), round(g.energy - full.energy)))
        print(f"{category}, drop_energy {args.drop_energy:g} nats after {args.drop_after} iterations: "
              f"{n} views, {dropped} hypotheses dropped ({merged} of them merged into another mode by "
              f"the full refine); MAP fit identical {same_map}/{n}; first grasp candidate identical {same_first}/{n}, "
              f"candidates of weight > 1e-3 identical {same_kept}/{n}, all candidates identical {same_cands}/{n}; "
              f"dropped hypotheses' gap to the best in the full run "
              f"min {min(gaps, default=float('nan')):.0f} nats (weight <= "
              f"{np.exp(-min(gaps, default=np.inf) / 15.0):.1e}), gap closed by the full refine at most "
              f"{max(closed, default=float('nan')):.0f} nats; median fit {1000 * np.median(t_full):.0f} ms -> "
              f"{1000 * np.median(t_drop):.0f} ms", flush=True)
        print("  (gap at the pause, gap after the full refine) of each dropped hypothesis, nats:", sorted(pairs))
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
