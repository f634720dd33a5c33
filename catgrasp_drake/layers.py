"""The package's layer order: which part may import which (``tests/core/test_layers.py`` enforces it).

A *unit* is a subpackage or a top-level module of ``catgrasp_drake``; a
module may import modules of its own unit and of units in LOWER layers,
never of a unit in its own layer or above -- at module top or inside a
function alike. Units in one layer are independent of each other.

=====  ==========================  =====================================================================
layer  units                       what they hold
=====  ==========================  =====================================================================
0      errors, layers              the project's exceptions; this table
1      core, (the package root)    numerics on numpy + scipy only: CPD, shape space, inference, rotations,
                                   regression, visibility, threads, file I/O (the root re-exports errors)
2      data, grasping, robot,      category generators, meshes, clouds, data set I/O, YCB import;
       runner                      grasp motions, descriptors, sampling, constraints; the robot models
                                   and their tables; the cached, parallel task runner
3      category_model, perception  the trained category model (shape space + grasp regressor); depth
                                   image -> object cloud (pure helpers and their LeafSystems)
4      prediction, viz             every prediction method on a category model; drawing (Meshcat,
                                   rendering, contact sheets, charts): data in, pictures out -- no station
5      station                     scenario, station builder (plant, cameras), judge, hand-written grasps
6      planning                    plan records, planning scene and its queries, the grasp planner,
                                   the planning model
7      systems                     LeafSystems of the transfer: estimator, predictors, plan playback and
                                   the motion planner (ports and calls only)
8      trial, baselines            one simulated, judged grasp trial; the baselines as plain functions
9      transfer, training,         the transfer diagram; training a category model (trials as tasks);
       grasp_search                the robustness search of a category's grasp
10     demo, evaluation, film      the demo; the paper's evaluation protocol; a film of one trial
                                   (frames at the phases of the motion)
11     benchmark                   the held-out benchmark and its report
12     cli                         the ``catgrasp`` command line
=====  ==========================  =====================================================================

Offline tools (``tools/``), ``diagrams/``, ``benchmarks/`` and the tests sit
above all of these and may import anything.
"""

from __future__ import annotations

PACKAGE = "catgrasp_drake"
#: Unit name of the package's own ``__init__.py``.
ROOT = "__init__"

#: (layer name, units), lowest layer first.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("errors", ("errors", "layers")),
    ("core", ("core", ROOT)),
    ("foundations", ("data", "grasping", "robot", "runner")),
    ("models", ("category_model", "perception")),
    ("prediction and drawing", ("prediction", "viz")),
    ("station", ("station",)),
    ("planning", ("planning",)),
    ("systems", ("systems",)),
    ("trial", ("trial", "baselines")),
    ("jobs", ("transfer", "training", "grasp_search")),
    ("protocols", ("demo", "evaluation", "film")),
    ("benchmark", ("benchmark",)),
    ("cli", ("cli",)),
)

#: unit -> layer index.
LAYER_OF: dict[str, int] = {unit: i for i, (_, units) in enumerate(LAYERS) for unit in units}


def unit_of(module: str) -> str | None:
    """The unit of a dotted module name inside the package (``catgrasp_drake.planning.scene`` -> ``planning``).

    ``catgrasp_drake`` itself is :data:`ROOT`; a name outside the package is None.
    """
    parts = module.split(".")
    if parts[0] != PACKAGE:
        return None
    return parts[1] if len(parts) > 1 else ROOT
