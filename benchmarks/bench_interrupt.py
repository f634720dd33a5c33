"""kill -9 / resume of a tiny training at random (seeded) moments: trials lost, trials counted twice.

    python benchmarks/bench_interrupt.py [--cycles 3] [--seed 0] [--workers 2]

The tiny training of ``tests/reliability/tiny_runs.py`` (two drills, 2 sampled motions each,
training seed 4: three grasp trials) runs once uninterrupted from an empty trial cache (the
reference), then again from another empty cache: the ``catgrasp train`` command is started,
SIGKILLed with its whole process group (CLI and worker processes) after a random delay, started
again, ... ``--cycles`` times, then run to completion. Delays are drawn uniformly in 5-95 % of the
reference's wall time, from ``--seed``. Counted:

* trials lost: a trial cached before a kill that is missing, or was recomputed (its file replaced),
  afterwards;
* trials counted twice: trials the final model's statistics count beyond the distinct trial specs;
* model identical: every array bit for bit, every statistic but the wall-clock ones, as the
  reference's.
"""

from __future__ import annotations

import argparse
import random
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.reliability import tiny_runs as tiny  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=3, help="kill -9 / resume cycles")
    ap.add_argument("--seed", type=int, default=0, help="seed of the kill moments")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    rng = random.Random(args.seed)
    root = Path(tempfile.mkdtemp(prefix="bench_interrupt_"))
    try:
        ref_dir = root / "reference"
        t0 = time.perf_counter()
        tiny.Run(tiny.train_command(ref_dir / "cache", ref_dir / "model.npz", args.workers), ref_dir / "log").wait()
        t_ref = time.perf_counter() - t0
        ref_keys = {p.stem for p in tiny.cached_files(ref_dir / "cache")}
        print(f"reference (uninterrupted): {len(ref_keys)} trials, {t_ref:.1f} s")

        cache, model = root / "run" / "cache", root / "run" / "model.npz"
        cmd = tiny.train_command(cache, model, args.workers)
        runs = killed = lost = 0
        t0 = time.perf_counter()
        for cycle in range(args.cycles):
            delay = rng.uniform(0.05, 0.95) * t_ref
            before = tiny.file_ids(tiny.cached_files(cache))
            run = tiny.Run(cmd, root / "run" / f"cycle{cycle}")
            runs += 1
            deadline = time.monotonic() + delay
            while time.monotonic() < deadline and run.proc.poll() is None:
                time.sleep(0.02)
            if run.proc.poll() is not None:
                run.wait()
                print(f"cycle {cycle + 1}: finished before the kill at {delay:.1f} s")
                break
            run.kill_group()
            killed += 1
            after = tiny.file_ids(tiny.cached_files(cache))
            lost += sum(1 for k, v in before.items() if after.get(k) != v)
            print(f"cycle {cycle + 1}: kill -9 at {delay:.1f} s with {len(after)}/{len(ref_keys)} trials cached "
                  f"({len(after) - len(before)} new)")
        if not model.exists():
            before = tiny.file_ids(tiny.cached_files(cache))
            tiny.Run(cmd, root / "run" / "final").wait()
            runs += 1
            after = tiny.file_ids(tiny.cached_files(cache))
            lost += sum(1 for k, v in before.items() if after.get(k) != v)
        t_run = time.perf_counter() - t0

        keys = {p.stem for p in tiny.cached_files(cache)}
        _, header = tiny.model_contents(model)
        twice = tiny.trial_count(header["meta"]["stats"]) - len(keys)
        lost += len(ref_keys - keys)
        same = tiny.model_differences(model, ref_dir / "model.npz") == [] and keys == ref_keys
        print()
        print("| runs tried | killed (kill -9) | trials lost | trials counted twice | model identical to the "
              "uninterrupted run | wall, interrupted runs | wall, uninterrupted |")
        print("|---|---|---|---|---|---|---|")
        print(f"| {runs} | {killed} | {lost} | {twice} | {'yes' if same else 'no'} | {t_run:.1f} s | {t_ref:.1f} s |")
        return 0 if (lost == 0 and twice == 0 and same) else 1
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
