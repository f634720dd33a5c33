"""Execute the hand-written functional grasps on the default drill and spray bottle.

    python diagrams/execute_grasp.py [--out out/] [--scenarios drill_default spray_bottle_default]

For each scenario: load the category's hand-written grasp
(``models/grasps/<category>_handwritten.yaml``, fitted to the instance's
annotated trigger), run one grasp trial in the hydroelastic station, log the
outcome, and write the Meshcat recording as self-contained HTML
(``<out>/<scenario>.html``) plus a JSON summary (``<out>/execute_grasp.json``).
"""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

from catgrasp_drake.core.fileio import atomic_write_text
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.station.scenario import load_scenario
from catgrasp_drake.trial import run_grasp_trial
from catgrasp_drake.viz.meshcat_tools import start_meshcat

log = logging.getLogger("execute_grasp")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out"), help="output directory (default: out/)")
    parser.add_argument("--scenarios", nargs="+", default=["drill_default", "spray_bottle_default"])
    parser.add_argument("--no-html", action="store_true", help="skip Meshcat and the HTML recordings")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    args.out.mkdir(parents=True, exist_ok=True)
    summary = {}
    for name in args.scenarios:
        scenario = load_scenario(name)
        motion = load_handwritten_motion(scenario.object.category, scenario.object.instance)
        meshcat = None if args.no_html else start_meshcat()
        html = None if meshcat is None else args.out / f"{name}.html"
        result = run_grasp_trial(scenario, motion, meshcat=meshcat, record_html=html)
        summary[name] = result.to_dict()
        log.info("%-22s grasp=%s functional=%s reason=%s (%s) rise=%.3f m tilt=%.1f deg sim=%.2f s wall=%.2f s",
                 name, result.grasp_success, result.functional_success, result.failure_reason, result.detail,
                 result.object_rise_m, result.object_tilt_deg, result.sim_time_s, result.wall_time_s)
        log.info("    hand links on the object: %s", ", ".join(result.hand_links_on_object) or "none")
        if html is not None:
            log.info("    recording: %s", html)
    atomic_write_text(args.out / "execute_grasp.json", json.dumps(summary, indent=2, default=list) + "\n")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
