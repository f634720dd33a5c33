"""Test helper: how far an object tips over when left alone on the station's table."""

from __future__ import annotations

import numpy as np


def tilt_after(category: str, name: str, directory, seconds: float) -> float:
    """The object's tilt from vertical (deg) after ``seconds`` of simulation, the robot at home and nothing
    touching it: ``name`` of ``category``, from ``directory`` (None: the committed instance)."""
    from pydrake.systems.analysis import Simulator

    from catgrasp_drake.station.scenario import load_scenario, with_instance
    from catgrasp_drake.trial import trial_diagram

    scenario = with_instance(load_scenario(f"{category}_default"), name, category=category,
                             model_dir=None if directory is None else str(directory))
    td = trial_diagram(scenario)
    context = td.diagram.CreateDefaultContext()
    Simulator(td.diagram, context).AdvanceTo(seconds)
    h = td.station
    X = h.plant.EvalBodyPoseInWorld(h.plant.GetMyContextFromRoot(context), h.object_body).GetAsMatrix4()
    return float(np.degrees(np.arccos(np.clip(X[2, 2], -1.0, 1.0))))
