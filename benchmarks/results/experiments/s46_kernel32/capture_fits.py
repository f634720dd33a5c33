"""Capture the shape estimator's fit inputs in the product's diagram (for squarem_probe.py; scratch, issue 17).

    python benchmarks/results/experiments/s46_kernel32/capture_fits.py CATEGORY OUT.pkl

Runs ``benchmarks/bench_transfer.py --category CATEGORY --seeds 1 --settings new`` and pickles the
``(args, kwargs)`` of every ``infer_latent_pose`` call the estimator makes (2 held-out views).
"""

import pickle
import runpy
import sys

import catgrasp_drake.core.inference as inference
import catgrasp_drake.systems.shape_estimator as shape_estimator


def main():
    category, out = sys.argv[1], sys.argv[2]
    calls = []

    def recording(*args, **kwargs):
        calls.append((args, kwargs))
        return inference.infer_latent_pose(*args, **kwargs)

    shape_estimator.infer_latent_pose = recording
    sys.argv = ["bench_transfer.py", "--category", category, "--seeds", "1", "--settings", "new"]
    try:
        runpy.run_path("benchmarks/bench_transfer.py", run_name="__main__")
    except SystemExit:
        pass
    with open(out, "wb") as f:
        pickle.dump(calls, f)


if __name__ == "__main__":
    main()
