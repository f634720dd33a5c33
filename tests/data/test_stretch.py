"""Stretched committed instances (the benchmark's ``stress`` split): known answers for the geometry and the mass."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from catgrasp_drake.data.dataset import imported_object, load_annotations, load_mesh
from catgrasp_drake.data.meshes import back_overhang_underside_m, read_mesh
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


# ----------------------------------------------------------------------------- shrouded copies
def test_a_bottle_rebuilt_from_its_own_parameters_is_the_committed_one_byte_for_byte():
    from catgrasp_drake.data.categories import build_spray_bottle
    from catgrasp_drake.data.dataset import instance_mesh_path, obj_bytes

    for name in ("spray_bottle_00", "spray_bottle_11"):  # a flat and a deep bottle: no shroud unless asked
        annotations = load_annotations("spray_bottle", name)
        rebuilt = build_spray_bottle(annotations["params"])
        assert obj_bytes(rebuilt.mesh) == instance_mesh_path("spray_bottle", name).read_bytes()
        assert rebuilt.regions == annotations["regions"]


def test_a_shrouded_bottle_hangs_its_head_to_the_windex_height_above_the_trigger_and_keeps_the_rest(tmp_path):
    from catgrasp_drake.data.stretch import shrouded_instance

    written = shrouded_instance("spray_bottle_11", tmp_path / "s")
    assert imported_object(tmp_path / "s") == ("spray_bottle", "spray_bottle_11_shroud")
    ann0, ann = load_annotations("spray_bottle", "spray_bottle_11"), json.loads(
        (tmp_path / "s" / "annotations.json").read_text())
    assert ann["regions"] == ann0["regions"] and ann["shrouded_from"] == "spray_bottle_11"
    assert ann0["mass_kg"] < written.mass_kg < 1.05 * ann0["mass_kg"]  # the shroud is a little more solid
    trigger_z = ann0["regions"]["trigger"]["center"][2]
    plain = load_mesh("spray_bottle", "spray_bottle_11")
    shrouded = read_mesh(tmp_path / "s" / "spray_bottle_11_shroud.obj")
    top = plain.bounds[1, 2] - 0.002
    begins = {label: back_overhang_underside_m(m, 0.028, start_m=top) - trigger_z
              for label, m in (("plain", plain), ("shrouded", shrouded))}
    assert begins["plain"] > 0.014  # the generator's heads: 14-36 mm above (s41 experiment)
    assert begins["shrouded"] == pytest.approx(0.005, abs=0.003)  # the Windex bottle: 5.4 mm
    with pytest.raises(InputError, match="above_trigger_m"):
        shrouded_instance("spray_bottle_11", tmp_path / "bad", above_trigger_m=-0.01)


def test_a_bottle_given_by_its_directory_is_shrouded_as_by_its_name_and_other_objects_are_refused(tmp_path):
    from catgrasp_drake.data.dataset import instance_dir
    from catgrasp_drake.data.stretch import shrouded_instance

    by_name = shrouded_instance("spray_bottle_03", tmp_path / "a")
    by_dir = shrouded_instance(instance_dir("spray_bottle", "spray_bottle_03"), tmp_path / "b")
    assert by_dir.name == by_name.name == "spray_bottle_03_shroud"
    assert (tmp_path / "a" / "spray_bottle_03_shroud.obj").read_bytes() == (
        tmp_path / "b" / "spray_bottle_03_shroud.obj").read_bytes()
    with pytest.raises(InputError, match="spray bottles, not on a drill"):
        shrouded_instance(instance_dir("drill", "drill_00"), tmp_path / "c")
    stretch_instance("spray_bottle", "spray_bottle_03", (1.0, 1.0, 1.0), tmp_path / "s", name="copy")
    ann = json.loads((tmp_path / "s" / "annotations.json").read_text())
    ann["params"] = {}
    (tmp_path / "s" / "annotations.json").write_text(json.dumps(ann))
    with pytest.raises(InputError, match="no generator parameters"):
        shrouded_instance(tmp_path / "s", tmp_path / "d")


def test_on_a_shrouded_bottle_the_thumb_meets_the_head_at_the_index_height_as_on_the_windex_bottle(tmp_path):
    from catgrasp_drake.data.stretch import shrouded_instance
    from catgrasp_drake.planning.fit import closing_contacts
    from catgrasp_drake.station.handwritten import handwritten_trial

    shrouded_instance("spray_bottle_11", tmp_path / "s")
    first = {}
    for label, directory, name in (("plain", None, "spray_bottle_11"), ("shroud", tmp_path / "s", None)):
        scenario, motion = handwritten_trial("spray_bottle", name, object_dir=directory)
        first[label] = {c.finger: c for c in closing_contacts(scenario, motion)}
    # the committed grasp's thumb never meets the plain bottle 11 (s41 experiment: thumb_height.txt) ...
    assert first["plain"]["thumb"].fraction is None
    # ... and meets the shroud at once, within millimetres of the index's height (the Windex bottle: 6 mm above)
    thumb, index = first["shroud"]["thumb"], first["shroud"]["index"]
    assert thumb.fraction == 0.0 and thumb.link.startswith("svh_thumb")
    assert abs(thumb.point_O[2] - index.point_O[2]) < 0.010


def test_the_back_overhangs_underside_is_found_on_a_known_shape():
    import trimesh

    column = trimesh.creation.box((0.02, 0.02, 0.20))  # 20 cm tall, 1 cm behind its axis
    column.apply_translation([0, 0, 0.10])
    head = trimesh.creation.box((0.02, 0.06, 0.03))  # reaches 4 cm behind the axis between z = 0.15 and 0.18
    head.apply_translation([0, -0.01, 0.165])
    mesh = trimesh.util.concatenate([column, head])
    assert back_overhang_underside_m(mesh, 0.028, step_m=0.001, start_m=0.175) == pytest.approx(0.150, abs=0.0015)
    assert np.isnan(back_overhang_underside_m(column, 0.005))  # reaches back all the way down: no underside
    with pytest.raises(InputError, match="behind_m"):
        back_overhang_underside_m(mesh, 0.0)
