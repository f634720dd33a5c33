"""Session 25 probe: more views for the yaw, on the COMMITTED instances (no simulation, no test split).

    python benchmarks/results/experiments/s25_views/probe.py [--category mug] [--placements 3] [--seed 4242]

Each committed instance is placed as the benchmark places it (seed ``--seed``), seen by the station camera and
by the same camera turned +90, -90 and 180 deg about the object, with depth noise, and fitted as the ``latent``
method fits (8 yaw starts, 3 hypotheses). Printed: the yaw error of the fit on view sets {0}, {0, 90},
{0, 90, -90}, {0, 90, -90, 180} (visibility-aware for every camera, and without a visibility model), and of
active policies that take the next view while ``yaw_ambiguous`` says the yaw is open. JSON lines to stdout's
file with ``--out``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import trial_placement, yaw_error_deg  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.fileio import atomic_write_text  # noqa: E402
from catgrasp_drake.data.dataset import INSTANCE_COUNTS, instance_name  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.prediction import ESTIMATORS  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.systems.shape_estimator import estimate_on_table, yaw_ambiguous  # noqa: E402
from catgrasp_drake.transfer import observe  # noqa: E402

AZIMUTHS = (0.0, 90.0, -90.0, 180.0)
OK_DEG = 10.0


def committed_views(category: str, placements: int, seed: int, azimuths):
    """Each COMMITTED instance of ``category`` placed as the benchmark places it (``seed``, depth noise on) and
    seen by the station camera turned by each of ``azimuths`` (deg): yields ``(name, k, scenario, views)``,
    ``views`` the ``(points_W, camera position)`` of each azimuth."""
    for i in range(INSTANCE_COUNTS[category]):
        name = instance_name(category, i)
        base = with_instance(load_scenario(f"{category}_default"), name, category=category)
        for k in range(placements):
            scenario, _, _ = trial_placement(base, name, k, seed, noise=True)
            yield name, k, scenario, [observe(scenario, turn_deg=az) for az in azimuths]


def merged_fit(space, views, n: int, X_WT, *, visibility: bool = True):
    """The ``latent`` method's estimate (8 yaw starts, its hypotheses) on the first ``n`` of ``views`` merged:
    visibility-aware for every camera, or (``visibility=False``) fitted like a full cloud."""
    p = np.vstack([v[0] for v in views[:n]])
    cams = np.vstack([v[1] for v in views[:n]]) if visibility else None
    return estimate_on_table(space, p, X_WT, camera_W=cams, yaw_candidates=8,
                             hypotheses=ESTIMATORS["latent"].hypotheses)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", default="mug")
    ap.add_argument("--placements", type=int, default=3)
    ap.add_argument("--seed", type=int, default=4242)
    ap.add_argument("--out")
    args = ap.parse_args(argv)
    model = CategoryModel.load(default_model_path(args.category), category=args.category)
    rows = []
    for name, k, scenario, views in committed_views(args.category, args.placements, args.seed, AZIMUTHS):
        X_WT, X_WO = scenario.table.pose.matrix(), scenario.X_WO()
        row = {"instance": name, "placement": k}
        for n in range(1, len(AZIMUTHS) + 1):
            t0 = time.perf_counter()
            e = merged_fit(model.space, views, n, X_WT)
            row[f"vis{n}"] = round(yaw_error_deg(e.X_WO, X_WO), 1)
            row[f"vis{n}_amb"] = bool(yaw_ambiguous(e))
            row[f"vis{n}_s"] = round(time.perf_counter() - t0, 3)
            if n >= 2:
                row[f"novis{n}"] = round(yaw_error_deg(merged_fit(model.space, views, n, X_WT, visibility=False).X_WO,
                                                       X_WO), 1)
        for budget in (2, 3, 4):  # active: next view while ambiguous
            n = 1
            while n < budget and row[f"vis{n}_amb"]:
                n += 1
            row[f"active{budget}"] = row[f"vis{n}"]
            row[f"active{budget}_views"] = n
        rows.append(row)
        print(json.dumps(row), flush=True)
    keys = [f"vis{n}" for n in range(1, 5)] + [f"novis{n}" for n in range(2, 5)] + ["active2", "active3", "active4"]
    print(f"\n{args.category}: {len(rows)} views of the committed instances (seed {args.seed}); yaw within "
          f"{OK_DEG:g} deg")
    for key in keys:
        ok = sum(abs(r[key]) <= OK_DEG for r in rows)
        extra = ""
        if key.startswith("active"):
            extra = f", mean views {np.mean([r[key + '_views'] for r in rows]):.2f}"
        print(f"  {key:8s} {ok}/{len(rows)}{extra}")
    if args.out:
        atomic_write_text(args.out, "".join(json.dumps(r) + "\n" for r in rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
