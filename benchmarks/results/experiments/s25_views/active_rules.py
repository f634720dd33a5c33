"""Session 25 probe: when to look again -- the yaw's ambiguity, or the grasp's functional part unseen (committed only).

    python benchmarks/results/experiments/s25_views/active_rules.py --category mug [--out active_rules_mug.jsonl]

Each COMMITTED instance (the tuning set) is placed three times as the benchmark does (seed 4242, depth noise
on) and fitted as the ``latent`` method fits (8 yaw starts, 3 hypotheses) on its first view, the first two
and all three (the station camera, then turned +90 and -90 deg; ``transfer.EXTRA_VIEW_AZIMUTHS_DEG``). Each
line: per view count n, the yaw error (deg), whether the fit is yaw-ambiguous (``yaw_ambiguous``) and the
fraction of its functional part observed (``part_seen_fraction``: the fit's points within 2 cm of the
category's functional point with a data point within 1 cm). Printed: yaws within 10 deg and mean views of
active policies (next view while the rule holds, at most three) for each rule and threshold.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from probe import committed_views, merged_fit  # noqa: E402  (this folder's probe.py)

from catgrasp_drake.benchmark.runner import yaw_error_deg  # noqa: E402
from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.fileio import atomic_write_text  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402
from catgrasp_drake.grasping.descriptor import motion_functional_point  # noqa: E402
from catgrasp_drake.systems.shape_estimator import (  # noqa: E402
    functional_part_indices,
    part_seen_fraction,
    yaw_ambiguous,
)
from catgrasp_drake.transfer import EXTRA_VIEW_AZIMUTHS_DEG  # noqa: E402

OK_DEG = 10.0


def active(rows, rule, budget=3):
    """(right yaws, mean views) of taking the next view while ``rule(row, n)`` holds."""
    ok, views = 0, 0
    for r in rows:
        n = 1
        while n < budget and rule(r, n):
            n += 1
        ok += abs(r[f"yaw{n}"]) <= OK_DEG
        views += n
    return ok, views / len(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", default="mug")
    ap.add_argument("--placements", type=int, default=3)
    ap.add_argument("--seed", type=int, default=4242)
    ap.add_argument("--out")
    args = ap.parse_args(argv)
    c = args.category
    model = CategoryModel.load(default_model_path(c), category=c)
    part = functional_part_indices(model.space, motion_functional_point(model.template, model.grasp_anchor_H))
    rows = []
    for name, k, sc, views in committed_views(c, args.placements, args.seed, (0.0,) + EXTRA_VIEW_AZIMUTHS_DEG):
        row = {"instance": name, "placement": k}
        for n in (1, 2, 3):
            e = merged_fit(model.space, views, n, sc.table.pose.matrix())
            row[f"yaw{n}"] = round(yaw_error_deg(e.X_WO, sc.X_WO()), 1)
            row[f"amb{n}"] = bool(yaw_ambiguous(e))
            row[f"seen{n}"] = round(part_seen_fraction(e, part), 3)
        rows.append(row)
        print(json.dumps(row), flush=True)
    wrong = sorted(r["seen1"] for r in rows if abs(r["yaw1"]) > OK_DEG)
    right = sorted(r["seen1"] for r in rows if abs(r["yaw1"]) <= OK_DEG)
    print(f"\n{c}: {len(rows)} placements, {len(part)} part points; part seen, first view: wrong yaws {wrong}; "
          f"right yaws, lowest five {right[:5]}")
    rules = {"ambiguous": lambda r, n: r[f"amb{n}"]}
    for t in (0.3, 0.5, 0.6):
        rules[f"part seen < {t:g}"] = lambda r, n, t=t: r[f"seen{n}"] < t
        rules[f"ambiguous or part seen < {t:g}"] = lambda r, n, t=t: r[f"amb{n}"] or r[f"seen{n}"] < t
    rules["always"] = lambda r, n: True
    for label, rule in rules.items():
        ok, views = active(rows, rule)
        print(f"  {label:32s} {ok}/{len(rows)} yaws within {OK_DEG:g} deg, {views:.2f} views")
    if args.out:
        atomic_write_text(args.out, "".join(json.dumps(r) + "\n" for r in rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
