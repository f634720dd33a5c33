"""Scenario YAML loading and validation."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core.visibility import look_at_matrix
from catgrasp_drake.errors import InputError
from catgrasp_drake.station.scenario import (
    DEFAULT_SCENARIO_FILE,
    Scenario,
    load_scenario,
    load_scenarios,
    scenario_from_dict,
)

REQUIRED = ("drill_default", "spray_bottle_default", "mug_default", "cylinder_test")


def test_named_scenarios_exist():
    scenarios = load_scenarios()
    for name in REQUIRED:
        assert name in scenarios
        assert isinstance(scenarios[name], Scenario)
        assert scenarios[name].name == name
    assert scenarios["cylinder_test"].object.primitive is not None
    assert scenarios["cylinder_test"].object.primitive.radius == pytest.approx(0.02)
    assert scenarios["drill_default"].plant.time_step == pytest.approx(5e-3)
    assert scenarios["drill_default"].plant.discrete_contact_approximation == "sap"


def test_load_one_matches_all():
    assert load_scenario("mug_default") == load_scenarios()["mug_default"]


def test_unknown_scenario_named():
    with pytest.raises(InputError, match="nope_scenario"):
        load_scenario("nope_scenario")


@pytest.mark.parametrize("entry, fragment", [
    ({"object": {"category": "drill", "instance": "drill_00", "colour": 1}}, "colour"),
    ({"objekt": {}}, "objekt"),
    ({"object": {"category": "banana"}}, "banana"),
    ({"object": {"category": "drill", "instance": "drill_99"}}, "drill_99"),
    ({"plant": {"time_step": -1}}, "time_step"),
    ({"plant": {"contact_model": "magic"}}, "contact_model"),
    ({"cameras": [{"name": "c", "fov_y_deg": 200}]}, "fov_y_deg"),
    ({"cameras": [{"name": "c", "depth_range": [2.0, 1.0]}]}, "depth_range"),
    ({"cameras": [{"name": "c", "width": 0}]}, "width"),
    ({"table": {"size": [1, 1]}}, "size"),
    ({"arm_q_home": [0, 0, 0]}, "arm_q_home"),
    ({"meshcat": "yes"}, "meshcat"),
    ({"object_cloud": {"seed": -3}}, "seed"),
])
def test_bad_fields_are_named(entry, fragment):
    with pytest.raises(InputError, match=fragment):
        scenario_from_dict("bad", entry)


def test_defaults_and_object_pose():
    s = scenario_from_dict("x", {"object": {"category": "drill", "instance": "drill_01",
                                            "xyz": [0.1, 0.2, 0.0], "yaw_deg": 90}})
    X = s.X_WO()
    np.testing.assert_allclose(X[:3, 3], np.array(s.table.pose.xyz) + [0.1, 0.2, 0.0])
    np.testing.assert_allclose(X[:3, 0], [0, 1, 0], atol=1e-12)  # yaw 90 deg: x_O along y_W


def test_look_at_camera_axes():
    X = look_at_matrix([1.0, 0.0, 0.5], [0.0, 0.0, 0.5])
    np.testing.assert_allclose(X[:3, 2], [-1, 0, 0], atol=1e-12)  # z forward
    np.testing.assert_allclose(X[:3, 1], [0, 0, -1], atol=1e-12)  # y down
    assert np.linalg.det(X[:3, :3]) == pytest.approx(1.0)


def test_invalid_yaml_file(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text("a: [1, 2\n")
    with pytest.raises(InputError):
        load_scenarios(p)
    p.write_text("[]\n")
    with pytest.raises(InputError):
        load_scenarios(p)


def test_default_file_location():
    assert DEFAULT_SCENARIO_FILE.name == "station.scenarios.yaml"
    assert DEFAULT_SCENARIO_FILE.is_file()
