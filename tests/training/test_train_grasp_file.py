"""``catgrasp train C --grasp FILE``: training from a canonical grasp other than the hand-written one."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.cli import main
from catgrasp_drake.station.handwritten import GRASPS_DIR, load_handwritten_motion

EXAMPLE_FOLDER = GRASPS_DIR.parents[0] / "examples" / "tankards"


@pytest.mark.slow
def test_train_from_a_grasp_file_keeps_it_as_the_template(tmp_path, capsys):
    spec = yaml.safe_load((GRASPS_DIR / "mug_handwritten.yaml").read_text())
    spec["grasp"]["position"][0] += 0.002  # 2 mm along x: still a mug grasp, but not the committed one
    grasp = tmp_path / "mug_moved.yaml"
    grasp.write_text(yaml.safe_dump(spec))
    out = tmp_path / "mug.npz"
    code = main(["train", "mug", "--instances", "mug_00", "mug_03", "--samples", "1", "--workers", "2",
                 "--grasp", str(grasp), "--cache", str(tmp_path / "cache"), "--out", str(out)])
    text = capsys.readouterr().out
    assert code == 0, text
    assert f"canonical grasp {grasp}" in text
    model = CategoryModel.load(out)
    assert model.params["grasp_file"] == str(grasp)
    moved = load_handwritten_motion("mug", "mug_00", grasp).pose("grasp")
    as_written = load_handwritten_motion("mug", "mug_00").pose("grasp")
    assert np.allclose(model.template.pose("grasp"), moved, atol=1e-9)
    assert np.allclose(model.template.pose("grasp")[:3, 3] - as_written[:3, 3], [0.002, 0, 0], atol=1e-9)


def test_grasp_file_errors_are_one_line(tmp_path, capsys):
    assert main(["train", "mug", "--grasp", str(tmp_path / "none.yaml"), "--out", str(tmp_path / "m.npz")]) == 2
    assert "--grasp: no such grasp file" in capsys.readouterr().err
    assert main(["train", "--objects", str(EXAMPLE_FOLDER), "--grasp", str(GRASPS_DIR / "mug_handwritten.yaml")]) == 2
    assert "--grasp: a category folder trains on its own meshes, canonical instance and grasp" in \
        capsys.readouterr().err
    # a grasp file of another category is refused before any training
    assert main(["train", "drill", "--grasp", str(GRASPS_DIR / "mug_handwritten.yaml"), "--out",
                 str(tmp_path / "m.npz")]) == 2
    assert "grasp for 'mug', not 'drill'" in capsys.readouterr().err
    assert not (tmp_path / "m.npz").exists()
