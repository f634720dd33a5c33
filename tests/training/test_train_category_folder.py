"""``catgrasp train --objects FOLDER``: a new category trained from a folder of meshes, end to end (physics).

The example tankards (models/examples/tankards) with one sampled motion per instance -- the folder's
hand-written grasp warped onto each -- must give functional grasps (the mug grasp holds a tankard's handle),
and the model, of the like-category, must transfer to a tankard it imports afterwards by itself.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from catgrasp_drake.benchmark.report import load_benchmark_records
from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.cli import main
from catgrasp_drake.core.fileio import file_sha256
from catgrasp_drake.data.dataset import obj_bytes, read_annotations
from catgrasp_drake.data.importer import import_object

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
from make_example_category import tankard  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[2] / "models" / "examples" / "tankards"


@pytest.mark.slow
def test_train_a_new_category_from_a_folder_then_import_a_new_member_with_its_model(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # the objects go to out/categories/tankard/ under the working directory
    model_path = tmp_path / "tankard.npz"
    code = main(["train", "--objects", str(EXAMPLE), "--samples", "1", "--workers", "2", "--cache",
                 str(tmp_path / "cache"), "--out", str(model_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    model = CategoryModel.load(model_path)
    assert model.category == "mug" and model.params["family"]["name"] == "tankard"
    assert model.instances == ("tankard_a", "tankard_b", "tankard_c") and model.canonical_instance == "tankard_a"
    st = model.stats
    assert st["trials_functional"] >= 2 and st["instances_with_functional_success"] >= 2, out
    # the model's template is the folder's grasp on the canonical tankard's handle
    handle = read_annotations(tmp_path / "out/categories/tankard/tankard_a/annotations.json")["regions"]["handle"]
    assert np.allclose(model.template.pose("grasp")[:3, 3], np.asarray(handle["center"]) +
                       [0.12132, 0.05246, 0.0266], atol=1e-6)
    # a new tankard, stored lying on its side and turned, is aligned and annotated by the family's model
    mesh, (centre, _) = tankard(0.046, 0.105, 0.006, 0.027, 0.0085, 0.55)
    turned = mesh.copy()
    turned.apply_transform(trimesh.transformations.euler_matrix(np.radians(90), 0, np.radians(130)))
    (tmp_path / "new.obj").write_bytes(obj_bytes(turned))
    new = import_object(tmp_path / "new.obj", "mug", model=model, out=tmp_path / "new")
    got = np.asarray(new.regions["handle"]["center"])
    assert np.abs(got - (centre - [0, 0, 0.003])).max() < 0.006, got  # the handle found (base cut 3 mm)
    assert new.mesh.bounds[0][2] > -1e-6 and new.mesh.extents[2] > 0.1  # standing upright
    # the family's own objects through the benchmark's transfer diagram, with the family's model
    records = tmp_path / "records.jsonl"
    code = main(["benchmark", "--objects", str(tmp_path / "out/categories/tankard/tankard_c"), "--model",
                 str(model_path), "--methods", "latent", "--placements", "1", "--out", str(records), "--cache",
                 str(tmp_path / "bcache"), "--workers", "0"])
    out = capsys.readouterr().out
    assert code == 0, out
    rec = load_benchmark_records(records)
    assert len(rec) == 1 and rec[0]["model_sha256"] == file_sha256(model_path) and rec[0]["instance"] == "tankard_c"
    assert main(["benchmark", "--categories", "mug", "--model", str(model_path)]) == 2
    assert "--model: only with --objects" in capsys.readouterr().err
    # a wrong category name for the folder is a one-line error
    assert main(["train", "drill", "--objects", str(EXAMPLE)]) == 2
    assert "a 'tankard' category (like mug), not 'drill'" in capsys.readouterr().err
