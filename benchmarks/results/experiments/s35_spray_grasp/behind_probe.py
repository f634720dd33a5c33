"""Session 35 probe: can the SVH hand hold a spray bottle from BEHIND its neck, the index wrapping the trigger's front?

    python benchmarks/results/experiments/s35_spray_grasp/behind_probe.py [--grasp behind_neck.yaml]

COMMITTED bottles only, no simulation. The grasp in ``behind_neck.yaml`` puts the palm against the back of the
neck (approach along the nozzle, +y), the fingers pointing across (+x) with the index at the trigger's height,
the thumb opposed on the other side: the way a person holds a spray bottle, and the way around a trigger gap
wider than the index (the category's grasp comes from the side and its fingertip slides into such a gap).
``planning.fit.closing_contacts`` steps the hand from preshape to closed against each committed bottle and
prints, per bottle, where each finger first meets it. Printed at the end: on how many bottles the index and the
middle finger meet the bottle at all, and the index on its trigger.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.data.dataset import list_instances, load_annotations  # noqa: E402
from catgrasp_drake.planning.fit import closing_contacts, hand_fit  # noqa: E402
from catgrasp_drake.station.handwritten import motion_from_spec  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402

HERE = Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grasp", type=Path, default=HERE / "behind_neck.yaml")
    args = ap.parse_args(argv)
    spec = yaml.safe_load(args.grasp.read_text())
    names = list_instances("spray_bottle")
    index_touches = middle_touches = index_on_trigger = 0
    for name in names:
        annotations = load_annotations("spray_bottle", name)
        scenario = with_instance(load_scenario("spray_bottle_default"), name, category="spray_bottle")
        motion = motion_from_spec(spec, annotations)
        contacts = {c.finger: c for c in closing_contacts(scenario, motion, region=annotations["regions"]["trigger"])}
        index_touches += contacts["index"].fraction is not None
        middle_touches += contacts["middle"].fraction is not None
        index_on_trigger += bool(contacts["index"].in_region)
        print(f"{name}: preshape {hand_fit(scenario, motion).summary()}")
        for c in sorted(contacts.values(), key=lambda c: (c.fraction is None, c.fraction or 0.0)):
            print(f"    {c.summary()}")
    print(f"{len(names)} committed bottles: the index meets the bottle on {index_touches}, its trigger on "
          f"{index_on_trigger}; the middle finger meets it on {middle_touches}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
