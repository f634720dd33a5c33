"""Stretched committed instances (the benchmark's ``stress`` split): known answers for the geometry and the mass."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from catgrasp_drake.data.dataset import imported_object, load_annotations, load_mesh
from catgrasp_drake.data.meshes import read_mesh
from catgrasp_drake.data.stretch import STRESS_FAMILIES, check_stretch, stretch_instance
from catgrasp_drake.errors import InputError


def test_a_stretched_drill_scales_mesh_regions_and_mass_exactly(tmp_path):
    s = np.array([0.8, 1.3, 1.1])
    w = stretch_instance("drill", "drill_03", s, tmp_path / "d", name="drill_03_test")
    assert imported_object(tmp_path / "d") == ("drill", "drill_03_test")
    source, ann0 = load_mesh("drill", "drill_03"), load_annotations("drill", "drill_03")
    mesh = read_mesh(tmp_path / "d" / "drill_03_test.obj")
    np.testing.assert_allclose(mesh.bounds, source.bounds * s, atol=2e-6)  # base stays on z = 0
    assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    ann = json.loads((tmp_path / "d" / "annotations.json").read_text())
    for name, region in ann0["regions"].items():
        np.testing.assert_allclose(ann["regions"][name]["center"], np.asarray(region["center"]) * s, atol=1e-6)
        np.testing.assert_allclose(ann["regions"][name]["half_extents"], np.asarray(region["half_extents"]) * s,
                                   atol=1e-6)
    # the same density: the mass scales with the volume, sx * sy * sz
    assert w.mass_kg == pytest.approx(ann0["mass_kg"] * float(np.prod(s)), rel=1e-4)
    assert ann["stretched_from"] == "drill_03" and ann["stretch"] == pytest.approx(list(s))
    assert ann["density_kg_m3"] == ann0["density_kg_m3"]
    sdf = (tmp_path / "d" / "drill_03_test.sdf").read_text()
    assert float(re.search(r"<mass>([^<]+)</mass>", sdf).group(1)) == pytest.approx(w.mass_kg, rel=1e-6)
    assert ann["mass_kg"] == pytest.approx(w.mass_kg, abs=1e-6)


@pytest.mark.parametrize("bad", [(0.0, 1.0, 1.0), (1.0, 1.0), (1.0, float("nan"), 1.0), (3.0, 1.0, 1.0), "big"])
def test_a_stretch_outside_the_category_is_refused_in_one_line(bad):
    with pytest.raises(InputError, match="stretch: expected") as e:
        check_stretch(bad)
    assert "\n" not in str(e.value)


def test_the_stress_families_are_valid_stretches():
    assert set(STRESS_FAMILIES) == {"small", "large", "thin", "deep"}
    for s in STRESS_FAMILIES.values():
        check_stretch(s)
