"""Session 18 experiment (needs local_fit.diff applied: git apply): for benchmark records, where the executed
grasp's functional point, the fitted trigger and the true trigger are (mm, object frame of the TRUE pose).
No simulation.

    python benchmarks/results/experiments/s18_local_fit/functional_point_diag.py RECORDS.jsonl [METHOD]
"""

import json
import sys

import numpy as np

from catgrasp_drake.benchmark.runner import _model, spec_from_record, trial_scenario
from catgrasp_drake.data.dataset import read_annotations
from catgrasp_drake.data.importer import canonical_annotations
from catgrasp_drake.prediction import functional_part_indices
from catgrasp_drake.transfer import make_transfer_diagram


def main(path, method="latent"):
    for line in open(path).readlines()[1:]:
        r = json.loads(line)
        if r["method"] != method:
            continue
        spec = spec_from_record(r)
        model = _model(spec["_model"], spec["category"])
        scenario, _, _ = trial_scenario(spec)
        td = make_transfer_diagram(scenario, model, view=spec["view"], method=spec["method"], min_confidence=0.0)
        ctx = td.diagram.CreateDefaultContext()
        est_ctx = td.estimator.GetMyMutableContextFromRoot(ctx)
        td.estimator.set_estimate(est_ctx, td.estimator.estimate_now(est_ctx))
        c = td.regressor.GetOutputPort("grasp_candidates_W").Eval(td.regressor.GetMyContextFromRoot(ctx))[0]
        idx = functional_part_indices(model, canonical_annotations(model))
        X_OW = np.linalg.inv(scenario.X_WO())
        true_c = np.asarray(read_annotations(f"{spec['model_dir']}/annotations.json")["regions"]["trigger"]["center"])
        fp = X_OW[:3, :3] @ c.functional_point_W + X_OW[:3, 3]
        part = X_OW[:3, :3] @ c.object_points_W[idx].mean(0) + X_OW[:3, 3]
        verdict = "F" if r["functional"] else r["reason"][:8]
        print(f"{r['instance']} t{r['trial']} {verdict:8s} fp-true {np.round(1000 * (fp - true_c), 1)} "
              f"part-true {np.round(1000 * (part - true_c), 1)} fp-part {np.round(1000 * (fp - part), 1)} "
              f"shift {np.round(1000 * c.local_shift_W, 1)}", flush=True)


if __name__ == "__main__":
    main(*sys.argv[1:3])
