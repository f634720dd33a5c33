"""A new category from a folder of meshes (``catgrasp train --objects FOLDER``): reading, importing, training.

Known answers: the example tankards are built from parameters whose true handle boxes
``tools/make_example_category.py`` returns, one of them stored turned 90 deg with the way back stated.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from catgrasp_drake.data.category_folder import import_category, read_category_folder
from catgrasp_drake.data.dataset import imported_object, read_annotations
from catgrasp_drake.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "models" / "examples" / "tankards"
sys.path.insert(0, str(ROOT / "tools"))
from make_example_category import write_example  # noqa: E402

#: The importer cuts the lowest 3 mm of a base off flat and moves everything down by as much.
BASE_DROP_M = 0.003


def test_the_committed_example_is_what_its_tool_writes(tmp_path):
    write_example(tmp_path / "tankards")
    for f in sorted(EXAMPLE.iterdir()):
        assert (tmp_path / "tankards" / f.name).read_bytes() == f.read_bytes(), f.name


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    out = tmp_path_factory.mktemp("categories") / "tankard"
    truth = write_example(tmp_path_factory.mktemp("truth"))
    return import_category(EXAMPLE, out=out), truth


def test_every_mesh_is_imported_with_its_handle_where_the_generator_put_it(imported):
    objs, truth = imported
    assert [o.name for o in objs] == ["tankard_a", "tankard_b", "tankard_c"]  # the canonical first
    for o in objs:
        assert imported_object(o.directory) == ("mug", o.name)  # an object of the like-category
        ann = read_annotations(o.directory / "annotations.json")
        assert ann["family"]["name"] == "tankard" and ann["functional"]
        box = ann["regions"]["handle"]
        want = np.asarray(truth[o.name]["center"]) - [0, 0, BASE_DROP_M]
        # the canonical's box is given; the others' are carried by CPD from it: within 7 mm of the truth
        # (measured: 6.0 mm on the 13 % shorter tankard_b, 1.0 mm on tankard_c)
        tol = 1e-4 if o.name == "tankard_a" else 0.007
        assert np.linalg.norm(np.asarray(box["center"]) - want) < tol, (o.name, box["center"], want)
        lo, hi = o.mesh.bounds
        assert abs(lo[2]) < 1e-6 and hi[2] > 0.08  # standing on z = 0
    # tankard_c was stored turned 90 deg about z: the stated transform put its handle back on +y
    c = objs[2]
    assert c.regions["handle"]["center"][1] > 0.05 and abs(c.regions["handle"]["center"][0]) < 0.005
    assert c.record["transform"]["rpy_deg"][2] == pytest.approx(-90.0)
    # masses from the folder's density (1900 kg/m^3) and each solid's volume
    assert all(0.2 < o.mass_kg < 0.8 for o in objs)


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("like: mug", "like: kettle"), "like 'kettle': unknown category"),
    (lambda t: t.replace("canonical: tankard_a.obj", "canonical: nope.obj"), "not one of the folder's meshes"),
    (lambda t: t.replace("grasp: grasp.yaml", "grasp: missing.yaml"), "no such file"),
    (lambda t: t.replace('"0 0 -90 0 0 0"', '"0 0 -90"'), "six numbers"),
    (lambda t: t.replace("name: tankard", "name: Tankard Mugs"), "name 'Tankard Mugs'"),
    (lambda t: t + "colour: blue\n", "unknown field"),
    (lambda t: t.replace("center: [0.0000, 0.0595, 0.0550]", "center: [0, 59.5, 55]"), "expected metres"),
])
def test_a_bad_category_yaml_is_a_one_line_error(tmp_path, edit, message):
    folder = tmp_path / "tankards"
    shutil.copytree(EXAMPLE, folder)
    (folder / "category.yaml").write_text(edit((folder / "category.yaml").read_text()))
    with pytest.raises(InputError, match=message) as e:
        read_category_folder(folder)
    assert "\n" not in str(e.value)


def test_a_folder_without_category_yaml_or_with_one_mesh_is_refused(tmp_path):
    with pytest.raises(InputError, match="no category.yaml"):
        read_category_folder(tmp_path)
    folder = tmp_path / "one"
    shutil.copytree(EXAMPLE, folder)
    for name in ("tankard_b.obj", "tankard_c.obj"):
        (folder / name).unlink()
    (folder / "category.yaml").write_text((folder / "category.yaml").read_text().replace(
        '  tankard_c.obj: "0 0 -90 0 0 0"', ""))
    with pytest.raises(InputError, match="at least 2 meshes"):
        read_category_folder(folder)


def test_the_alignment_picture_shows_an_object_above_its_folders_canonical(imported, tmp_path):
    from PIL import Image

    from catgrasp_drake.viz.sheets import import_sheet

    objs, _ = imported
    png = import_sheet(objs[2].directory, tmp_path / "sheet.png", size=(120, 120), reference_dir=objs[0].directory)
    img = np.asarray(Image.open(png).convert("RGB"), float)
    assert img.shape[0] >= 240 and img.shape[1] >= 360  # two rows of three views
    red = (img[..., 0] > 180) & (img[..., 1] < 140) & (img[..., 2] < 140)
    top, bottom = red[: img.shape[0] // 2], red[img.shape[0] // 2:]
    assert top.sum() > 50 and bottom.sum() > 50  # the handle drawn on the object and on the canonical
