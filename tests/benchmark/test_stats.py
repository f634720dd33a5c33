"""Known answers of the benchmark's bootstrap statistics (instance resampling, strata, pairing)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from catgrasp_drake.benchmark.stats import (
    PAIR_KEY,
    bootstrap_rate,
    pair_records,
    paired_bootstrap,
    paired_bootstrap_difference,
)
from catgrasp_drake.errors import InputError


def _bernoulli_trials(rng, rates, trials):
    """Instances with the given per-instance success probabilities, ``trials`` independent trials each."""
    instances = np.repeat(np.arange(len(rates)), trials)
    successes = rng.random(len(instances)) < np.repeat(rates, trials)
    return instances, successes


def test_interval_covers_a_known_rate():
    rng = np.random.default_rng(7)
    instances, successes = _bernoulli_trials(rng, np.full(40, 0.6), 5)
    rate, low, high = bootstrap_rate(instances, successes)
    assert low <= 0.6 <= high and low < rate < high
    assert high - low < 0.3
    # and over many seeded data sets the 95 % interval covers the true rate about 95 % of the time
    covered = []
    for k in range(100):
        inst, s = _bernoulli_trials(np.random.default_rng(100 + k), np.full(40, 0.6), 5)
        _, lo, hi = bootstrap_rate(inst, s, n_boot=500, seed=k)
        covered.append(lo <= 0.6 <= hi)
    assert 0.85 <= np.mean(covered) <= 1.0


def test_instance_bootstrap_covers_when_instances_differ_and_trial_bootstrap_does_not():
    # half the instances succeed 20 % of the time, half always: population rate 0.6, trials within an
    # instance are correlated, so only the instance-level interval has about its nominal coverage
    inst_cover, trial_cover = [], []
    for k in range(150):
        rng = np.random.default_rng(1000 + k)
        rates = np.where(rng.random(20) < 0.5, 0.2, 1.0)
        inst, s = _bernoulli_trials(rng, rates, 10)
        _, lo, hi = bootstrap_rate(inst, s, n_boot=500, seed=k)
        inst_cover.append(lo <= 0.6 <= hi)
        _, lo, hi = bootstrap_rate(np.arange(len(s)), s, n_boot=500, seed=k)
        trial_cover.append(lo <= 0.6 <= hi)
    assert np.mean(inst_cover) >= 0.85
    assert np.mean(trial_cover) <= 0.75


def test_all_successes_give_a_hundred_percent_interval():
    instances = np.repeat([f"drill_t{i:02d}" for i in range(10)], 3)
    assert bootstrap_rate(instances, np.ones(30, bool)) == (1.0, 1.0, 1.0)
    assert bootstrap_rate(instances, np.zeros(30, bool)) == (0.0, 0.0, 0.0)


def test_resampling_is_by_instance():
    instances = ["a"] * 10 + ["b"] * 10
    successes = [True] * 10 + [False] * 10
    rate, low, high = bootstrap_rate(instances, successes)
    assert rate == 0.5
    assert low <= 0.2 and high >= 0.8  # draws {a, a}, {a, b}, {b, b}: 1, 0.5, 0
    # the same outcomes treated as 20 independent trials: a much narrower binomial-like interval
    _, t_low, t_high = bootstrap_rate(np.arange(20), successes)
    assert 0.2 < t_low < 0.5 < t_high < 0.8
    assert (high - low) > 2 * (t_high - t_low)


def test_edge_cases():
    rate, low, high = bootstrap_rate([], [])
    assert math.isnan(rate) and math.isnan(low) and math.isnan(high)
    assert bootstrap_rate(["x"] * 3, [True, False, True]) == (2 / 3, 2 / 3, 2 / 3)
    with pytest.raises(InputError):
        bootstrap_rate(["x", "y"], [True])
    with pytest.raises(InputError):
        bootstrap_rate(["x"], [0.5])
    with pytest.raises(InputError):
        bootstrap_rate(["x"], [True], level=1.5)
    with pytest.raises(InputError):
        bootstrap_rate(["x"], [True], n_boot=0)


def test_strata_keep_their_number_of_instances():
    # one instance per category: within-category resampling never changes the sample -> degenerate interval
    instances = ["d0"] * 5 + ["s0"] * 5
    successes = [True] * 5 + [False] * 5
    strata = ["drill"] * 5 + ["spray_bottle"] * 5
    assert bootstrap_rate(instances, successes, strata=strata) == (0.5, 0.5, 0.5)
    assert bootstrap_rate(instances, successes)[1:] == (0.0, 1.0)
    # the same instance name in two strata is two instances
    assert bootstrap_rate(["x"] * 10, successes, strata=strata) == (0.5, 0.5, 0.5)


def test_deterministic_and_independent_of_trial_order():
    rng = np.random.default_rng(3)
    instances, successes = _bernoulli_trials(rng, rng.random(15), 4)
    names = np.array([f"i{k}" for k in instances])
    first = bootstrap_rate(names, successes, seed=5)
    assert bootstrap_rate(names, successes, seed=5) == first
    perm = rng.permutation(len(names))
    assert bootstrap_rate(names[perm], successes[perm], seed=5) == first
    assert bootstrap_rate(names, successes, seed=6) != first
    b = rng.random(len(names)) < 0.3
    d = paired_bootstrap_difference(names, successes, b, seed=5)
    assert paired_bootstrap_difference(names[perm], successes[perm], b[perm], seed=5) == d


def test_paired_difference_of_identical_outcomes_is_exactly_zero():
    rng = np.random.default_rng(11)
    instances, a = _bernoulli_trials(rng, rng.random(12), 3)
    assert paired_bootstrap_difference(instances, a, a.copy()) == (0.0, 0.0, 0.0)
    r = paired_bootstrap(instances, a, a)
    assert r.frac_le_zero == 1.0 and not r.excludes_zero and r.trials == 36 and r.instances == 12


def test_known_positive_difference_excludes_zero():
    rng = np.random.default_rng(12)
    instances = np.repeat(np.arange(20), 5)
    u = rng.random(len(instances))
    a, b = u < 0.8, u < 0.3  # same trials, a succeeds whenever b does (paired)
    r = paired_bootstrap(instances, a, b)
    assert r.diff == pytest.approx(a.mean() - b.mean()) and r.diff > 0.3
    assert r.low > 0.0 and r.excludes_zero and r.frac_le_zero == 0.0
    assert r.low <= 0.5 <= r.high
    diff, low, high = paired_bootstrap_difference(instances, b, a)
    assert high < 0 and diff == -r.diff
    with pytest.raises(InputError):
        paired_bootstrap(instances, a, b[:-1])
    empty = paired_bootstrap([], [], [])
    assert empty.trials == 0 and math.isnan(empty.diff)


def _rec(instance, trial, method, functional, view="single", physics="default", category="drill"):
    return {"split": "test", "category": category, "instance": instance, "trial": trial, "view": view,
            "method": method, "physics": physics, "grasp": functional, "functional": functional}


def test_pair_records_aligns_by_key_and_counts_the_dropped():
    a = [_rec("d1", t, "latent", t % 2 == 0) for t in range(4)] + [_rec("d2", 0, "latent", True)]
    b = [_rec("d1", t, "rigid", False) for t in (3, 2, 1, 0)] + [_rec("d3", 0, "rigid", True),
                                                                 _rec("d3", 1, "rigid", True)]
    p = pair_records(a, b)
    assert p.key == PAIR_KEY and len(p) == 4
    assert (p.unpaired_a, p.unpaired_b, p.unpaired) == (1, 2, 3)
    assert [r["trial"] for r in p.a] == [r["trial"] for r in p.b] == [0, 1, 2, 3]
    fa, fb = p.outcomes("functional")
    assert fa.tolist() == [True, False, True, False] and not fb.any()
    assert p.field("instance").tolist() == ["d1"] * 4
    assert pair_records(a[::-1], b[::-1]).keys == p.keys  # order of the records does not matter
    # another physics or view is another trial
    assert len(pair_records(a, [_rec("d1", 0, "rigid", True, physics="friction_0.5")])) == 0
    # pairing across physics settings: key without physics
    q = pair_records(a, [_rec("d1", 0, "latent", False, physics="friction_0.5")],
                     key=("split", "category", "instance", "trial", "view", "method"))
    assert len(q) == 1 and q.unpaired_a == 4


def test_pair_records_refuses_duplicates_and_missing_fields():
    a = [_rec("d1", 0, "latent", True), _rec("d1", 0, "latent", False)]
    with pytest.raises(InputError, match="same key"):
        pair_records(a, [])
    bad = {k: v for k, v in _rec("d1", 0, "latent", True).items() if k != "view"}
    with pytest.raises(InputError, match="'view'"):
        pair_records([bad], [])
