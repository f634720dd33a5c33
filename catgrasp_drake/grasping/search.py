"""Cross-entropy search for the best parameters of a noisy, expensive objective (pure numpy).

Used to search grasps (``catgrasp_drake.grasp_search``): a candidate is a
vector of grasp-variation parameters, its score the robustness measured by
simulated trials. The objective is evaluated in batches -- one call per round
with every candidate of the round -- so that the caller can run the trials in
parallel (local workers or Ray).

Each round draws ``population`` candidates from a diagonal Gaussian
(clipped to ``lower``/``upper``; the round-0 population holds the mean itself
as its first candidate, so the start is always measured), scores them,
and refits the Gaussian to the ``elite`` best (with smoothing ``alpha`` and a
floor ``min_std`` so the search does not collapse on a noisy score). The
best candidate over all rounds is returned with its score, so the result is
never worse than the start as measured. Seeded: the same inputs and ``seed``
give the same candidates.

With a cheap ``feasible`` test (e.g. a kinematic screen of a grasp on many
objects), each round's population is filled by rejection: candidates are
drawn in batches of ``draw_batch``, the infeasible ones are dropped and drawn
again, up to ``max_draws`` per round; only then, if the population is still
short, are the first infeasible draws kept (the caller scores them). So the
expensive objective is spent on candidates that pass the test, and the elite
are refitted from a full population.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from catgrasp_drake.errors import InputError


@dataclass(frozen=True)
class CemParams:
    """Cross-entropy method settings."""

    rounds: int = 4
    population: int = 12
    elite: int = 3
    alpha: float = 0.7  # weight of the elite fit in the new mean/std (1: no smoothing)
    min_std_fraction: float = 0.1  # std floor, as a fraction of the initial std
    seed: int = 0

    def __post_init__(self):
        for name in ("rounds", "population", "elite"):
            value = getattr(self, name)
            if not (isinstance(value, (int, np.integer)) and value >= 1):
                raise InputError(f"{name}: expected a positive integer, got {value!r}")
        if self.elite > self.population:
            raise InputError(f"elite: {self.elite} is more than the population {self.population}")
        if not 0.0 < self.alpha <= 1.0:
            raise InputError(f"alpha: expected a value in (0, 1], got {self.alpha}")
        if not 0.0 <= self.min_std_fraction <= 1.0:
            raise InputError(f"min_std_fraction: expected a value in [0, 1], got {self.min_std_fraction}")


@dataclass
class CemResult:
    """The best candidate, its score, and every round's candidates and scores."""

    best: np.ndarray
    best_score: float
    mean: np.ndarray  # the final sampling distribution
    std: np.ndarray
    candidates: list = field(default_factory=list)  # per round: (population, d)
    scores: list = field(default_factory=list)  # per round: (population,)
    draws: list = field(default_factory=list)  # per round, with a feasibility test: {"drawn": n, "infeasible": m}

    @property
    def evaluations(self) -> int:
        return int(sum(len(s) for s in self.scores))


