"""Session 35: fresh-split records of several data seeds pooled, with the report's own tables (measured only).

    python benchmarks/results/experiments/s35_fresh_pooled/pool.py RECORDS.jsonl [RECORDS.jsonl ...]

Prints ``catgrasp report``'s tables (``benchmark.report.benchmark_tables``) for the records of all the files
together. The report refuses several fresh seeds in one table, since their instances share names
(``drill_00`` of seed 20261205 is not ``drill_00`` of 20261206). So each fresh record's instance is renamed
``<name>@<data_seed>`` and its ``data_seed`` set to the label ``pooled``. The instances of two seeds are then
distinct draws, methods still pair trial by trial within a seed, and the bootstrap resamples all instances.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.report import benchmark_tables, load_benchmark_records  # noqa: E402


def pooled(record: dict) -> dict:
    """A fresh-split record with its data seed in its instance's name (module docstring); others unchanged."""
    if record["split"] != "fresh":
        return record
    return record | {"instance": f"{record['instance']}@{record['data_seed']}", "data_seed": "pooled"}


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv:
        print(__doc__)
        return 2
    records = [pooled(r) for path in argv for r in load_benchmark_records(path)]
    print(f"## {len(records)} records from {', '.join(argv)}\n\n{benchmark_tables(records)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
