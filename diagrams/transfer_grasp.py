"""Grasp transfer to a novel instance, as a plain Drake diagram script (copy it, edit it).

    python diagrams/transfer_grasp.py [--category drill] [--instance drill_12] [--seed 0]
                                      [--view single|full] [--html out/transfer_grasp.html]
                                      [--graphviz docs/transfer_diagram.png]

What it does, step by step (the same builder serves ``catgrasp demo`` and the tests):

1. load the trained category model (shape space + grasp regressor);
2. describe the scene: the category's default scenario from
   ``models/station.scenarios.yaml`` with the object replaced by the novel
   instance and moved to a seeded random yaw and position;
3. ``make_transfer_diagram``: station (plant, scene graph, UR10 + SVH hand,
   table, object, RgbdSensor) + object cloud + LatentShapeEstimator +
   GraspRegressor + MotionPlanner, wired into one Diagram;
4. simulate it with a plain ``Simulator``: the estimator's initialization
   event fits the shape to the camera's cloud, the regressor and the planner
   follow through Drake's caches, the PD-gained actuators execute;
5. read the results off the systems' output ports and judge the grasp.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main(argv=None) -> int:
    from pydrake.systems.analysis import Simulator

    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.core.fileio import atomic_write_bytes
    from catgrasp_drake.demo import default_model_path, pick_novel_instance
    from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
    from catgrasp_drake.transfer import make_transfer_diagram
    from catgrasp_drake.trial import judge_spec, simulate_and_judge
    from catgrasp_drake.viz.meshcat_tools import start_meshcat

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", default="drill")
    ap.add_argument("--instance", default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--view", choices=("single", "full"), default="single")
    ap.add_argument("--html", default="out/transfer_grasp.html", help="Meshcat recording ('' for no Meshcat)")
    ap.add_argument("--graphviz", default=None, help="also write the diagram's systems and ports as PNG/SVG")
    args = ap.parse_args(argv)

    # 1. the category model
    model = CategoryModel.load(default_model_path(args.category), category=args.category)
    # 2. the scene
    instance = pick_novel_instance(model, args.instance)
    scenario = random_placement(with_instance(load_scenario(f"{args.category}_default"), instance), args.seed)
    # 3. the diagram
    meshcat = start_meshcat() if args.html else None
    td = make_transfer_diagram(scenario, model, meshcat, view=args.view)
    if args.graphviz:
        import pydot

        graph = pydot.graph_from_dot_data(td.diagram.GetGraphvizString(max_depth=1))[0]
        data = graph.create_svg() if args.graphviz.endswith(".svg") else graph.create_png()
        atomic_write_bytes(args.graphviz, data)
        print(f"wrote {args.graphviz}")
    # 4. simulate: Initialize() runs the estimator's initialization event
    simulator = Simulator(td.diagram)
    context = simulator.get_mutable_context()
    simulator.Initialize()
    estimate = td.estimator.GetOutputPort("estimate").Eval(td.estimator.GetMyContextFromRoot(context))
    plan = td.generator.GetOutputPort("plan").Eval(td.generator.GetMyContextFromRoot(context))
    print(f"{instance}: {len(estimate.observed_W)} observed points, scale {estimate.scale:.3f}, "
          f"confidence {estimate.confidence:.2f}, plan {plan.status}")
    if not plan.ok:
        return 1
    spec = judge_spec(td.station, lift_height=0.12)
    # the simulator was initialized above; simulate_and_judge re-initializes on the same context (same state)
    verdict, _, _, sim_time = simulate_and_judge(td.diagram, context, td.station, plan.timeline, spec,
                                                 meshcat=meshcat, record_html=args.html or None)
    # 5. the outcome
    print(f"simulated {sim_time:.1f} s: grasp {verdict.grasp_success}, functional {verdict.functional_success}"
          f"{'' if verdict.functional_success else f' ({verdict.failure_reason}: {verdict.detail})'}")
    if args.html:
        print(f"wrote {args.html}")
    return 0 if verdict.functional_success else 1


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
