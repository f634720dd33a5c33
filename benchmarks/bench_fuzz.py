"""Property-based fuzzing of every public entry point: generated bad inputs, crashes, hangs, slowest rejection.

    python benchmarks/bench_fuzz.py [--profile ci|nightly] [--hang-s 30] [-k EXPR]

Runs the fuzz tests (``tests/reliability/test_fuzz_*.py``, ``test_numerical_robustness.py``,
``test_million_points.py``) with pytest in a subprocess under the chosen Hypothesis profile
(``ci``: deterministic, the CI set; ``nightly``: 10x the examples, randomised). Every generated
call is recorded by the tests' harness (``tests/reliability/harness.py``; the library knows
nothing of it) and summarised here, per entry point:

* inputs: generated calls tried (bad inputs, plus valid ones that exercise the other arguments);
* results / rejected: calls that returned a finite, well-shaped result / raised the project's own
  exception with a one-line message;
* crashes: any other ending (a numpy/scipy/Drake/open3d/trimesh exception, a RuntimeWarning such
  as an overflow, a NaN result, a multi-line message) -- must be 0;
* hangs: calls interrupted after ``--hang-s`` seconds -- must be 0;
* slowest rejection: seconds, and the input class it was given.

Exit status 0 only when pytest passed with no crash and no hang.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TESTS = ["tests/reliability/test_fuzz_*.py", "tests/reliability/test_numerical_robustness.py",
         "tests/reliability/test_million_points.py"]


def _table(records: list[dict]) -> list[str]:
    by_entry: dict[str, list[dict]] = collections.defaultdict(list)
    for r in records:
        by_entry[r["entry"]].append(r)
    head = (f"{'entry point':<36s} {'inputs':>6s} {'results':>7s} {'rejected':>8s} {'crashes':>7s} {'hangs':>5s}  "
            f"slowest rejection")
    lines = [head, "-" * len(head)]
    totals = collections.Counter()
    for entry in sorted(by_entry):
        rs = by_entry[entry]
        c = collections.Counter(r["outcome"] for r in rs)
        rej = [r for r in rs if r["outcome"] == "rejected"]
        slow = max(rej, key=lambda r: r["seconds"]) if rej else None
        slow_s = f"{slow['seconds']:.3f} s  ({slow['label'][:60]})" if slow else "-"
        lines.append(f"{entry:<36s} {len(rs):6d} {c['result']:7d} {c['rejected']:8d} {c['crash']:7d} {c['hang']:5d}  "
                     f"{slow_s}")
        totals.update(c)
        totals["inputs"] += len(rs)
    lines.append("-" * len(head))
    rej = [r for r in records if r["outcome"] == "rejected"]
    slow = max(rej, key=lambda r: r["seconds"]) if rej else None
    lines.append(f"{'TOTAL (' + str(len(by_entry)) + ' entry points)':<36s} {totals['inputs']:6d} "
                 f"{totals['result']:7d} {totals['rejected']:8d} {totals['crash']:7d} {totals['hang']:5d}  "
                 + (f"{slow['seconds']:.3f} s  ({slow['entry']}: {slow['label'][:50]})" if slow else "-"))
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--profile", choices=("ci", "nightly"), default="ci", help="Hypothesis profile")
    ap.add_argument("--hang-s", type=float, default=30.0, help="a single call running longer is a hang")
    ap.add_argument("-k", default=None, help="pytest -k expression (a subset of the fuzz tests)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench_fuzz_") as tmp:
        record = Path(tmp) / "calls.jsonl"
        env = dict(os.environ, HYPOTHESIS_PROFILE=args.profile, CATGRASP_FUZZ_RECORD=str(record),
                   CATGRASP_FUZZ_HANG_S=str(args.hang_s))
        files = sorted(str(p.relative_to(REPO)) for pattern in TESTS for p in REPO.glob(pattern))
        cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *files]
        if args.k:
            cmd += ["-k", args.k]
        print(f"profile {args.profile}: pytest on {len(files)} files ...", flush=True)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        summary = [ln for ln in proc.stdout.splitlines() if ln.strip()][-1:] or ["(no pytest output)"]
        records = [json.loads(ln) for ln in record.read_text().splitlines()] if record.is_file() else []
    print("\n".join(_table(records)))
    crashes = sum(r["outcome"] == "crash" for r in records)
    hangs = sum(r["outcome"] == "hang" for r in records)
    print(f"\npytest: {summary[0]}  (exit {proc.returncode}); wall time {wall:.1f} s")
    if proc.returncode != 0:
        print("\n".join(proc.stdout.splitlines()[-40:]))
        print(proc.stderr[-2000:], file=sys.stderr)
    for r in records:
        if r["outcome"] in ("crash", "hang"):
            print(f"  {r['outcome']}: {r['entry']} [{r['label']}] {r['message']}")
    return 0 if proc.returncode == 0 and crashes == 0 and hangs == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
