"""A small evaluation: one held-out drill, one view, all four methods; records and Table I agree."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from catgrasp_drake.baselines import METHODS
from catgrasp_drake.demo import default_model_path
from catgrasp_drake.evaluation import (
    EvalConfig,
    auroc,
    evaluate,
    format_table,
    leave_two_out,
    load_records,
    table_one,
)


def test_leave_two_out_folds_follow_the_paper():
    folds = leave_two_out("drill")
    assert len(folds) == 6
    tested = [t for _, test in folds for t in test]
    assert len(tested) == 12 and len(set(tested)) == 12 and "drill_00" not in tested
    for train, test in folds:
        assert train[0] == "drill_00" and not set(train) & set(test) and len(train) == 11
    assert len(leave_two_out("spray_bottle")) == 7 and len(leave_two_out("mug")) == 7
    # the last fold's training set is the committed default model's
    assert folds[5][1] == ["drill_11", "drill_12"]


def test_auroc_known_answers():
    assert auroc([0.9, 0.8, 0.1, 0.2], [1, 1, 0, 0]) == 1.0
    assert auroc([0.1, 0.2, 0.9, 0.8], [1, 1, 0, 0]) == 0.0
    assert auroc([0.5, 0.5], [1, 0]) == 0.5
    assert auroc([0.3, 0.4], [1, 1]) is None


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("eval")
    (out / "drill").mkdir()
    # fold 5 trains on every drill but drill_11/12 with the default budget: that is the committed model
    shutil.copy(default_model_path("drill"), out / "drill" / "fold5.npz")
    config = EvalConfig(category="drill", views=("single",), instances=("drill_12",), workers=2,
                        out_dir=str(out))
    return config, evaluate(config)


@pytest.mark.slow
def test_records_cover_every_method_and_instance_once(report):
    config, rep = report
    keys = {(r["instance"], r["view"], r["method"]) for r in rep.records}
    assert len(rep.records) == len(METHODS) and keys == {("drill_12", "single", m) for m in METHODS}
    for r in rep.records:
        assert r["fold"] == 5 and r["seed"] == 0 and r["num_points"] > 300
        assert isinstance(r["grasp"], bool) and isinstance(r["functional"], bool)
        assert r["functional"] <= r["grasp"]
        assert (r["reason"] is None) == r["functional"]
        assert 0.0 <= r["confidence"] <= 1.0 and r["inference_s"] > 0


def test_table_counts_equal_the_records_and_reload(report):
    config, rep = report
    for m in METHODS:
        rs = [r for r in rep.records if r["method"] == m]
        assert rep.table[m]["grasp"]["single"] == [sum(r["grasp"] for r in rs), 1]
        assert rep.table[m]["functional"]["single"] == [sum(r["functional"] for r in rs), 1]
    reloaded = load_records(f"{config.out_dir}/drill/records.jsonl")
    assert table_one(reloaded) == rep.table
    text = format_table("drill", rep.table)
    assert "paper (RA-L 2018)" in text and all(f"| {m} |" in text for m in METHODS)
    assert set(rep.inference_s) == set(METHODS)
    assert rep.confidence["trials"] == 1


def test_rerun_reads_the_cache(report):
    config, rep = report
    cache = Path(config.out_dir) / "drill" / "trial_cache"
    before = sorted(p.name for p in cache.rglob("*.json"))
    again = evaluate(config)
    assert again.records == rep.records
    assert len(before) == len(METHODS) and sorted(p.name for p in cache.rglob("*.json")) == before  # nothing recomputed
