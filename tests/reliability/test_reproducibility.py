"""Same seed -> same results, bit for bit, on one machine: data generation, model files, task order.

Training and an evaluation trial run twice: ``test_against_reference_runs.py`` (it shares the reference runs).

Wall-clock timings are the only fields allowed to differ, and they are named: a model's
``MODEL_TIMING_STATS``, a trial's ``TRIAL_TIMING_FIELDS``, an evaluation record's
``evaluation.TIMING_FIELDS``.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from . import tiny_runs as tiny

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


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
