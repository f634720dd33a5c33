"""Hand postures per category."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.errors import InputError
from catgrasp_drake.robot import models


@pytest.mark.parametrize("category", ["drill", "spray_bottle", "mug", "cylinder"])
def test_postures_exist_and_are_within_limits(category):
    postures = models.load_hand_postures(category)
    limits = models.hand_joint_limits()
    for name in ("open", "preshape", "closed"):
        q = postures[name]
        assert q.shape == (9,) and q.dtype == float
        for joint, value in zip(models.HAND_ACTUATED_JOINTS, q):
            assert limits[joint][0] <= value <= limits[joint][1]
    # Closing never opens a finger and flexes the middle and ring fingers further than the preshape
    # (thumb and little finger may keep their preshape, e.g. a tucked thumb).
    flex = [models.HAND_ACTUATED_JOINTS.index(j)
            for j in ("svh_thumb_flexion", "svh_middle_proximal", "svh_ring", "svh_pinky")]
    assert np.all(postures["closed"][flex] >= postures["preshape"][flex])
    wrap = [models.HAND_ACTUATED_JOINTS.index(j) for j in ("svh_middle_proximal", "svh_middle_distal", "svh_ring")]
    assert np.all(postures["closed"][wrap] > postures["preshape"][wrap])


@pytest.mark.parametrize("category", ["drill", "spray_bottle"])
def test_trigger_categories_keep_the_index_finger_partly_open(category):
    postures = models.load_hand_postures(category)
    q = postures["closed"]
    idx = models.HAND_ACTUATED_JOINTS.index
    # the index's distal joint closes less than the middle finger's, so the distal link lands on the trigger
    assert q[idx("svh_index_distal")] < q[idx("svh_middle_distal")] - 0.3
    # thumb tucked across the palm throughout (an opposed thumb sweeps through the drill body)
    for name in ("open", "preshape", "closed"):
        assert postures[name][idx("svh_thumb_flexion")] > 0.9
        assert postures[name][idx("svh_thumb_opposition")] < 0.1


def test_unknown_category_lists_known_ones():
    with pytest.raises(InputError, match="drill.*mug.*spray_bottle") as info:
        models.load_hand_postures("teapot")
    assert "teapot" in str(info.value)
    with pytest.raises(InputError):
        models.load_hand_postures(None)  # type: ignore[arg-type]


def test_bad_posture_file_is_reported(tmp_path, monkeypatch):
    from catgrasp_drake.errors import ModelFileError

    bad = tmp_path / "postures.yaml"
    bad.write_text("version: 1\ncategories:\n  drill:\n    open: {svh_thumb_flexion: 0.0}\n")
    monkeypatch.setattr(models, "HAND_POSTURES_PATH", bad)
    models._postures_file.cache_clear()
    try:
        with pytest.raises(ModelFileError, match="missing"):
            models.load_hand_postures("drill")
        joints = ", ".join(f"{j}: 5.0" for j in models.HAND_ACTUATED_JOINTS)
        bad.write_text("version: 1\ncategories:\n  drill:\n    open: {" + joints + "}\n")
        models._postures_file.cache_clear()
        with pytest.raises(ModelFileError, match="outside the joint limits"):
            models.load_hand_postures("drill")
    finally:
        models._postures_file.cache_clear()
