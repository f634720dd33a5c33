"""The README's and docs/benchmark.md's benchmark tables are exactly what the committed records give."""

from __future__ import annotations

import pytest

from catgrasp_drake.benchmark.report import check_markdown, committed_models, load_benchmark_records
from tests.conftest import REPO

RESULTS = REPO / "benchmarks" / "results"


def test_committed_tables_equal_the_committed_records():
    paths = sorted(RESULTS.glob("*.jsonl"))
    if not paths:
        pytest.skip("no committed benchmark records yet")
    records = load_benchmark_records(paths)  # format, version, count and checksum of every file
    assert records
    for md in (REPO / "README.md", REPO / "docs" / "benchmark.md"):
        stale = check_markdown(md, records, committed_models())  # rows of earlier models marked
        assert stale == [], f"{md.name}: tables {stale} differ from benchmarks/results; run 'catgrasp report'"
