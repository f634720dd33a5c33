"""How many shape hypotheses, which temperature, and does ranking by support change the grasp? (tuning set)

    python benchmarks/bench_posterior.py [--categories mug drill spray_bottle] [--placements 3] [--seed 4242]

On the COMMITTED instances only (``models/objects``; the test split is never
used), each instance is placed ``--placements`` times by the benchmark's
seeded placement (``benchmark.runner.trial_placement`` with ``--seed``), seen
once by the station camera with depth noise, and fitted by the transfer
diagram's estimator (``estimate_on_table``, 8 yaw starts); no simulation.
Printed per category:

- for each number of hypotheses k: how many views the estimate's yaw is
  within 10 deg of the truth, and the median estimate time;
- with every start refined (``hypotheses=8, yaw_keep=None``): the same count,
  the views whose best-support grasp (``prediction.grasp_candidates``) is not
  the MAP fit's, for temperatures 1-30 nats and radii 1-4 cm, the mean
  log-probability the tempered weights give the hypotheses within 10 deg, and
  the count when the most confident fit is chosen instead of the lowest energy.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.benchmark.runner import trial_placement, yaw_error_deg  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.data.dataset import INSTANCE_COUNTS, instance_name  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.prediction import ShapeHypothesis, grasp_candidates, hypothesis_weights  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402

YAW_OK_DEG = 10.0
KS = (1, 2, 3, 4)
TEMPERATURES = (1.0, 3.0, 5.0, 15.0, 30.0, 40.0)
RADII = (0.01, 0.02, 0.04)


def views(category: str, placements: int, seed: int):
    """(instance, placement index, points_W, camera_W, X_WT, X_WO true) of every committed instance."""
    for i in range(INSTANCE_COUNTS[category]):
        name = instance_name(category, i)
        base = with_instance(load_scenario(f"{category}_default"), name, category=category)
        for k in range(placements):
            scenario, _, _ = trial_placement(base, name, k, seed, noise=True)
            p_W, camera_W = observe(scenario)
            yield name, k, p_W, camera_W, scenario.table.pose.matrix(), scenario.X_WO()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--categories", nargs="+", default=["mug", "drill", "spray_bottle"])
    ap.add_argument("--placements", type=int, default=3)
    ap.add_argument("--seed", type=int, default=4242)
    args = ap.parse_args(argv)
    for category in args.categories:
        model = CategoryModel.load(default_model_path(category), category=category)
        ok = {k: 0 for k in KS}
        ms = {k: [] for k in KS}
        full_ok = conf_ok = n = 0
        changed = {(T, r): 0 for T in TEMPERATURES for r in RADII}
        logp = {T: [] for T in TEMPERATURES}
        for _name, _k, p_W, camera_W, X_WT, X_WO in views(category, args.placements, args.seed):
            n += 1
            for h in KS:
                t0 = time.perf_counter()
                e = estimate_on_table(model.space, p_W, X_WT, camera_W=camera_W, yaw_candidates=8, hypotheses=h)
                ms[h].append(1000 * (time.perf_counter() - t0))
                ok[h] += abs(yaw_error_deg(e.X_WO, X_WO)) <= YAW_OK_DEG
            e = estimate_on_table(model.space, p_W, X_WT, camera_W=camera_W, yaw_candidates=8, hypotheses=8,
                                  yaw_keep=None)
            fits = e.hypotheses or (e,)
            right = np.array([abs(yaw_error_deg(f.X_WO, X_WO)) <= YAW_OK_DEG for f in fits])
            full_ok += bool(right[0])
            conf_ok += bool(right[int(np.argmax([f.confidence for f in fits]))])
            hyps = [ShapeHypothesis(f.x, f.X_WO, f.scale, f.completed_W, f.energy) for f in fits]
            for T in TEMPERATURES:
                for r in RADII:
                    top = grasp_candidates("latent", model, hyps, temperature=T, radius=r)[0]
                    changed[(T, r)] += top.hypothesis != 0
                if right.any():
                    w = hypothesis_weights([f.energy for f in fits], T)
                    logp[T].append(float(np.log(max(w[right].sum(), 1e-12))))
        print(f"\n{category}: {n} views of the committed instances (seed {args.seed}), yaw within {YAW_OK_DEG:g} deg")
        print("| hypotheses | yaw right | median estimate |\n|---:|---:|---:|")
        for h in KS:
            print(f"| {h} | {ok[h]}/{n} | {np.median(ms[h]):.0f} ms |")
        print(f"| 8, every start refined | {full_ok}/{n} | — |")
        print(f"most confident of the 8 instead of the lowest energy: {conf_ok}/{n}")
        print("views where the best-support grasp is not the MAP fit's (temperature x radius): "
              + ", ".join(f"T={T:g} r={100 * r:g}cm: {c}" for (T, r), c in changed.items()))
        print("mean log-probability of the right hypotheses: "
              + ", ".join(f"T={T:g}: {np.mean(v):.2f}" for T, v in logp.items() if v))
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
