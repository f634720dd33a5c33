"""The cross-entropy search on cheap objectives with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.search import CemParams, CemSearch, cem_maximize


def _noisy_peak(target, noise, seed=1):
    rng = np.random.default_rng(seed)
    calls = []

    def evaluate(X):
        calls.append(len(X))
        return -np.sum((X - target) ** 2, axis=1) + noise * rng.standard_normal(len(X))

    return evaluate, calls


def test_cem_finds_the_peak_of_a_noisy_quadratic_and_never_returns_worse_than_the_start():
    target = np.array([0.3, -0.2, 0.05])
    evaluate, calls = _noisy_peak(target, noise=0.002)
    result = cem_maximize(evaluate, np.zeros(3), np.full(3, 0.3), params=CemParams(rounds=12, population=20,
                                                                                    elite=5, seed=4))
    assert np.linalg.norm(result.best - target) < 0.08
    assert np.linalg.norm(result.mean - target) < 0.08
    assert result.best_score >= result.scores[0][0]  # the start (candidate 0 of round 0) is measured
    np.testing.assert_array_equal(result.candidates[0][0], np.zeros(3))
    assert calls == [20] * 12 and result.evaluations == 240  # one batch per round


def test_cem_is_seeded_respects_bounds_and_frozen_parameters():
    evaluate, _ = _noisy_peak(np.array([2.0, 2.0]), noise=0.0)
    p = CemParams(rounds=5, population=8, elite=2, seed=7)
    a = cem_maximize(evaluate, [0.0, 0.0], [1.0, 0.0], lower=[-0.5, -1.0], upper=[0.5, 1.0], params=p)
    b = cem_maximize(evaluate, [0.0, 0.0], [1.0, 0.0], lower=[-0.5, -1.0], upper=[0.5, 1.0], params=p)
    for x, y in zip(a.candidates, b.candidates):
        np.testing.assert_array_equal(x, y)
    every = np.concatenate(a.candidates)
    assert every[:, 0].max() <= 0.5 and every[:, 0].min() >= -0.5
    assert np.all(every[:, 1] == 0.0)  # std 0 freezes a parameter
    assert a.best[0] == pytest.approx(0.5)  # the peak lies outside the bounds: the bound is the answer


def test_cem_rejects_bad_settings_in_one_line():
    f, _ = _noisy_peak(np.zeros(2), 0.0)
    with pytest.raises(InputError, match="elite"):
        CemParams(population=3, elite=4)
    with pytest.raises(InputError, match="bounds"):
        cem_maximize(f, [0.0, 0.0], [1.0, 1.0], lower=[0.5, 0.0])
    with pytest.raises(InputError, match="std"):
        cem_maximize(f, [0.0, 0.0], [1.0, np.nan])
    with pytest.raises(InputError, match="scores"):
        cem_maximize(lambda X: np.zeros(len(X) + 1), [0.0, 0.0], [1.0, 1.0])


def test_ask_and_tell_is_the_same_search_as_cem_maximize():
    def evaluate(X):
        return -np.sum((X - [0.3, -0.2]) ** 2, axis=1)

    p = CemParams(rounds=4, population=6, elite=2, seed=5)
    reference = cem_maximize(evaluate, [0.0, 0.0], [0.5, 0.5], params=p)
    search = CemSearch([0.0, 0.0], [0.5, 0.5], params=p)
    while not search.done:
        X = search.ask()
        np.testing.assert_array_equal(search.ask(), X)  # asking twice gives the same round
        search.tell(evaluate(X))
    for a, b in zip(search.result.candidates, reference.candidates):
        np.testing.assert_array_equal(a, b)
    assert search.result.best_score == reference.best_score
    with pytest.raises(InputError, match="rounds"):
        search.ask()
    with pytest.raises(InputError, match="ask"):
        CemSearch([0.0], [1.0], params=p).tell([0.0] * 6)


def test_a_feasibility_test_fills_every_round_with_feasible_candidates_and_finds_the_constrained_peak():
    target = np.array([0.6, 0.0])  # the peak lies in the infeasible half x0 > 0.3: the answer is on its edge
    evaluate, calls = _noisy_peak(target, noise=0.0)
    tested = []

    def feasible(X):
        tested.append(len(X))
        return X[:, 0] <= 0.3

    p = CemParams(rounds=8, population=10, elite=3, seed=2)
    result = cem_maximize(evaluate, [0.0, 0.0], [0.4, 0.4], params=p, feasible=feasible, draw_batch=7)
    every = np.concatenate(result.candidates)
    assert calls == [10] * 8 and np.all(every[:, 0] <= 0.3)  # full rounds, only feasible candidates
    assert result.best[0] == pytest.approx(0.3, abs=0.03) and abs(result.best[1]) < 0.05
    assert set(tested) <= {7} and sum(tested) == sum(d["drawn"] for d in result.draws)
    assert all(d["infeasible"] < d["drawn"] for d in result.draws) and sum(d["infeasible"] for d in result.draws) > 0
    # unconstrained, the same search goes past the edge
    free = cem_maximize(evaluate, [0.0, 0.0], [0.4, 0.4], params=p)
    assert free.best[0] > 0.45 and free.draws == []
    # nothing feasible: after max_draws the round keeps the start and the first refused draws
    none = cem_maximize(evaluate, [0.0, 0.0], [0.4, 0.4], params=CemParams(rounds=1, population=4, elite=1),
                        feasible=lambda X: np.zeros(len(X), bool), max_draws=9, draw_batch=4)
    assert none.draws == [{"drawn": 9, "infeasible": 9}] and len(none.candidates[0]) == 4
    np.testing.assert_array_equal(none.candidates[0][0], [0.0, 0.0])
    with pytest.raises(InputError, match="booleans"):
        cem_maximize(evaluate, [0.0, 0.0], [0.4, 0.4], feasible=lambda X: np.ones(len(X) + 1, bool))
