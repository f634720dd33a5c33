"""Grasp trials per second: local worker processes vs a local Ray cluster, same task function, same specs.

    python benchmarks/bench_scaleout.py [--trials 8] [--workers 2]

The specs are the hand-written drill grasp anchored on ``--trials`` drills
(``training.grasp_trial_task``, the task that training runs). Each backend
starts from an empty cache; Ray's time includes starting the local head.
Also prints the outcomes of both runs so equality can be checked by eye (the
test ``tests/runner/test_ray.py`` asserts it).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.data.dataset import list_instances  # noqa: E402
from catgrasp_drake.runner import run_tasks  # noqa: E402
from catgrasp_drake.station.handwritten import load_handwritten_motion  # noqa: E402
from catgrasp_drake.training import grasp_trial_task  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=8)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    names = list_instances("drill")[: args.trials]
    specs = [{"task": "grasp_trial", "scenario": "drill_default", "category": "drill", "instance": n,
              "motion": load_handwritten_motion("drill", n).to_dict()} for n in names]
    rows = []
    for backend in ("local", "ray"):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            if backend == "local":
                out = run_tasks(grasp_trial_task, specs, cache_dir=tmp, code_version="bench", workers=args.workers)
            else:
                import ray

                ray.init(num_cpus=args.workers, include_dashboard=False, log_to_driver=False,
                         _node_ip_address="127.0.0.1")
                try:
                    out = run_tasks(grasp_trial_task, specs, cache_dir=tmp, code_version="bench",
                                    ray_address="local")
                finally:
                    ray.shutdown()
            dt = time.perf_counter() - t0
        sim = sum(o.result.get("sim_time_s", 0.0) for o in out)
        rows.append((backend, len(out), dt, len(out) / dt, sim))
        print(f"{backend}: " + ", ".join(f"{o.spec['instance']}={o.result.get('failure_reason') or 'ok'}"
                                         for o in out))
    print(f"\n| backend ({args.workers} cores) | trials | wall | trials/s | simulated s per wall s |")
    print("|---|---|---|---|---|")
    for backend, n, dt, rate, sim in rows:
        print(f"| {backend} | {n} | {dt:.1f} s | {rate:.2f} | {sim / dt:.2f} |")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
