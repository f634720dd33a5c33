"""Does the category's hand-written grasp fit each object? The preshaped hand against its true mesh, no simulation.

    python diagrams/hand_fit.py [--categories drill spray_bottle mug] [--objects DIR ...] [--posture preshape]
                                [--closing] [--grasp FILE] [--json FILE]

For each committed instance of ``--categories`` and each imported object
(``catgrasp import-object``, the stress split's stretched copies under
``out/benchmark/data/stress/<category>/``, the YCB scans), the category's
hand-written grasp is anchored on the object's own annotated region
(``station.handwritten.handwritten_trial``, as ``catgrasp film`` does) and its hand, in ``--posture``, is
checked against the object's mesh (``catgrasp_drake.planning.fit.hand_fit``:
the signed-distance grid of the planner's object clearance). Printed per object:
the depth of the hand's deepest point inside the object (mm; negative = clear),
the three deepest links, and what the planner will do with it: nothing (within
its 4 mm tolerance), move the grasp out by so much (and the index finger with it,
off the trigger), or refuse it (a trial's ``collision_before_closing``). Half a
second to a second per object; a trial takes 5-10 s.

``--closing`` also prints the order in which the fingers, thumb and palm meet the object as the hand closes
(``planning.fit.closing_contacts``: the posture stepped from preshape to closed with the hand and object still):
how far into the closing each arrives, with which link, and whether on the category's functional region (the
trigger or handle), with the hand where the planner's object clearance puts it -- e.g. the index on the
trigger's side, or the thumb after the fingers have pushed. About 2 s more per object.

``--grasp FILE`` checks another grasp file of the category in place of its hand-written grasp (e.g. an
earlier or a searched one, as ``catgrasp film --grasp``), anchored on each object's region the same way.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.core.fileio import atomic_write_text  # noqa: E402
from catgrasp_drake.data.dataset import list_instances  # noqa: E402
from catgrasp_drake.grasping.constraints import load_constraint  # noqa: E402
from catgrasp_drake.planning.fit import closing_contacts, hand_fit  # noqa: E402
from catgrasp_drake.station.handwritten import handwritten_trial, moved_about  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--categories", nargs="*", default=None,
                    help="committed instances of these categories (default: all three unless --objects)")
    ap.add_argument("--objects", type=Path, nargs="*", default=[], help="imported objects' directories")
    ap.add_argument("--posture", default="preshape", help="the hand posture checked (open, preshape, closed)")
    ap.add_argument("--closing", action="store_true",
                    help="also the order in which fingers, thumb and palm meet the object as the hand closes")
    ap.add_argument("--grasp", type=Path, default=None,
                    help="a grasp file to check instead of the category's hand-written grasp (as catgrasp film)")
    ap.add_argument("--json", type=Path, default=None, help="also write the rows here")
    args = ap.parse_args(argv)
    categories = args.categories if args.categories is not None else ([] if args.objects else
                                                                      ["drill", "spray_bottle", "mug"])
    items = [(c, name, None) for c in categories for name in list_instances(c)]
    items += [(None, None, d) for d in args.objects]  # an imported object: its directory says the rest
    print(f"{'object':26s} {'depth (mm)':>10s}  {'deepest links (mm)':48s} planner")
    rows = []
    for category, name, directory in items:
        scenario, motion = handwritten_trial(category, name, object_dir=directory, grasp_file=args.grasp)
        category, name = scenario.object.category, scenario.object.instance
        fit = hand_fit(scenario, motion, posture=args.posture)
        links = ", ".join(f"{k.removeprefix('svh_')} {1000 * d:.1f}" for k, d in fit.deepest_links())
        shift_mm = 1000 * float(np.linalg.norm(fit.shift_m))
        action = "refused" if not fit.plannable else (f"moved {shift_mm:.1f} mm" if shift_mm > 0 else "as written")
        print(f"{name:26s} {1000 * fit.depth_m:10.1f}  {links:48s} {action}")
        rows.append({"category": category, "object": name, "depth_mm": round(1000 * fit.depth_m, 2),
                     "link_depths_mm": {k: round(1000 * d, 2) for k, d in fit.link_depths_m.items()},
                     "shift_mm": round(shift_mm, 2), "plannable": fit.plannable})
        if args.closing:
            region = scenario.object.annotations().get("regions", {}).get(load_constraint(category).region)
            if fit.plannable and np.any(fit.shift_m):  # where the planner will have moved the hand
                motion = moved_about(motion, np.zeros(3), fit.shift_m)
            contacts = closing_contacts(scenario, motion, region=region)
            for c in contacts:
                print(f"    {c.summary()}")
            rows[-1]["closing"] = [{"finger": c.finger, "fraction": c.fraction, "link": c.link,
                                    "point_mm": None if c.point_O is None else [round(1000 * v, 1) for v in c.point_O],
                                    "in_region": c.in_region} for c in contacts]
    refused = sum(not r["plannable"] for r in rows)
    moved = sum(r["plannable"] and r["shift_mm"] > 0 for r in rows)
    print(f"{len(rows)} objects: {len(rows) - refused - moved} as written, {moved} moved by the planner, "
          f"{refused} refused")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(args.json, json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
