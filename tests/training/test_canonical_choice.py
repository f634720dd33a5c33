"""Choosing the canonical instance by how well its functional region warps onto the others."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.errors import InputError
from catgrasp_drake.training import _region_centre, choose_canonical_by_region

SHAPE_KWARGS = {"beta": 0.10, "lam": 2.0, "variance": 0.95, "max_iter": 60}


def _bottle(rng, height):
    """A cylinder body (radius 4 cm) with a box 'head' on top, ~300 points (m)."""
    t = rng.uniform(0, 2 * np.pi, 220)
    z = rng.uniform(0, height, 220)
    body = np.c_[0.04 * np.cos(t), 0.04 * np.sin(t), z]
    head = np.c_[rng.uniform(-0.015, 0.015, 80), rng.uniform(-0.02, 0.05, 80), height + rng.uniform(0, 0.03, 80)]
    return np.vstack([body, head])


def test_the_instance_with_a_misplaced_region_is_not_chosen_and_consistent_ones_warp_within_millimetres():
    """Known answer: four bottles of different heights with the region on the front of the head
    (y 4 cm, 1.5 cm above the body), consistently annotated on three of them; on the last it is annotated
    3 cm lower. As canonical, that one starts every other instance's grasp ~3 cm off (mean error ~3 cm);
    the consistent ones are off only on it (~1 cm mean, 3 cm / 3 instances)."""
    rng = np.random.default_rng(4)
    heights = [0.16, 0.18, 0.20, 0.22]
    clouds = [_bottle(rng, h) for h in heights]
    centres = [np.array([0.0, 0.04, h + 0.015]) for h in heights]
    _, consistent, _ = choose_canonical_by_region(clouds, centres, SHAPE_KWARGS)
    assert np.all(consistent < 0.005)  # measured 2.9-3.9 mm
    centres[3] = centres[3] - [0.0, 0.0, 0.03]
    index, errors, space = choose_canonical_by_region(clouds, centres, SHAPE_KWARGS)
    assert index != 3 and errors[3] > 1.5 * errors[:3].max()  # measured 21.5 vs 11.7-12.1 mm
    assert np.all((errors[:3] > 0.007) & (errors[:3] < 0.016))
    assert space.canonical.shape == clouds[index].shape


def test_a_training_instance_without_the_region_is_a_one_line_error():
    with pytest.raises(InputError, match="no 'trigger' region annotated"):
        _region_centre({"regions": {"handle": {"center": [0, 0, 0]}}}, "trigger", "bottle_7")