def _vector(value, d: int | None, name: str) -> np.ndarray:
    try:
        a = np.array(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected numbers") from None
    if d is not None and a.shape != (d,):
        raise InputError(f"{name}: expected {d} values, got {a.size}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: contains NaN or inf")
    return a


class CemSearch:
    """The cross-entropy method as ask/tell (module docstring), so several searches can share one batch of
    trials: ``X = search.ask()`` gives the round's candidates (population, d), ``search.tell(scores)``
    refits the Gaussian; ``search.result`` holds the best candidate and every round so far."""

    def __init__(self, mean, std, *, lower=None, upper=None, params: CemParams = CemParams()):
        mean = _vector(mean, None, "mean")
        d = mean.size
        std = _vector(std, d, "std")
        if np.any(std < 0):
            raise InputError("std: expected non-negative values")
        self.lower = np.full(d, -np.inf) if lower is None else _vector(lower, d, "lower")
        self.upper = np.full(d, np.inf) if upper is None else _vector(upper, d, "upper")
        if np.any(self.lower > self.upper) or np.any(mean < self.lower) or np.any(mean > self.upper):
            raise InputError("lower/upper: the bounds must hold the mean (lower <= mean <= upper)")
        self.params = params
        self._start = mean
        self._rng = np.random.default_rng(params.seed)
        self._floor = params.min_std_fraction * std
        self._pending: np.ndarray | None = None
        self.result = CemResult(best=mean.copy(), best_score=-np.inf, mean=mean.copy(), std=std.copy())

    @property
    def round(self) -> int:
        """Rounds told so far."""
        return len(self.result.scores)

    @property
    def done(self) -> bool:
        return self.round >= self.params.rounds

    def _draw(self, n: int) -> np.ndarray:
        r = self.result
        return np.clip(r.mean + r.std * self._rng.standard_normal((n, r.mean.size)), self.lower, self.upper)

    def ask(self, feasible: Callable[[np.ndarray], np.ndarray] | None = None, *, draw_batch: int | None = None,
            max_draws: int | None = None) -> np.ndarray:
        """This round's candidates (population, d); the first round's first candidate is the start.

        ``feasible(X (K, d)) -> (K,) bool``: fill the population by rejection (module docstring), drawing
        ``draw_batch`` candidates at a time (default 4 x population) and at most ``max_draws`` per round
        (default 40 x population). The start is kept whatever its test says: it is the reference.
        """
        if self.done:
            raise InputError(f"the search has run its {self.params.rounds} rounds")
        if self._pending is None:
            p = self.params
            if feasible is None:
                X = self._draw(p.population)
                if self.round == 0:
                    X[0] = self._start
            else:
                X = self._draw_feasible(feasible, draw_batch or 4 * p.population, max_draws or 40 * p.population)
            self._pending = X
        return self._pending.copy()

    def _draw_feasible(self, feasible, draw_batch: int, max_draws: int) -> np.ndarray:
        p = self.params
        kept = [self._start] if self.round == 0 else []
        refused, drawn = [], 0
        while len(kept) < p.population and drawn < max_draws:
            B = self._draw(min(draw_batch, max_draws - drawn))
            ok = np.asarray(feasible(B.copy()), dtype=bool).reshape(-1)
            if ok.shape != (len(B),):
                raise InputError(f"feasible(...): expected {len(B)} booleans, got {ok.size}")
            drawn += len(B)
            kept.extend(B[ok])
            refused.extend(B[~ok])
        self.result.draws.append({"drawn": drawn, "infeasible": len(refused)})
        return np.array((kept + refused)[:p.population])

    def tell(self, scores) -> None:
        """Score this round's candidates (population,) and refit the sampling Gaussian to the elite."""
        if self._pending is None:
            raise InputError("tell: ask for the round's candidates first")
        X, p, r = self._pending, self.params, self.result
        scores = _vector(scores, p.population, "evaluate(...) scores")
        self._pending = None
        r.candidates.append(X)
        r.scores.append(scores)
        i = int(np.argmax(scores))  # first of the ties: the start wins a tie in round 0
        if scores[i] > r.best_score:
            r.best, r.best_score = X[i].copy(), float(scores[i])
        elite = X[np.argsort(-scores, kind="stable")[:p.elite]]
        a = p.alpha
        r.mean = a * elite.mean(axis=0) + (1 - a) * r.mean
        r.std = np.maximum(a * elite.std(axis=0) + (1 - a) * r.std, self._floor)


def cem_maximize(evaluate: Callable[[np.ndarray], np.ndarray], mean, std, *, lower=None, upper=None,
                 params: CemParams = CemParams(), on_round: Callable | None = None,
                 feasible: Callable[[np.ndarray], np.ndarray] | None = None, draw_batch: int | None = None,
                 max_draws: int | None = None) -> CemResult:
    """Maximise ``evaluate`` by the cross-entropy method (module docstring).

    ``evaluate(candidates (K, d)) -> scores (K,)``; ``mean``/``std`` (d,)
    the initial Gaussian; ``lower``/``upper`` (d,) optional bounds.
    ``on_round(round_index, candidates, scores)`` is called after every
    round (progress, checkpoints). ``feasible``, ``draw_batch``, ``max_draws``: the population filled by
    rejection (:meth:`CemSearch.ask`). Returns a :class:`CemResult`.
    """
    search = CemSearch(mean, std, lower=lower, upper=upper, params=params)
    while not search.done:
        k = search.round
        X = search.ask(feasible, draw_batch=draw_batch, max_draws=max_draws)
        search.tell(evaluate(X.copy()))
        if on_round is not None:
            on_round(k, X, search.result.scores[-1])
    return search.result
