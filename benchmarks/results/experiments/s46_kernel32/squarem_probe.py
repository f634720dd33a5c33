"""SQUAREM on the latent fit's refine against plain EM, on the diagram's own fits (a scratch probe, not the library).

    python benchmarks/results/experiments/s46_kernel32/squarem_probe.py CATEGORY em|sq

First runs ``benchmarks/bench_transfer.py --category CATEGORY --seeds 1 --settings new`` and keeps the
``(args, kwargs)`` of every ``infer_latent_pose`` call its shape estimator makes (2 held-out views); then fits
each of them again, with the refine as below.

The refine's EM (``core.inference._Problem.run`` with ``tol`` > 0) is replaced by ``core.em.squarem`` over
theta = (x, rotation vector about the start's rotation, t, log s, log sigma2), the visibility updated on the
same schedule (every 4 evaluations, not while the model moved < 2 mm). Every hypothesis refined to the end
(``drop_energy=None``), at most 40 and 80 evaluations. Prints the median time of 3 runs, final energies,
evaluations, convergence, the MAP fit's yaw and scale.
"""

import math
import runpy
import sys
import time

import numpy as np
from scipy.spatial.transform import Rotation

import catgrasp_drake.core.inference as inference
import catgrasp_drake.systems.shape_estimator as shape_estimator
from catgrasp_drake.core.cpd import estep
from catgrasp_drake.core.em import sigma2_update, squarem
from catgrasp_drake.core.rotations import rotz

#: Each fit timed this many times (the median is printed).
REPEATS = 3


def refine_by_squarem(prob, st, O, n_iter, tol, vis_every=1, vis_move=0.0, kernel32=False, **_):
    q, R_ref = prob.q, st.R.copy()
    T0 = prob.fit(st.x, st.R, st.t, st.s).T
    vis = prob.visible(T0) if st.visible is None else st.visible
    T_vis, evals = T0, [0]

    def pack(x, R, t, s, s2):
        return np.concatenate([x, Rotation.from_matrix(R_ref.T @ R).as_rotvec(), t, [math.log(s), math.log(s2)]])

    def unpack(th):
        R = R_ref @ Rotation.from_rotvec(th[q:q + 3]).as_matrix()
        if prob.upright:
            R = rotz(math.atan2(R[1, 0], R[0, 0]))
        s = float(np.clip(math.exp(th[q + 6]), *prob.scale_bounds))
        return th[:q], R, th[q + 3:q + 6], s, max(math.exp(th[q + 7]), inference.SIGMA2_MIN_M2)

    def em_map(th):
        nonlocal vis, T_vis
        x, R, t, s, s2 = unpack(th)
        fit = prob.fit(x, R, t, s)
        k, evals[0] = evals[0], evals[0] + 1
        if k > 0 and vis_every and k % vis_every == 0 and float(np.abs(fit.T - T_vis).max()) >= vis_move:
            vis, T_vis = prob.visible(fit.T), fit.T
        idx = np.flatnonzero(vis)
        e = estep(fit.T[idx], O, s2, prob.w, log_uniform=prob.log_uniform(len(idx), s2), kernel32=kernel32)
        new = prob.mstep(e, idx, fit, O, s2)
        s2_new = max(sigma2_update(O, new.T[idx], e), inference.SIGMA2_MIN_M2)
        return pack(new.x, new.R, new.t, new.s, s2_new), e.nll + 0.5 * prob.prior * float(x @ x), False

    r = squarem(em_map, pack(st.x, st.R, st.t, st.s, st.sigma2), n_points=len(O), max_evals=n_iter, tol=tol)
    st.x, st.R, st.t, st.s, st.sigma2 = unpack(r.theta)
    st.energy, st.iterations = r.objective, st.iterations + r.evaluations
    st.converged = st.converged or r.stop == "tol"
    st.visible, st.T_visible = vis, T_vis
    return st


def diagram_fits(category):
    """The ``(args, kwargs)`` of the shape estimator's fits in ``bench_transfer.py`` (one placement per view)."""
    calls = []

    def recording(*args, **kwargs):
        calls.append((args, kwargs))
        return inference.infer_latent_pose(*args, **kwargs)

    shape_estimator.infer_latent_pose, argv = recording, sys.argv
    sys.argv = ["bench_transfer.py", "--category", category, "--seeds", "1", "--settings", "new"]
    try:
        runpy.run_path("benchmarks/bench_transfer.py", run_name="__main__")
    except SystemExit:
        pass
    finally:
        shape_estimator.infer_latent_pose, sys.argv = inference.infer_latent_pose, argv
    return calls


def main():
    category, mode = sys.argv[1], sys.argv[2]
    calls = diagram_fits(category)
    plain = inference._Problem.run

    def run(self, st, O, n_iter, tol, **kw):
        if tol > 0 and mode == "sq":  # the refine (the search runs with tol 0)
            return refine_by_squarem(self, st, O, n_iter, tol, **kw)
        return plain(self, st, O, n_iter, tol, **kw)

    inference._Problem.run = run
    for args, kwargs in calls:
        for max_iter in (40, 80):
            times = []
            for _ in range(REPEATS):
                t = time.perf_counter()
                r = inference.infer_latent_pose(*args, **{**kwargs, "drop_energy": None, "max_iter": max_iter})
                times.append(time.perf_counter() - t)
            print(mode, max_iter, f"{1000 * float(np.median(times)):.0f} ms",
                  "energies", [round(h.energy, 2) for h in r.hypotheses],
                  "evaluations", [h.iterations for h in r.hypotheses], "converged", [h.converged for h in r.hypotheses],
                  "yaw", round(math.degrees(r.yaw), 1), "scale", round(r.s, 4))


if __name__ == "__main__":
    main()
