"""Which benchmark failures are fits the wrong way round? Re-estimates each trial's pose (no simulation).

    python benchmarks/diagnose_yaw.py --category mug [--records benchmarks/results/test_mug.jsonl]
                                      [--method latent_map] [--threshold 20]

For every trial of ``--method`` in the records file (test split), the trial's
scenario (placement, camera, depth noise) is rebuilt from the benchmark's
seeded specs, the method's estimator is run once (the transfer diagram's,
without planning or simulation), and the signed yaw error of the fit
(``benchmark.runner.yaw_error_deg``) is printed beside the recorded outcome.
A measurement of the test split, not a tuning step. Prints how many failures
have ``|yaw error| >= --threshold`` deg.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.benchmark.report import load_benchmark_records  # noqa: E402
from catgrasp_drake.benchmark.runner import (  # noqa: E402
    BenchmarkConfig,
    _model,
    trial_scenario,
    trial_specs,
    yaw_error_deg,
)
from catgrasp_drake.transfer import make_transfer_diagram  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--category", required=True)
    ap.add_argument("--records", help="default: benchmarks/results/test_<category>.jsonl")
    ap.add_argument("--method", default="latent_map")
    ap.add_argument("--threshold", type=float, default=20.0)
    args = ap.parse_args(argv)
    path = args.records or f"benchmarks/results/test_{args.category}.jsonl"
    recorded = {(r["instance"], r["trial"]): r for r in load_benchmark_records(path)
                if r["method"] == args.method and r["category"] == args.category}
    config = BenchmarkConfig(categories=(args.category,), methods=(args.method,), workers=0)
    failures = wrong = 0
    for spec in trial_specs(config):
        r = recorded.get((spec["instance"], spec["trial"]))
        if r is None:
            continue
        scenario, _, _ = trial_scenario(spec)
        td = make_transfer_diagram(scenario, _model(spec["_model"], spec["category"]), view=spec["view"],
                                   method=spec["method"])
        context = td.estimator.GetMyMutableContextFromRoot(td.diagram.CreateDefaultContext())
        estimate = td.estimator.estimate_now(context)
        yaw = yaw_error_deg(estimate.X_WO, scenario.X_WO())
        if not r["functional"]:
            failures += 1
            wrong += abs(yaw) >= args.threshold
        print(f"{spec['instance']} trial {spec['trial']}: yaw error {yaw:7.1f} deg, "
              f"{'functional' if r['functional'] else r['reason']}")
    print(f"{args.method}: {wrong} of {failures} failures with |yaw error| >= {args.threshold:g} deg")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
