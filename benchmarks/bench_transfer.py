"""Perception-to-motion latency of the transfer diagram (depth image in -> grasp motion out), by estimator setting.

For each held-out instance of the committed category model and each seeded
placement, the transfer diagram (single view, unknown yaw: 8 starts) is built
once per setting; per placement a fresh context is made and, with the depth
and label images already rendered (the sensor's own time, reported apart),
the stages are timed through the diagram's ports:

1. ``cloud``: label mask, DepthImageToPointCloud, crop, voxel grid (ObjectCloudSystem);
2. ``estimate``: the LatentShapeEstimator's fit; of which ``core`` is the
   core's ``infer_latent_pose`` time (its own timer);
3. ``regress``: the GraspRegressor's output (R(x), warp, similarity);
4. ``IK plan``: the MotionPlanner's ``plan`` port (not part of the latency).

Latency = cloud + estimate + regress (arm planning excluded). The share
outside the core = (latency - core) / latency. Median and max over all runs.

Settings, interleaved placement by placement so that both see the same load:

* ``old``: the estimator as before issue 17 -- ``voxel_size=None`` (the
  camera's 5 mm cloud as given) and ``core.inference.LEGACY_SEARCH`` (all 8
  starts searched to the end, two hidden-point removals per start, float64,
  visibility recomputed on schedule);
* ``new``: the defaults (the fit's voxel grid at 1.4x the model's spacing,
  the 4 best of 8 starts kept after 2 iterations, float32 search E-step,
  visibility updates skipped while the model moved < 2 mm).

* ``fast`` (``--settings old new fast``; session 23): what the 50 ms goal costs -- one shape
  hypothesis (no posterior: the ``latent_map`` estimate), the yaw search's starts 8 iterations
  instead of 12 and the refine at most 12 instead of 40 (``prediction.FAST_ESTIMATE``; the benchmark's
  ``latent_fast`` method). Chosen on the committed
  held-out instances this script measures; not a default.

* ``free`` (session 31): ``new`` with the paper's free similarity (three rotation angles) instead of the
  default upright fit (a yaw about the table normal): what keeping the object upright costs or saves.
  Every other setting is upright.

* ``parallel`` (session 32): ``new`` with the yaw search's starts and the shape hypotheses fitted side by
  side, a thread per core (``fit_threads=None``), instead of one after another; the same estimate to the
  bit, so the difference is time only.

* ``nodrop`` (session 34): ``new`` with every shape hypothesis refined to the end, as before
  ``core.inference.DROP_ENERGY``: hypotheses more than 200 nats behind the best after 16 iterations now stop
  there (the MAP fit unchanged).

Also per setting: the estimate's accuracy against the true object (its mesh
surface, 4000 seeded samples, at its true pose): Chamfer distance, the error
on the part the camera does not see (true points > 1 cm from the observed
cloud) and the rotation error of X_WO (deg). The cloud stage's code and the
regressor's single-threaded BLAS are the same in both settings (the cloud is
bit-identical to the earlier code, which took ~20 ms: see the report).

* ``f64`` (session 46): ``new`` with every E-step's kernel in float64, as before ``kernel32`` (the default now
  takes the ``exp`` of its float64 exponents in float32: ``core.cpd.estep(kernel32=True)``).

* ``noreseed`` (session 48): ``new`` without ``reseed`` -- the other shape hypotheses not refined again from the
  best fit's shape (``prediction.RESEEDED_CATEGORIES``: the default for mugs only; elsewhere the same as ``new``).

Run:  python benchmarks/bench_transfer.py [--category drill] [--seeds 5]
      [--settings old new fast free parallel nodrop f64 noreseed]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.inference import LEGACY_SEARCH  # noqa: E402
from catgrasp_drake.data.dataset import instance_mesh_path, list_instances  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.prediction import FAST_ESTIMATE  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance  # noqa: E402
from catgrasp_drake.transfer import make_transfer_diagram  # noqa: E402

#: One shape hypothesis, a shorter yaw search and refine: the 50 ms setting (module docstring), the benchmark's
#: ``latent_fast`` method.
SETTINGS = {"old": dict(voxel_size=None, **LEGACY_SEARCH), "new": {}, "fast": {"hypotheses": 1} | FAST_ESTIMATE,
            "free": {"upright": False}, "parallel": {"fit_threads": None}, "nodrop": {"drop_energy": None},
            "f64": {"kernel32": False}, "noreseed": {"reseed": False}}
NAMES = ("render (sensor)", "cloud", "estimate", "  of which core", "regress", "LATENCY", "share outside core",
         "IK plan")


def true_surface_W(scenario, n=4000):
    o = scenario.object
    mesh = trimesh.load(instance_mesh_path(o.category, o.instance), force="mesh", process=False)
    p, _ = trimesh.sample.sample_surface(mesh, n, seed=0)
    X = scenario.X_WO()
    return np.asarray(p) @ X[:3, :3].T + X[:3, 3]


def run_once(scenario, model, options, truth):
    td = make_transfer_diagram(scenario, model, **options)
    ctx = td.diagram.CreateDefaultContext()
    sensor = td.station.cameras["camera0"]
    s_ctx = sensor.GetMyContextFromRoot(ctx)
    t0 = time.perf_counter()
    sensor.depth_image_32F_output_port().Eval(s_ctx)
    sensor.label_image_output_port().Eval(s_ctx)
    render = time.perf_counter() - t0
    t0 = time.perf_counter()
    td.cloud_port.Eval(td.cloud_port.get_system().GetMyContextFromRoot(ctx))
    cloud = time.perf_counter() - t0
    e_ctx = td.estimator.GetMyMutableContextFromRoot(ctx)
    t0 = time.perf_counter()
    est = td.estimator.estimate_now(e_ctx)
    estimate = time.perf_counter() - t0
    td.estimator.set_estimate(e_ctx, est)
    t0 = time.perf_counter()
    td.regressor.GetOutputPort("grasp_motion_W").Eval(td.regressor.GetMyContextFromRoot(ctx))
    regress = time.perf_counter() - t0
    t0 = time.perf_counter()
    plan = td.generator.GetOutputPort("plan").Eval(td.generator.GetMyContextFromRoot(ctx))
    t_plan = time.perf_counter() - t0
    core = est.timing["total"]
    latency = cloud + estimate + regress
    times = (render, cloud, estimate, core, regress, latency, (latency - core) / latency, t_plan)
    c = est.completed_W
    hidden = truth[cKDTree(est.observed_W).query(truth)[0] > 0.01]
    chamfer = 0.5 * (cKDTree(truth).query(c)[0].mean() + cKDTree(c).query(truth)[0].mean())
    unseen = cKDTree(c).query(hidden)[0].mean()
    X_true = scenario.X_WO()
    cos = (np.trace(est.X_WO[:3, :3].T @ X_true[:3, :3]) - 1.0) / 2.0
    acc = (1e3 * chamfer, 1e3 * unseen, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))))
    return times, acc, len(est.observed_W), est.result.diagnostics["n_observed"], plan.ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", default="drill")
    ap.add_argument("--seeds", type=int, default=5, help="placements per held-out instance")
    ap.add_argument("--settings", nargs="+", default=["old", "new"], choices=list(SETTINGS),
                    help="estimator settings timed side by side (interleaved placement by placement)")
    args = ap.parse_args(argv)
    settings = {k: SETTINGS[k] for k in args.settings}
    model = CategoryModel.load(default_model_path(args.category), category=args.category)
    held_out = [n for n in list_instances(args.category) if n not in model.instances]
    rows = {k: [] for k in settings}
    accs = {k: [] for k in settings}
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} at the start")
    for instance in held_out:
        base = with_instance(load_scenario(f"{args.category}_default"), instance)
        for seed in range(args.seeds):
            scenario = random_placement(base, seed)
            truth = true_surface_W(scenario)
            order = list(settings) if seed % 2 == 0 else list(settings)[::-1]
            for name in order:
                times, acc, n_obs, n_fit, ok = run_once(scenario, model, settings[name], truth)
                rows[name].append(times)
                accs[name].append(acc)
                print(f"  {instance} seed {seed} {name}: {n_obs} points ({n_fit} fitted), "
                      f"latency {1000 * times[5]:.0f} ms (core {1000 * times[3]:.0f} ms), "
                      f"plan {1000 * times[7]:.0f} ms ({'ok' if ok else 'failed'}), "
                      f"unseen {acc[1]:.2f} mm, rotation {acc[2]:.1f} deg")
    n_runs = len(next(iter(rows.values())))
    print(f"\n{args.category}: {n_runs} runs per setting ({len(held_out)} held-out instances x {args.seeds} "
          f"placements), single view, unknown yaw (8 starts); load average {os.getloadavg()[0]:.2f} at the end")
    print("| stage | " + " | ".join(f"{s} median | {s} max" for s in settings) + " |")
    print("|---|" + "---|---|" * len(settings))
    A = {k: np.array(v) for k, v in rows.items()}
    for k, name in enumerate(NAMES):
        cells = []
        for s in settings:
            col = A[s][:, k]
            if name.startswith("share"):
                cells += [f"{100 * np.median(col):.1f}%", f"{100 * col.max():.1f}%"]
            else:
                cells += [f"{1000 * np.median(col):.1f} ms", f"{1000 * col.max():.1f} ms"]
        print(f"| {name.strip()} | " + " | ".join(cells) + " |")
    print("\nAccuracy against the true object (mean over runs; rotation: median and max)")
    print("| setting | Chamfer (mm) | unseen part (mm) | rotation error median (deg) | max (deg) |")
    print("|---|---|---|---|---|")
    for s in settings:
        a = np.array(accs[s])
        print(f"| {s} | {a[:, 0].mean():.2f} | {a[:, 1].mean():.2f} | {np.median(a[:, 2]):.1f} | {a[:, 2].max():.1f} |")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
