"""The planner's own model of the world: its hand needs no hydroelastic pressure fields (issue 17)."""

from __future__ import annotations

import numpy as np

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.demo import default_model_path
from catgrasp_drake.planning.model import make_planning_model
from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
from catgrasp_drake.transfer import true_object_points_W


def _compliant_hand_geometries(pm) -> int:
    inspector = pm.scene_graph.model_inspector()
    n = 0
    for body in pm.plant.GetBodyIndices(pm.hand):
        for gid in pm.plant.GetCollisionGeometriesForBody(pm.plant.get_body(body)):
            props = inspector.GetProximityProperties(gid)
            n += props is not None and props.HasProperty("hydroelastic", "compliance_type")
    return n


def test_planning_without_the_hands_pressure_fields_makes_the_same_plan():
    """The planner asks only for signed distances: without the hand's compliant-hydroelastic declaration its
    plan is bit for bit the one made with it, on a drill placed off-centre with the object as an obstacle."""
    model = CategoryModel.load(default_model_path("drill"), category="drill")
    scenario = random_placement(with_instance(load_scenario("drill_default"), "drill_03"), 2)
    X = scenario.X_WO()
    motion = model.transfer(np.zeros(model.space.q), X[:3, :3], X[:3, 3], 1.0)
    obstacle = true_object_points_W(scenario)
    compliant = make_planning_model(scenario, obstacle, compliant_hand=True)
    default = make_planning_model(scenario, obstacle)
    assert _compliant_hand_geometries(compliant) > 10 and _compliant_hand_geometries(default) == 0
    a, b = compliant.plan(motion), default.plan(motion)
    assert a.ok and b.ok
    for field in ("times", "q_arm", "q_hand"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert a.knot_names == b.knot_names and a.object_shift == b.object_shift
