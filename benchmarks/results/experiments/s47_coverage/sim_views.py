"""Session 47: simulate chosen benchmark views, one trial each (``latent``, single view), in this process.

    python benchmarks/results/experiments/s47_coverage/sim_views.py --split val --category drill \
        --views drill_00:1 drill_00:4 [--method latent] [--data DIR] --out FILE.jsonl

Each view is the benchmark's own trial spec (``benchmark.runner.trial_specs``: placement, camera, depth noise,
seed 0), run by ``benchmark_trial_task``, so its record is what ``catgrasp benchmark`` writes for it. Run from a
git worktree of another commit (``cd W && PYTHONPATH=W python .../sim_views.py``) to get that code's record.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path.cwd()))

from catgrasp_drake.benchmark.runner import BenchmarkConfig, benchmark_trial_task, trial_specs  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", default="val")
    ap.add_argument("--category", default="drill")
    ap.add_argument("--views", nargs="+", required=True, help="INSTANCE:PLACEMENT")
    ap.add_argument("--method", default="latent")
    ap.add_argument("--data-seed", type=int, default=None)
    ap.add_argument("--data", default="out/benchmark/data")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    wanted = [(v.split(":")[0], int(v.split(":")[1])) for v in args.views]
    config = BenchmarkConfig(split=args.split, categories=(args.category,), methods=(args.method,),
                             placements=max(t for _, t in wanted) + 1, instances=tuple(sorted({i for i, _ in wanted})),
                             data_seed=args.data_seed, data_dir=args.data)
    specs = [s for s in trial_specs(config) if (s["instance"], s["trial"]) in wanted]
    with open(args.out, "w") as f:
        for spec in specs:
            record = benchmark_trial_task(spec)
            f.write(json.dumps(record) + "\n")
            f.flush()
            print(spec["instance"], spec["trial"], record["functional"], record["reason"], record["yaw_error_deg"],
                  flush=True)
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
