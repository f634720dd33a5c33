"""An object from a folder of its own (e.g. a prepared YCB scan) instead of the embedded data set."""

from __future__ import annotations

import shutil

import pytest

from catgrasp_drake.data.dataset import instance_dir, load_annotations
from catgrasp_drake.errors import InputError
from catgrasp_drake.station.builder import make_station
from catgrasp_drake.station.scenario import load_scenario, scenario_from_dict, with_instance
from catgrasp_drake.trial import judge_spec, trial_diagram


def test_station_loads_an_object_from_model_dir(tmp_path):
    folder = tmp_path / "my_drill"
    shutil.copytree(instance_dir("drill", "drill_03"), folder)
    scenario = with_instance(load_scenario("drill_default"), "drill_03", model_dir=folder)
    assert scenario.object.sdf_file() == str(folder / "drill_03.sdf")
    assert scenario.object.annotations() == load_annotations("drill", "drill_03")
    station = make_station(scenario)
    context = station.CreateDefaultContext()
    cloud = station.GetOutputPort("camera0.object_cloud_W").Eval(context)
    assert cloud.size() > 300
    spec = judge_spec(trial_diagram(scenario).station, 0.12)
    assert spec.regions["trigger"] == load_annotations("drill", "drill_03")["regions"]["trigger"]


def test_model_dir_in_yaml_is_checked(tmp_path):
    with pytest.raises(InputError, match="no drill_03.sdf"):
        scenario_from_dict("x", {"object": {"category": "drill", "instance": "drill_03", "model_dir": str(tmp_path)}})
