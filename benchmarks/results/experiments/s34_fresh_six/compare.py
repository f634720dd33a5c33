"""Session 34: a fresh-split records file, latent against its baselines, with the report's own tables (measured only).

    python benchmarks/results/experiments/s34_fresh_six/compare.py RECORDS.jsonl [COMMITTED.jsonl]

Prints ``catgrasp report``'s tables (``benchmark.report.benchmark_tables``: every method's rates and latent
minus each baseline, paired over instances) for all the file's placements, then for placements 3 and up alone
(the ones the committed records do not hold), then how many of the file's trials repeat the verdict of the
same trial in ``COMMITTED`` (default ``benchmarks/results/fresh_seed20261205.jsonl``; trials matched by
category, method, instance, placement, view, physics and data seed).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.report import benchmark_tables, load_benchmark_records  # noqa: E402
from catgrasp_drake.benchmark.stats import PAIR_KEY, pair_records  # noqa: E402

VERDICT = ("grasp", "functional", "reason")


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    records = load_benchmark_records(argv[0])
    committed = load_benchmark_records(argv[1] if len(argv) > 1 else "benchmarks/results/fresh_seed20261205.jsonl")
    print(f"## {argv[0]}: all placements\n\n{benchmark_tables(records)}")
    later = [r for r in records if r["trial"] >= 3]
    if later:
        print(f"## placements 3 and up alone\n\n{benchmark_tables(later)}")
    pairs = pair_records(records, committed, key=PAIR_KEY + ("method", "data_seed"))
    same = sum(all(a[f] == b[f] for f in VERDICT) for a, b in zip(pairs.a, pairs.b))
    print(f"trials also in the committed records: {len(pairs)}; the same verdict: {same}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
