"""``catgrasp train C --grasp FILE``: its errors (training from a grasp file: test_train_stretch.py)."""

from __future__ import annotations

from catgrasp_drake.cli import main
from catgrasp_drake.station.handwritten import GRASPS_DIR

EXAMPLE_FOLDER = GRASPS_DIR.parents[0] / "examples" / "tankards"


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
