"""The plant's sensitivity and speed knobs reach the geometry they name (and only it)."""

from __future__ import annotations

import dataclasses

from pydrake.systems.framework import DiagramBuilder

from catgrasp_drake.station.builder import add_station
from catgrasp_drake.station.scenario import load_scenario, scenario_from_dict


def _hints(h, instance):
    inspector = h.scene_graph.model_inspector()
    out = set()
    for b in h.plant.GetBodyIndices(instance):
        for g in h.plant.GetCollisionGeometriesForBody(h.plant.get_body(b)):
            props = inspector.GetProximityProperties(g)
            if props.HasProperty("hydroelastic", "resolution_hint"):
                out.add(round(props.GetProperty("hydroelastic", "resolution_hint"), 6))
    return out


def test_hand_resolution_hint_replaces_the_hand_capsules_hint_only():
    base = load_scenario("drill_default")
    h0 = add_station(DiagramBuilder(), base)
    assert _hints(h0, h0.hand) == {0.006}
    coarse = base.replace(plant=dataclasses.replace(base.plant, hand_resolution_hint=0.01))
    h1 = add_station(DiagramBuilder(), coarse)
    assert _hints(h1, h1.hand) == {0.01}
    assert _hints(h1, h1.table) == _hints(h0, h0.table)  # the table keeps its own


def test_knobs_parse_from_yaml():
    s = scenario_from_dict("x", {"plant": {"hand_resolution_hint": 0.012, "object_friction": 0.5,
                                           "hand_effort_scale": 0.6}})
    assert (s.plant.hand_resolution_hint, s.plant.object_friction, s.plant.hand_effort_scale) == (0.012, 0.5, 0.6)


def test_object_mass_scale_weighs_the_object_in_the_simulation_context():
    import numpy as np
    import pytest

    from catgrasp_drake.station.builder import apply_context_knobs

    base = load_scenario("drill_default")
    heavy = base.replace(plant=dataclasses.replace(base.plant, object_mass_scale=1.3))
    builder = DiagramBuilder()
    h = add_station(builder, heavy)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_ctx = h.plant.GetMyContextFromRoot(context)
    m0 = h.object_body.default_mass()
    G0 = h.object_body.CalcSpatialInertiaInBodyFrame(plant_ctx).CopyToFullMatrix6()
    apply_context_knobs(h, context)
    assert h.object_body.get_mass(plant_ctx) == pytest.approx(1.3 * m0)
    G1 = h.object_body.CalcSpatialInertiaInBodyFrame(plant_ctx).CopyToFullMatrix6()
    np.testing.assert_allclose(G1, 1.3 * G0, rtol=1e-12, atol=1e-15)  # the same shape of inertia, 30 % more
    assert scenario_from_dict("x", {"plant": {"object_mass_scale": 0.7}}).plant.object_mass_scale == 0.7


def test_sap_near_rigid_threshold_reaches_the_plant_and_bad_values_are_refused():
    import pytest

    from catgrasp_drake.errors import InputError

    base = load_scenario("drill_default")
    assert add_station(DiagramBuilder(), base).plant.get_sap_near_rigid_threshold() == 1.0  # Drake's default
    off = scenario_from_dict("x", {"plant": {"sap_near_rigid_threshold": 0.0}})
    assert off.plant.sap_near_rigid_threshold == 0.0
    h = add_station(DiagramBuilder(), base.replace(plant=off.plant))
    assert h.plant.get_sap_near_rigid_threshold() == 0.0
    with pytest.raises(InputError, match="sap_near_rigid_threshold"):
        scenario_from_dict("x", {"plant": {"sap_near_rigid_threshold": -1.0}})
