"""The one EM loop of CPD-style registration: rigid and non-rigid CPD, latent shape + pose inference (numpy only).

The model points, moved by the current parameters, are the centres of an isotropic Gaussian
mixture of variance ``sigma2`` (plus a uniform outlier term) that explains the targets ``X``
(N, D). One iteration of :func:`em_loop`:

1. E-step: posteriors of the targets (an :class:`~catgrasp_drake.core.cpd.EStep` record);
2. objective ``f = nll + penalty`` (``penalty``: the parameters' regulariser or prior) and the
   convergence test ``|f - f_prev| / N < tol``;
3. M-step: new parameters (an :class:`MStep` record);
4. closed-form variance (:func:`sigma2_update`), kept at or above a floor;
5. optional callback, then the floor test.

The callers differ only in what they pass: the E-step (dense, truncated, float32, over the visible
model points), the M-step (weighted Procrustes, kernel solve, latent solve), the floor and whether
reaching it stops the loop. Units are the caller's (CPD works in normalised coordinates, the
inference in metres).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class MStep:
    """Parameters after one M-step (or the starting ones).

    ``centres`` (K, D): the mixture centres of the E-step before this M-step, moved to the new
    parameters (what :func:`sigma2_update` pairs with that E-step's posteriors; at the start, the
    starting centres); ``penalty``: the objective's parameter term at the new parameters (added to
    the next E-step's ``nll``); ``params``: the caller's own parameters, passed through untouched.
    """

    centres: np.ndarray
    penalty: float = 0.0
    params: object = None


@dataclass(frozen=True)
class EMResult:
    """End of :func:`em_loop`: the last :class:`MStep` ``m`` (the start when none ran), the last E-step
    ``e`` (None when none ran), the last ``objective`` (inf when none), ``sigma2`` after the last
    M-step, ``iterations`` (M-steps done) and ``stop``: "tol" (objective converged), "floor"
    (``sigma2`` reached its floor), "no_mass" (the targets' posterior mass at most ``min_mass``:
    every target an outlier, nothing to fit) or "max_iter"."""

    m: MStep
    e: object
    objective: float
    sigma2: float
    iterations: int
    stop: str

    @property
    def converged(self) -> bool:
        return self.stop in ("tol", "floor")


def sigma2_update(X: np.ndarray, T: np.ndarray, e) -> float:
    """Closed-form variance ``sum_mn P_mn |x_n - t_m|^2 / (Np D)`` for targets ``X`` (N, D), centres ``T``
    (M, D) and the E-step ``e`` that gave the posteriors (squared units of ``X``)."""
    D = X.shape[1]
    xPx = float(e.Pt1 @ (X * X).sum(1))
    tPt = float(e.P1 @ (T * T).sum(1))
    trPXT = float((e.PX * T).sum())
    return (xPx - 2.0 * trPXT + tPt) / (e.Np * D)


def em_loop(X: np.ndarray, e_step: Callable, m_step: Callable[..., MStep], start: MStep, sigma2: float, *,
            n_iter: int, tol: float, sigma2_floor: float, stop_at_floor: bool = True, min_mass: float = 1e-300,
            k_start: int = 0, f_prev: float = math.inf,
            callback: Callable[[int, np.ndarray, float, float], object] | None = None) -> EMResult:
    """EM iterations ``k = k_start .. n_iter - 1`` on targets ``X`` (N, D) from parameters ``start``.

    ``e_step(k, m, sigma2)`` gives the E-step at parameters ``m`` (the last :class:`MStep`);
    ``m_step(e, m, sigma2)`` the next :class:`MStep`. ``sigma2`` is the starting variance; after each
    M-step it is ``max(sigma2_update(X, m.centres, e), sigma2_floor)``, and reaching the floor ends the
    loop if ``stop_at_floor``; an E-step whose posterior mass ``Np`` is at most ``min_mass`` ends it too
    (every target an outlier). ``callback(k + 1, m.centres, sigma2, f)`` after each M-step, with ``f``
    the objective of the E-step before it. ``k_start`` resumes an earlier run that stopped at ``n_iter`` =
    ``k_start``; ``f_prev``, that run's last ``objective``, makes the first convergence test the one the
    uninterrupted run would have made (left at inf, the test starts afresh: with ``tol`` 0 the same).
    """
    N = X.shape[0]
    m, e, f, done, stop = start, None, math.inf, 0, "max_iter"
    for k in range(k_start, n_iter):
        e = e_step(k, m, sigma2)
        f = e.nll + m.penalty
        if abs(f_prev - f) / N < tol:
            stop = "tol"  # (no M-step follows: m is the result)
            break
        f_prev = f
        if e.Np <= min_mass:
            stop = "no_mass"
            break
        m = m_step(e, m, sigma2)
        done += 1
        sigma2 = max(sigma2_update(X, m.centres, e), sigma2_floor)
        if callback is not None:
            callback(k + 1, m.centres, sigma2, f)
        if stop_at_floor and sigma2 <= sigma2_floor:
            stop = "floor"
            break
    return EMResult(m, e, f, sigma2, done, stop)


@dataclass(frozen=True)
class SquaremResult:
    """End of :func:`squarem`: the parameter vector ``theta``, the objective at the last evaluation,
    ``evaluations`` of the EM map, ``stop`` ("tol", "map" -- the map asked to stop, e.g. the variance at
    its floor -- or "max_evals") and ``cycles`` (extrapolations tried, ``accepted`` of them)."""

    theta: np.ndarray
    objective: float
    evaluations: int
    stop: str
    cycles: int
    accepted: int


#: SQUAREM's first bound on the step length and its growth factor (the R package ``SQUAREM``'s
#: ``step.max0``/``mstep`` are 1 and 4; a first bound of 4 saved 3 of 49 evaluations on
#: ``benchmarks/bench_cpd.py``'s 2000-point problem).
SQUAREM_STEP_MAX0 = 4.0
SQUAREM_MSTEP = 4.0


def squarem(em_map: Callable, theta0: np.ndarray, *, n_points: int, max_evals: int, tol: float) -> SquaremResult:
    """Accelerate a monotone EM map by squared extrapolation (SQUAREM, Varadhan & Roland, Scand. J.
    Stat. 2008, scheme S3, with the adaptive step bound of their R package).

    ``em_map(theta) -> (theta_next, f, stop)``: one EM step from the parameter vector ``theta``,
    the objective ``f`` AT ``theta`` (what its E-step gives), and ``stop`` (True: ``theta_next``
    is final, e.g. the variance reached its floor). A cycle from ``theta`` takes two EM steps
    (``theta1``, ``theta2``), extrapolates ``theta + 2 a r + a^2 v`` (``r = theta1 - theta``,
    ``v = theta2 - 2 theta1 + theta``, ``a = |r| / |v|`` clamped to ``[1, step_max]``) and takes one
    EM step from there; the cycle's result is kept if the objective at the extrapolated point is
    not above the one at ``theta`` (the step bound then grows 4x when it was reached), else the
    plain ``theta2`` (and the bound shrinks 4x). The convergence test is the EM loop's,
    ``|f - f_prev| / n_points < tol``, between consecutive evaluations.
    """
    evals, cycles, accepted = 0, 0, 0
    step_max = SQUAREM_STEP_MAX0
    theta = np.asarray(theta0, float)
    f_prev = math.inf

    def step(t):
        nonlocal evals
        evals += 1
        return em_map(t)

    while True:
        if evals >= max_evals:
            return SquaremResult(theta, f_prev, evals, "max_evals", cycles, accepted)
        theta1, f0, stop = step(theta)
        if abs(f_prev - f0) / n_points < tol:
            return SquaremResult(theta, f0, evals, "tol", cycles, accepted)
        if stop or evals >= max_evals:
            return SquaremResult(theta1, f0, evals, "map" if stop else "max_evals", cycles, accepted)
        theta2, f1, stop = step(theta1)
        if abs(f0 - f1) / n_points < tol:
            return SquaremResult(theta1, f1, evals, "tol", cycles, accepted)
        if stop or evals >= max_evals:
            return SquaremResult(theta2, f1, evals, "map" if stop else "max_evals", cycles, accepted)
        r = theta1 - theta
        v = theta2 - 2.0 * theta1 + theta
        vv = float(v @ v)
        a = math.sqrt(float(r @ r) / vv) if vv > 0.0 else 1.0
        a = max(1.0, min(step_max, a))
        cycles += 1
        theta3, fp, stop = step(theta + 2.0 * a * r + a * a * v)
        if math.isfinite(fp) and fp <= f0:
            accepted += 1
            theta, f_prev = theta3, fp
            if a == step_max:
                step_max *= SQUAREM_MSTEP
        else:
            theta, f_prev = theta2, f1
            step_max = max(1.0, step_max / SQUAREM_MSTEP)
            stop = False
        if stop:
            return SquaremResult(theta, f_prev, evals, "map", cycles, accepted)
