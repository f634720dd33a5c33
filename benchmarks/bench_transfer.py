"""Perception-to-motion latency of the grasp transfer diagram (depth image in -> grasp motion out).

For each held-out instance of the committed category model and each seeded
placement, the transfer diagram (single view, unknown yaw: 8 starts) is built
once per instance; per placement a fresh context is made and, with the depth
and label images already rendered (the sensor's own time, reported apart),
the stages are timed through the diagram's ports:

1. ``cloud``: label mask, DepthImageToPointCloud, crop, voxel grid (ObjectCloudSystem);
2. ``estimate``: the LatentShapeEstimator's fit; of which ``core`` is the
   core's ``infer_latent_pose`` time (its own timer);
3. ``regress``: the GraspRegressor's output (R(x), warp, similarity).

Latency = cloud + estimate + regress (arm planning excluded). The share
outside the core = (latency - core) / latency. Median and max over all runs.

Run:  python benchmarks/bench_transfer.py [--category drill] [--seeds 5]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.data.dataset import list_instances  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance  # noqa: E402
from catgrasp_drake.transfer import make_transfer_diagram  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", default="drill")
    ap.add_argument("--seeds", type=int, default=5, help="placements per held-out instance")
    args = ap.parse_args(argv)
    model = CategoryModel.load(default_model_path(args.category), category=args.category)
    held_out = [n for n in list_instances(args.category) if n not in model.instances]
    rows = []
    for instance in held_out:
        base = with_instance(load_scenario(f"{args.category}_default"), instance)
        for seed in range(args.seeds):
            td = make_transfer_diagram(random_placement(base, seed), model)
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
            core = est.timing["total"]
            latency = cloud + estimate + regress
            rows.append((render, cloud, estimate, core, regress, latency, (latency - core) / latency))
            print(f"  {instance} seed {seed}: {len(est.observed_W)} points, latency {1000 * latency:.0f} ms "
                  f"(core {1000 * core:.0f} ms), render {1000 * render:.0f} ms")
    A = np.array(rows)
    names = ("render (sensor)", "cloud", "estimate", "  of which core", "regress", "LATENCY", "share outside core")
    print(f"\n{args.category}: {len(rows)} runs ({len(held_out)} held-out instances x {args.seeds} placements), "
          "single view, unknown yaw (8 starts)")
    print(f"| {'stage':<20s} | {'median':>10s} | {'max':>10s} |")
    print(f"|{'-' * 22}|{'-' * 12}|{'-' * 12}|")
    for k, name in enumerate(names):
        if name.startswith("share"):
            print(f"| {name:<20s} | {100 * np.median(A[:, k]):9.1f}% | {100 * A[:, k].max():9.1f}% |")
        else:
            print(f"| {name:<20s} | {1000 * np.median(A[:, k]):7.1f} ms | {1000 * A[:, k].max():7.1f} ms |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
