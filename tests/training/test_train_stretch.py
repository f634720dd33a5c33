"""``catgrasp train C --stretch FAMILY [--grasp FILE]``: training on the committed instances and their stretched
copies, from a canonical grasp file."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.cli import build_parser, main
from catgrasp_drake.data.dataset import load_mesh
from catgrasp_drake.data.meshes import read_mesh
from catgrasp_drake.data.stretch import STRESS_FAMILIES
from catgrasp_drake.errors import InputError
from catgrasp_drake.station.handwritten import GRASPS_DIR, load_handwritten_motion


def test_the_cli_offers_exactly_the_stress_families():
    action = next(a for a in build_parser()._subparsers._group_actions[0].choices["train"]._actions
                  if a.dest == "stretch")
    assert tuple(action.choices) == tuple(STRESS_FAMILIES)


def test_stretched_objects_are_written_once_per_family_and_unknown_families_refused(tmp_path):
    from catgrasp_drake.benchmark.runner import stretched_objects

    got = stretched_objects(tmp_path, "mug", ["mug_00", "mug_03"], ["deep", "small"])
    assert [n for n, _ in got] == ["mug_00_deep", "mug_03_deep", "mug_00_small", "mug_03_small"]
    mesh = read_mesh(got[0][1] / "mug_00_deep.obj")
    assert np.allclose(mesh.extents, load_mesh("mug", "mug_00").extents * STRESS_FAMILIES["deep"], atol=1e-5)
    stamp = (got[0][1] / "mug_00_deep.obj").stat().st_mtime_ns
    assert stretched_objects(tmp_path, "mug", ["mug_00"], ["deep"]) == got[:1]
    assert (got[0][1] / "mug_00_deep.obj").stat().st_mtime_ns == stamp  # not written again
    with pytest.raises(InputError, match=r"unknown \['wide'\]; known: small, large, thin, deep"):
        stretched_objects(tmp_path, "mug", ["mug_00"], ["wide"])


@pytest.mark.slow
def test_train_with_stretched_copies_and_a_grasp_file_trains_on_both_from_that_grasp(tmp_path, capsys):
    """One training run checks ``--stretch`` and ``--grasp`` (tests/training/test_train_grasp_file.py has the
    grasp file's errors): the stretched copies are trained on, and the grasp file is the template."""
    spec = yaml.safe_load((GRASPS_DIR / "mug_handwritten.yaml").read_text())
    spec["grasp"]["position"][0] += 0.002  # 2 mm along x: still a mug grasp, but not the committed one
    grasp = tmp_path / "mug_moved.yaml"
    grasp.write_text(yaml.safe_dump(spec))
    out = tmp_path / "mug.npz"
    code = main(["train", "mug", "--instances", "mug_00", "mug_03", "--stretch", "deep", "--samples", "1",
                 "--workers", "2", "--grasp", str(grasp), "--cache", str(tmp_path / "cache"),
                 "--stretch-dir", str(tmp_path / "stretched"), "--out", str(out)])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "and their 2 stretched copies (deep)" in text
    model = CategoryModel.load(out)
    assert model.instances == ("mug_00", "mug_03", "mug_00_deep", "mug_03_deep")
    assert (tmp_path / "stretched" / "mug" / "mug_03_deep" / "mug_03_deep.sdf").is_file()
    assert model.stats["per_instance"]["mug_03_deep"]["sampled"] == 1
    # the grasp file is the template, as written
    assert f"canonical grasp {grasp}" in text
    assert model.params["grasp_file"] == str(grasp)
    moved = load_handwritten_motion("mug", "mug_00", grasp).pose("grasp")
    as_written = load_handwritten_motion("mug", "mug_00").pose("grasp")
    assert np.allclose(model.template.pose("grasp"), moved, atol=1e-9)
    assert np.allclose(model.template.pose("grasp")[:3, 3] - as_written[:3, 3], [0.002, 0, 0], atol=1e-9)
