"""Faults: trials that throw inside Drake, dead workers, corrupt files.

kill -9 and resume: ``test_against_reference_runs.py`` (it shares the uninterrupted reference runs).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
from pathlib import Path

import pytest

from catgrasp_drake.errors import ModelFileError
from catgrasp_drake.runner import run_tasks, task_key

from . import tiny_runs as tiny

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _one_line_naming(message: str, path) -> None:
    assert message and "\n" not in message, message
    assert str(path) in message, message


def object_trial(spec: dict) -> dict:
    """Worker task: the real grasp trial (``run_grasp_trial``) of the hand-written drill grasp on the object
    in ``spec["model_dir"]``."""
    from catgrasp_drake.station.handwritten import load_handwritten_motion
    from catgrasp_drake.station.scenario import load_scenario, with_instance
    from catgrasp_drake.trial import run_grasp_trial

    scenario = with_instance(load_scenario("drill_default"), spec["instance"], model_dir=spec["model_dir"])
    return run_grasp_trial(scenario, load_handwritten_motion("drill", spec["instance"])).to_dict()


def _broken_objects(tmp_path) -> list[dict]:
    from catgrasp_drake.data.dataset import instance_dir

    meshes = {
        # a face naming a vertex that does not exist: a failed DRAKE_DEMAND in Drake's triangle mesh,
        # which pydrake raises as SystemExit
        "bad_index": "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 2 3\nf 1 2 9\n",
        # no vertices at all: Drake's MakeConvexHull throws RuntimeError
        "garbage": "this is not a mesh\n",
    }
    specs = []
    for name, text in meshes.items():
        folder = tmp_path / name
        shutil.copytree(instance_dir("drill", "drill_03"), folder)
        (folder / "drill_03.obj").write_text(text)
        specs.append({"instance": "drill_03", "model_dir": str(folder), "case": name})
    return specs


@pytest.mark.parametrize("workers", [0, 2], ids=["in_process", "worker_processes"])
def test_a_trial_that_throws_inside_drake_is_a_failed_trial_with_its_reason(tmp_path, workers):
    specs = _broken_objects(tmp_path)
    outcomes = run_tasks(object_trial, specs, cache_dir=tmp_path / "cache", code_version="t", workers=workers)
    assert len(outcomes) == 2  # the run finished
    for o in outcomes:
        r = o.result
        assert r["status"] == "error", r
        assert r["error"] and "\n" not in r["error"]
    bad_index, garbage = (o.result["error"] for o in outcomes)
    assert bad_index.startswith("SystemExit: Failure at") and "condition" in bad_index
    assert garbage.startswith("RuntimeError:") and "MakeConvexHull" in garbage
    # a deterministic failure is an outcome like any other: cached, not retried
    again = run_tasks(object_trial, specs, cache_dir=tmp_path / "cache", code_version="t", workers=workers)
    assert all(o.cached for o in again) and [o.result for o in again] == [o.result for o in outcomes]


def crashing_task(spec: dict) -> dict:
    """Kills its own worker process when asked to (a segfault or OOM kill, as far as the pool can tell)."""
    if spec.get("crash"):
        os.kill(os.getpid(), signal.SIGKILL)
    return {"y": spec["x"] * 2}


def test_a_worker_that_dies_costs_its_own_task_not_the_run(tmp_path):
    specs = [{"x": 0}, {"x": 1, "crash": True}, {"x": 2}, {"x": 3}, {"x": 4}]
    out = run_tasks(crashing_task, specs, cache_dir=tmp_path, code_version="v", workers=2)
    assert [o.result.get("y") for o in out] == [0, None, 4, 6, 8]
    dead = out[1].result
    assert dead["status"] == "error" and dead["error"] == \
        "WorkerDied: the worker process running this task was killed by SIGKILL"
    # the dead worker's task is not cached (it may have been killed from outside): the next run retries it
    assert sorted(p.stem for p in tiny.cached_files(tmp_path)) == sorted(o.key for i, o in enumerate(out) if i != 1)
    # (two uncached tasks: a single one would run in this process -- and kill it)
    again = run_tasks(crashing_task, specs + [{"x": 5}], cache_dir=tmp_path, code_version="v", workers=2)
    assert [o.cached for o in again] == [True, False, True, True, True, False] and again[1].result == dead


def test_a_task_result_that_cannot_be_stored_is_an_error_not_a_dead_run(tmp_path):
    out = run_tasks(_unstorable, [{"x": 1}], cache_dir=tmp_path, code_version="v", workers=0)
    assert out[0].result["status"] == "error" and "JSON serializable" in out[0].result["error"]


def _unstorable(spec):
    return {"value": object()}


# ----------------------------------------------------------------------------- corrupt files
def _square(spec: dict) -> dict:
    return {"y": spec["x"] ** 2}


def test_corrupt_trial_cache_files_are_recomputed(tmp_path):
    specs = [{"x": i} for i in range(6)]
    first = run_tasks(_square, specs, cache_dir=tmp_path, code_version="v", workers=0)
    paths = [tmp_path / f"{o.key}.json" for o in first]
    paths[0].write_text(paths[0].read_text()[:40])  # truncated
    paths[1].write_text(paths[1].read_text().replace('"y": 1', '"y": 7'))  # edited: checksum mismatch
    paths[2].write_text("[1, 2, 3]\n")  # valid JSON, not a cache record
    paths[3].write_bytes(b"\xff\xfe\x00garbage")  # not UTF-8
    shutil.copy(paths[5], paths[4])  # another trial's (whole, valid) file under this key
    again = run_tasks(_square, specs, cache_dir=tmp_path, code_version="v", workers=0)
    assert [o.cached for o in again] == [False] * 5 + [True]
    assert [o.result["y"] for o in again] == [i * i for i in range(6)]
    for p in paths:  # rewritten whole
        record = json.loads(p.read_text())
        assert record["format"] == "catgrasp.task_result" and record["format_version"] == 1 and record["sha256"]


def test_a_legacy_cache_file_without_checksum_is_still_read(tmp_path):
    out = run_tasks(_square, [{"x": 3}], cache_dir=tmp_path, code_version="v", workers=0)
    p = tmp_path / f"{out[0].key}.json"
    record = json.loads(p.read_text())
    for k in ("format", "format_version", "sha256"):
        record.pop(k)
    p.write_text(json.dumps(record))
    again = run_tasks(_square, [{"x": 3}], cache_dir=tmp_path, code_version="v", workers=0)
    assert again[0].cached and again[0].result["y"] == 9


_MODEL_CORRUPTIONS = {
    "truncated": lambda b: b[: len(b) // 2],
    "empty": lambda b: b"",
    "not_an_archive": lambda b: b"hello, I am not a model\n" * 10,
    "bit_flip": lambda b: b[: len(b) // 2] + bytes([b[len(b) // 2] ^ 0x10]) + b[len(b) // 2 + 1:],
}


@pytest.mark.parametrize("corruption", sorted(_MODEL_CORRUPTIONS))
def test_a_corrupt_model_file_is_a_one_line_error_naming_it(tmp_path, corruption):
    from catgrasp_drake.category_model import CategoryModel

    path = tmp_path / "drill.npz"
    path.write_bytes(_MODEL_CORRUPTIONS[corruption]((tiny.REPO / "models/trained/drill.npz").read_bytes()))
    with pytest.raises(ModelFileError) as e:
        CategoryModel.load(path)
    _one_line_naming(str(e.value), path)


def test_an_edited_model_fails_its_checksum(tmp_path):
    import numpy as np

    from catgrasp_drake.category_model import CategoryModel

    arrays, header = tiny.model_contents(tiny.REPO / "models/trained/drill.npz")
    arrays["regressor/coef"] = arrays["regressor/coef"] + 1e-12
    header_array = np.frombuffer(json.dumps(header).encode(), np.uint8)
    path = tmp_path / "edited.npz"
    np.savez(path, __header__=header_array, **arrays)
    with pytest.raises(ModelFileError, match="checksum mismatch") as e:
        CategoryModel.load(path)
    _one_line_naming(str(e.value), path)


def test_a_model_whose_header_is_not_an_object_is_a_clear_error(tmp_path):
    import numpy as np

    from catgrasp_drake.category_model import CategoryModel

    path = tmp_path / "odd.npz"
    np.savez(path, __header__=np.frombuffer(b"[1, 2]", np.uint8), a=np.ones(2))
    with pytest.raises(ModelFileError, match="corrupt header") as e:
        CategoryModel.load(path)
    _one_line_naming(str(e.value), path)


def test_a_corrupt_fold_model_stops_the_evaluation_with_its_name(tmp_path):
    from catgrasp_drake.evaluation import EvalConfig, evaluate

    out = tiny.prepare_eval_dir(tmp_path)
    fold = out / "drill" / f"fold{tiny.EVAL_FOLD}.npz"
    fold.write_bytes(fold.read_bytes()[:1000])
    config = EvalConfig(category="drill", methods=("latent",), views=("single",), instances=(tiny.EVAL_INSTANCE,),
                        workers=0, out_dir=str(out))
    with pytest.raises(ModelFileError, match="delete it to retrain it") as e:
        evaluate(config)
    _one_line_naming(str(e.value), fold)
    assert not tiny.eval_cache(out).exists()  # stopped before any trial


def test_the_cli_reports_a_corrupt_model_in_one_line(tmp_path, capsys):
    from catgrasp_drake.cli import main

    path = tmp_path / "drill.npz"
    path.write_bytes(b"\x00" * 100)
    assert main(["view", "drill", "--model", str(path), "--once"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("catgrasp: error:")
    _one_line_naming(err, path)



def test_a_script_reports_a_missing_object_directory_in_one_line(tmp_path):
    """The diagram and benchmark scripts end bad input as the catgrasp command does: one line, status 2."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[2]
    missing = tmp_path / "no_such_object"
    run = subprocess.run([sys.executable, str(root / "diagrams" / "handwritten_sweep.py"), "--objects", str(missing)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2
    err = run.stderr.strip()
    assert err.startswith("handwritten_sweep.py: error:") and "Traceback" not in err
    _one_line_naming(err, missing)

def _records():
    return [{"category": "drill", "fold": 5, "instance": "drill_11", "view": "single", "method": m,
             "seed": 0, "grasp": m == "latent", "functional": False, "reason": "not_lifted",
             "confidence": 0.5, "inference_s": 0.2} for m in ("latent", "rigid", "cpd")]


_RECORD_CORRUPTIONS = {
    "truncated": lambda t: t[: len(t) - 40],
    "edited": lambda t: t.replace('"grasp": true', '"grasp": false'),
    "record_dropped": lambda t: "".join(t.splitlines(keepends=True)[:-1]),
    "not_json": lambda t: t.replace("{", "<", 2),
    "header_of_another_format": lambda t: t.replace("catgrasp.eval_records", "catgrasp.something_else"),
}


@pytest.mark.parametrize("corruption", sorted(_RECORD_CORRUPTIONS))
def test_corrupt_records_are_a_one_line_error_naming_the_file(tmp_path, corruption):
    from catgrasp_drake.evaluation import load_records, write_records

    path = tmp_path / "records.jsonl"
    write_records(path, _records())
    assert load_records(path) == _records()
    path.write_text(_RECORD_CORRUPTIONS[corruption](path.read_text()))
    with pytest.raises(ModelFileError) as e:
        load_records(path)
    _one_line_naming(str(e.value), path)


def test_records_without_header_and_non_object_lines(tmp_path):
    from catgrasp_drake.evaluation import load_records

    path = tmp_path / "records.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in _records()))  # written before the header existed
    assert load_records(path) == _records()
    path.write_text(json.dumps(_records()[0]) + "\n[1, 2]\n")
    with pytest.raises(ModelFileError, match="line 2 is a JSON list") as e:
        load_records(path)
    _one_line_naming(str(e.value), path)
    with pytest.raises(ModelFileError) as e:
        load_records(tmp_path / "missing.jsonl")
    _one_line_naming(str(e.value), tmp_path / "missing.jsonl")


def test_corrupt_report_is_a_one_line_error_naming_it(tmp_path):
    from catgrasp_drake.evaluation import load_report, write_report

    path = tmp_path / "report.json"
    report = {"table": {"latent": {"grasp": {"single": [1, 2]}}}, "wall_s": 1.5, "nan": float("nan")}
    write_report(path, report)
    body = load_report(path)
    assert body["table"] == report["table"] and body["format"] == "catgrasp.eval_report"
    path.write_text(path.read_text().replace("1.5", "2.5"))
    with pytest.raises(ModelFileError, match="checksum") as e:
        load_report(path)
    _one_line_naming(str(e.value), path)
    path.write_text(path.read_text()[:30])
    with pytest.raises(ModelFileError) as e:
        load_report(path)
    _one_line_naming(str(e.value), path)


def test_the_eval_cache_key_follows_the_model_file(tmp_path):
    """A retrained (different) fold model never reuses the trials of the old one; a copy of it elsewhere does."""
    from catgrasp_drake.evaluation import EvalConfig, leave_two_out, trial_specs

    config = EvalConfig(category="drill", methods=("latent",), views=("single",), out_dir=str(tmp_path))
    a, b = tmp_path / "a.npz", tmp_path / "b.npz"
    a.write_bytes(b"model one")
    b.write_bytes(b"model two")
    folds = leave_two_out("drill")
    spec_a = trial_specs(config, {k: str(a) for k in range(len(folds))}, folds)[0]
    shutil.copy(b, a)  # same path, new contents
    spec_b = trial_specs(config, {k: str(a) for k in range(len(folds))}, folds)[0]
    assert spec_a["_model"] == spec_b["_model"] and task_key(spec_a, "v") != task_key(spec_b, "v")
    shutil.copy(a, tmp_path / "c.npz")  # the same contents at another path: the same trials
    spec_c = trial_specs(config, {k: str(tmp_path / "c.npz") for k in range(len(folds))}, folds)[0]
    assert spec_c["_model"] != spec_b["_model"] and task_key(spec_c, "v") == task_key(spec_b, "v")

