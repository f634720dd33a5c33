"""Same seed -> same results, bit for bit, on one machine: data generation, training, an evaluation trial.

Wall-clock timings are the only fields allowed to differ, and they are named: a model's
``MODEL_TIMING_STATS``, a trial's ``TRIAL_TIMING_FIELDS``, an evaluation record's
``evaluation.TIMING_FIELDS``.
"""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from . import tiny_runs as tiny

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


@pytest.mark.slow
def test_training_twice_with_the_same_seed_gives_a_bit_identical_model(tmp_path):
    """A library call with worker processes vs the reference CLI run with one worker (other process, other
    scheduling, other trial order per process): every array bit for bit, every statistic but timings."""
    from catgrasp_drake.training import TrainingConfig, train_category

    tiny.start_reference_training()  # in the background, beside this run
    config = TrainingConfig(samples_per_instance=tiny.TRAIN_SAMPLES, seed=tiny.TRAIN_SEED, workers=2,
                            cache_dir=str(tmp_path / "cache"))
    model = train_category(tiny.TRAIN_CATEGORY, list(tiny.TRAIN_INSTANCES), config)
    model.save(tmp_path / "model.npz")
    ref_model, ref_cache, _ = tiny.reference_training()
    tiny.skip_if_code_changed(tmp_path / "cache", ref_cache)
    assert tiny.model_differences(tmp_path / "model.npz", ref_model) == []
    assert model.stats["trials_functional"] >= 1  # a model learnt from real successes
    # trial by trial, too
    mine = {f.name: json.loads(f.read_text())["result"] for f in tiny.cached_files(tmp_path / "cache")}
    ref = {f.name: json.loads(f.read_text())["result"] for f in tiny.cached_files(ref_cache)}
    assert sorted(mine) == sorted(ref)

    def outcome(r):
        return {k: v for k, v in r.items() if k not in tiny.TRIAL_TIMING_FIELDS}

    assert all(outcome(mine[k]) == outcome(ref[k]) for k in ref)


@pytest.mark.slow
def test_one_evaluation_trial_twice_gives_the_same_record():
    """The reference evaluation's latent trial (a CLI subprocess) run again in this process: same record,
    the named timing fields aside."""
    from catgrasp_drake.evaluation import TIMING_FIELDS, eval_trial_task

    ref_out, _ = tiny.reference_evaluation()
    cached = [json.loads(f.read_text()) for f in tiny.cached_files(tiny.eval_cache(ref_out))]
    (ref,) = [c for c in cached if c["spec"]["method"] == "latent"]
    again = eval_trial_task(ref["spec"])
    again.setdefault("status", "ok")
    assert ref["result"]["status"] == "ok" and ref["result"]["sim_s"] > 0  # an executed trial, not an error

    def outcome(r):
        return {k: v for k, v in r.items() if k not in TIMING_FIELDS}

    assert outcome(again) == outcome(ref["result"])
    assert set(again) - set(outcome(again)) == set(TIMING_FIELDS)


def test_data_generation_is_bit_for_bit(tmp_path):
    """The whole data set, generated twice from its seed: byte-identical files, equal to the committed ones;
    another seed gives other shapes (the seed is really used)."""
    from catgrasp_drake.data.dataset import generate_dataset, objects_dir, tree_digest

    generate_dataset(tmp_path / "a")
    generate_dataset(tmp_path / "b")
    a, b = tree_digest(tmp_path / "a"), tree_digest(tmp_path / "b")
    assert a == b and len(a) >= 3 * 40
    assert a == tree_digest(objects_dir())
    generate_dataset(tmp_path / "c", categories=("drill",), seed=7)
    c = tree_digest(tmp_path / "c")
    assert all(c[k] != a[k] for k in c if k.endswith(".obj"))


def test_a_model_file_is_byte_identical_whenever_it_is_written(tmp_path, monkeypatch):
    """No wall-clock time in the archive: the same model saved at two moments gives the same bytes."""
    from catgrasp_drake.category_model import CategoryModel

    model = CategoryModel.load(tiny.REPO / "models" / "trained" / "drill.npz")
    model.save(tmp_path / "a.npz")
    later = time.time() + 3 * 24 * 3600.0
    monkeypatch.setattr(time, "time", lambda: later)
    model.save(tmp_path / "b.npz")
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    arrays_a, _ = tiny.model_contents(tmp_path / "a.npz")
    arrays_ref, _ = tiny.model_contents(tiny.REPO / "models" / "trained" / "drill.npz")
    assert all(np.array_equal(arrays_a[k], arrays_ref[k]) for k in arrays_ref)


def test_run_tasks_returns_spec_order_whatever_the_completion_order(tmp_path):
    from catgrasp_drake.runner import run_tasks

    specs = [{"x": i, "sleep": 0.3 * (i % 3 == 0)} for i in range(6)]
    a = run_tasks(_slow_square, specs, cache_dir=None, code_version="v", workers=2)
    b = run_tasks(_slow_square, specs[::-1], cache_dir=None, code_version="v", workers=0)
    assert [o.result for o in a] == [o.result for o in b[::-1]] == [{"y": i * i, "status": "ok"} for i in range(6)]


def _slow_square(spec):
    time.sleep(spec["sleep"])
    return {"y": spec["x"] ** 2}
