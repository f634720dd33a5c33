"""Non-rigid CPD speed and accuracy: catgrasp_drake vs pycpd 2.0.0 vs probreg, identical data and parameters.

Data (seeded): M = N points filling a drill-sized box (0.06 x 0.12 x 0.18 m),
the target is the source moved by a known smooth deformation
(``G(source, ctrl; 0.05 m) A``, 12 random control points, the same field at
every size) plus
0.5 mm Gaussian noise, and shuffled. All data
are pre-normalised with catgrasp's joint normalisation (so its internal
normalisation is the identity and every library sees the same numbers), then
every method runs exactly ``--iters`` EM iterations (tolerance 0: identical
work; the three libraries use different stopping rules; pycpd also stops
when sigma2 stops changing exactly, hence the per-iteration column) with the same
kernel width beta (probreg's ``beta`` is the squared width: it gets beta^2),
lambda (pycpd's alpha, probreg's lmd), w and initial sigma2 rule.
Error = RMS distance between the registered source points and their known
ground-truth positions (relative to the RMS displacement).

Also reported: catgrasp with its own stopping rule (objective change per
point < 1e-5) and the peak memory of one CPD run at the largest size
(tracemalloc: numpy allocations).

Run:  python benchmarks/bench_cpd.py --sizes 500 1000 2000 4000
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from catgrasp_drake.core.cpd import joint_normalization, nonrigid_cpd  # noqa: E402
from catgrasp_drake.core.kernels import gaussian_kernel  # noqa: E402

BETA, LAM, W = 0.7, 5.0, 0.01  # normalised units (data RMS radius 1; 0.7 ~ the true field's 0.05 m)


def make_problem(n, seed=0):
    lo, hi = np.array([-0.03, -0.06, 0.0]), np.array([0.03, 0.06, 0.18])
    field = np.random.default_rng(seed)  # the same deformation field at every size
    ctrl = field.uniform(lo, hi, size=(12, 3))
    A = field.normal(scale=0.01, size=(12, 3))
    rng = np.random.default_rng(seed + n)
    Y = rng.uniform(lo, hi, size=(n, 3))
    X = Y + gaussian_kernel(Y, ctrl, 0.05) @ A
    noisy = X + rng.normal(scale=5e-4, size=X.shape)  # 0.5 mm sensor noise (keeps sigma2 > 0 for pycpd)
    perm = rng.permutation(n)  # the target's order carries no correspondence
    c, s = joint_normalization(Y, noisy)
    Yn, Xn, gt = (Y - c) / s, (noisy - c) / s, (X - c) / s
    return Yn, Xn[perm], gt  # source, target (shuffled), noise-free ground truth of each source point


def run_ours(Y, X, iters, low_rank, tol=0.0):
    r = nonrigid_cpd(Y, X, beta=BETA, lam=LAM, w=W, max_iter=iters, tol=tol, low_rank=low_rank)
    return r.transformed, r.iterations, r.rank


def run_pycpd(Y, X, iters):
    from pycpd import DeformableRegistration

    reg = DeformableRegistration(X=X, Y=Y, alpha=LAM, beta=BETA, w=W, max_iterations=iters, tolerance=0.0)
    TY, _ = reg.register()
    return TY, reg.iteration, len(Y)


def run_probreg(Y, X, iters):
    from probreg import cpd

    # probreg's kernel is exp(-|d|^2 / (2 beta)): its "beta" is the squared width
    reg = cpd.NonRigidCPD(Y, beta=BETA**2, lmd=LAM, use_cuda=False)
    res = reg.registration(X, w=W, maxiter=iters, tol=-1.0)  # tol < 0: never stops early
    return res.transformation.transform(Y), iters, len(Y)


def timed(fn, *a, repeat=1):
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn(*a)
        dt = time.perf_counter() - t0
        best = dt if best is None or dt < best else best
    return out, best


def peak_mb(fn, *a):
    tracemalloc.start()
    tracemalloc.reset_peak()
    fn(*a)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[500, 1000, 2000, 4000])
    ap.add_argument("--iters", type=int, default=100)
    ap.add_argument("--max-reference-size", type=int, default=4000,
                    help="skip pycpd/probreg above this size (they take minutes at 4000)")
    ap.add_argument("--no-memory", action="store_true")
    args = ap.parse_args(argv)
    print(f"Non-rigid CPD, M = N, {args.iters} EM iterations for every method, beta={BETA} lambda={LAM} w={W} "
          f"(normalised units), {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}")
    print()
    print("| M = N | method | time (s) | iterations | ms / iteration | kernel rank | RMS error / RMS displacement | "
          "speed-up vs pycpd (total) | speed-up vs pycpd (per iteration) | RMS / pycpd's RMS |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n in args.sizes:
        Y, X, gt = make_problem(n)
        disp = np.sqrt(((gt - Y) ** 2).sum(1).mean())
        rows = []
        methods = [("catgrasp, low-rank auto", lambda: run_ours(Y, X, args.iters, "auto")),
                   ("catgrasp, exact kernel", lambda: run_ours(Y, X, args.iters, None))]
        if n <= args.max_reference_size:
            methods += [("pycpd 2.0.0", lambda: run_pycpd(Y, X, args.iters)),
                        ("probreg 0.3.8", lambda: run_probreg(Y, X, args.iters))]
        methods.append(("catgrasp, low-rank auto, own stopping rule (tol 1e-5)",
                        lambda: run_ours(Y, X, args.iters, "auto", tol=1e-5)))
        for name, fn in methods:
            if name.startswith("catgrasp, exact") and n > 2000:
                continue  # O(M^3) per iteration: shown up to 2000
            try:
                (T, it, rank), dt = timed(fn)
            except ImportError as e:
                print(f"| {n} | {name} | skipped ({e}) | | | | | | | |")
                continue
            rms = np.sqrt(((T - gt) ** 2).sum(1).mean()) / disp
            rows.append((name, dt, it, rank, rms))
        ref = next((r for r in rows if r[0].startswith("pycpd")), None)
        for name, dt, it, rank, rms in rows:
            sp = f"{ref[1] / dt:.1f}x" if ref else "-"
            spi = f"{(ref[1] / ref[2]) / (dt / it):.1f}x" if ref else "-"
            rr = f"{rms / ref[4]:.3f}" if ref else "-"
            print(f"| {n} | {name} | {dt:.3f} | {it} | {1e3 * dt / it:.1f} | {rank} | {rms:.4f} | {sp} | {spi} "
                  f"| {rr} |")
    if not args.no_memory:
        n = max(args.sizes)
        Y, X, _ = make_problem(n)
        print()
        print(f"Peak memory of one CPD run at M = N = {n} (tracemalloc, numpy arrays; {args.iters} iterations):")
        print()
        print("| method | peak (MiB) |")
        print("|---|---|")
        print(f"| catgrasp, low-rank auto | {peak_mb(run_ours, Y, X, args.iters, 'auto'):.0f} |")
        if n <= 2000:
            print(f"| catgrasp, exact kernel | {peak_mb(run_ours, Y, X, args.iters, None):.0f} |")
        if n <= args.max_reference_size:
            try:
                print(f"| pycpd 2.0.0 (5 iterations) | {peak_mb(run_pycpd, Y, X, 5):.0f} |")
            except ImportError:
                pass


if __name__ == "__main__":
    main()
