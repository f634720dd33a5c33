"""Scenario YAML loading and validation."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

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


# ----------------------------------------------------------------------------- Drake's loader, one-line errors
@pytest.mark.parametrize("entry, where", [
    ({"object": {"category": "drill", "colour": 1}}, "'x'.object: unknown field 'colour'"),
    ({"objekt": {}}, "'x': unknown field 'objekt'"),
    ({"cameras": [{}, {"look_at": {"eye": [1, 0, 0], "tagret": [0, 0, 0]}}]}, "'x'.cameras[1].look_at: unknown field"),
    ({"plant": {"time_step": "fast"}}, "'x'.plant.time_step:"),
    ({"cameras": [{"width": 1.5}]}, "'x'.cameras[0].width:"),
    ({"cameras": [{"name": 7}]}, "'x'.cameras[0].name:"),
    ({"meshcat": 1}, "'x'.meshcat:"),
    ({"object": 5}, "'x'.object: expected a mapping, got int"),
    ({"cameras": [5]}, "'x'.cameras[0]: expected a mapping, got int"),
    ({"cameras": 5}, "'x'.cameras: expected a list, got int"),
    ({"object": {"xyz": "abc"}}, "'x'.object.xyz: expected a list, got str"),
    ({"object": {"xyz": [0, 0, float("nan")]}}, "'x'.object.xyz: expected finite numbers"),
    ({"table": {"xyz": [0, 0, 0, 1]}}, "'x'.table.xyz: expected 3 numbers"),
    ({"object": {"primitive": {"radius": 0}}}, "'x'.object.primitive.radius: expected a positive number"),
    ({"plant": {"object_friction": float("inf")}}, "'x'.plant.object_friction: expected a finite number"),
    ({"object_cloud": {"edge_dropout": 1.5}}, "'x'.object_cloud.edge_dropout: expected a probability"),
    ([1, 2], "'x': expected a mapping, got list"),
])
def test_loader_errors_are_one_line_and_name_the_field(entry, where):
    from tests.reliability.harness import check_message

    with pytest.raises(InputError) as e:
        scenario_from_dict("x", entry)
    check_message(e.value)
    assert where in str(e.value)


def test_file_errors_name_the_file_and_are_one_line(tmp_path):
    from tests.reliability.harness import check_message

    p = tmp_path / "mine.scenarios.yaml"
    p.write_text("ok: {}\nbad:\n  plant: {time_step: 0.001, contact_modle: point}\n")
    for call in (lambda: load_scenarios(p), lambda: load_scenario("bad", p)):
        with pytest.raises(InputError, match=r"^mine\.scenarios\.yaml: scenario 'bad'\.plant: unknown field "
                                             r"'contact_modle'") as e:
            call()
        check_message(e.value)
    assert load_scenario("ok", p) == Scenario(name="ok")
    with pytest.raises(InputError, match="unknown scenario 'nope' in mine.scenarios.yaml; known: ok, bad"):
        load_scenario("nope", p)
    p.write_text("a: [1, 2\n")
    with pytest.raises(InputError) as e:
        load_scenarios(p)
    check_message(e.value)
    assert str(p) in str(e.value)
    from catgrasp_drake.errors import ModelFileError
    with pytest.raises(ModelFileError, match="cannot read scenario file"):
        load_scenario("ok", tmp_path / "missing.yaml")


def test_yaml_entry_types_and_defaults_as_the_records():
    """What Drake's loader fills reaches the frozen records as tuples of floats; null and absent take defaults."""
    s = scenario_from_dict("x", {"object": {"xyz": [1, 2, 3], "yaw_deg": 5}, "arm_q_home": [0, 1, 2, 3, 4, 5],
                                 "plant": None, "table": {"size": [1, 1, 1]}, "cameras": None})
    assert s.object.xyz == (1.0, 2.0, 3.0) and all(type(v) is float for v in s.object.xyz)
    assert type(s.object.yaw_deg) is float and isinstance(s.arm_q_home, tuple)
    assert s.table.size == (1.0, 1.0, 1.0) and s.table.pose == Scenario().table.pose
    assert s.plant == Scenario().plant and s.cameras == Scenario().cameras
    assert scenario_from_dict("unnamed", None) == scenario_from_dict("unnamed", {}) == Scenario()
    assert hash(s) == hash(scenario_from_dict("x", {"object": {"xyz": [1.0, 2.0, 3.0], "yaw_deg": 5.0},
                                                    "arm_q_home": [0, 1, 2, 3, 4, 5], "table": {"size": [1] * 3}}))
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.object.xyz = (0.0, 0.0, 0.0)
    cam = scenario_from_dict("x", {"cameras": [{"name": "top", "X_WC": {"xyz": [0, 0, 1]}}]}).cameras[0]
    assert (cam.X_WC.xyz, cam.look_at_eye, cam.look_at_target) == ((0.0, 0.0, 1.0), None, None)
    prim = scenario_from_dict("x", {"object": {"primitive": {"shape": "box"}}}).object
    assert (prim.category, prim.instance, prim.primitive.size) == (None, None, (0.05, 0.05, 0.15))
    assert scenario_from_dict("x", {"object": {"category": "mug"}}).object.instance == "mug_00"


# ----------------------------------------------------------------------------- fuzz
_JUNK = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), st.floats(allow_nan=True),
                  st.text(max_size=8), st.lists(st.floats(-5, 5), max_size=7),
                  st.dictionaries(st.text(max_size=6), st.integers(), max_size=3))


def _paths(d, prefix=()):
    """Every (path, value) in a nested YAML entry (mappings and lists)."""
    items = d.items() if isinstance(d, dict) else enumerate(d) if isinstance(d, list) else ()
    for k, v in items:
        yield prefix + (k,), v
        yield from _paths(v, prefix + (k,))


@st.composite
def _mutated_entries(draw):
    """A named scenario's raw YAML entry with one field replaced, removed or added."""
    raw = yaml.safe_load(DEFAULT_SCENARIO_FILE.read_text())
    entry = copy.deepcopy(raw[draw(st.sampled_from(sorted(raw)))])
    path, _ = draw(st.sampled_from(list(_paths(entry))))
    parent = entry
    for k in path[:-1]:
        parent = parent[k]
    how = draw(st.sampled_from(["replace", "replace", "remove", "add"]))
    if how == "replace":
        parent[path[-1]] = draw(_JUNK)
    elif how == "remove":
        del parent[path[-1]]
    elif isinstance(parent, dict):
        parent[draw(st.text(min_size=1, max_size=8))] = draw(_JUNK)
    return entry


@settings(max_examples=60, deadline=None, derandomize=True, database=None)
@given(_mutated_entries())
def test_fuzz_mutated_entries_load_or_fail_in_one_line(entry):
    from tests.reliability.harness import attempt

    def check(s):
        assert isinstance(s, Scenario)
        hash(s)
        assert s == scenario_from_dict("fuzz", entry)

    attempt("scenario_from_dict", "mutated", scenario_from_dict, "fuzz", entry, check=check, words=("scenario",))


@settings(max_examples=40, deadline=None, derandomize=True, database=None)
@given(st.text(max_size=80))
def test_fuzz_scenario_file_text(tmp_path_factory, text):
    from tests.reliability.harness import attempt

    p = tmp_path_factory.mktemp("fuzz") / "s.yaml"
    p.write_text(text)
    attempt("load_scenarios", "text", load_scenarios, p)
