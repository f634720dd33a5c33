"""Bootstrap intervals for the benchmark's success rates (numpy only).

The trials of one instance are not independent (same shape, same model
errors), so every interval here resamples *instances* with replacement -- a
drawn instance brings all its trials along -- and the statistic is the pooled
rate of the resample (successes / trials). With ``strata`` (e.g. the category
of each trial) the instances are resampled within each stratum, keeping the
strata's sizes (a stratified bootstrap, for cells that pool categories).
Intervals are percentile intervals.

Everything is a deterministic function of the inputs and ``seed``: clusters
are ordered by name (not by the order of the trials), the draws come from
``np.random.default_rng(seed)`` and the resampled sums are integer sums, so the
same trials give the same interval bit for bit, whatever their order.

Edge cases: no trials -> ``(nan, nan, nan)``; a single instance (per stratum)
-> the degenerate interval ``(rate, rate, rate)``; all successes -> ``(1, 1, 1)``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np

from catgrasp_drake.errors import InputError

N_BOOT = 2000
SEED = 0
LEVEL = 0.95
#: Fields that identify one trial across methods (same instance, placement, view and physics).
PAIR_KEY = ("split", "category", "instance", "trial", "view", "physics")


# ----------------------------------------------------------------------------- internals
def _check(n_boot: int, level: float) -> None:
    if int(n_boot) != n_boot or n_boot < 1:
        raise InputError(f"n_boot: expected a positive integer, got {n_boot!r}")
    if not 0.0 < float(level) < 1.0:
        raise InputError(f"level: expected a confidence level in (0, 1), got {level!r}")


def _labels(values, n: int, name: str) -> np.ndarray:
    a = np.asarray(values)
    if a.ndim != 1 or len(a) != n:
        raise InputError(f"{name}: expected {n} labels (one per trial), got shape {a.shape}")
    return a.astype(str)


def _outcomes(values, name: str) -> np.ndarray:
    a = np.asarray(values)
    if a.ndim != 1:
        raise InputError(f"{name}: expected a 1-D array of trial outcomes, got shape {a.shape}")
    if a.dtype != bool:
        if a.size and not np.all((a == 0) | (a == 1)):
            raise InputError(f"{name}: trial outcomes must be booleans or 0/1")
        a = a.astype(bool)
    return a


class _Clusters:
    """Trials grouped into (stratum, instance) clusters, ordered by name; bootstrap weights per cluster."""

    def __init__(self, instances, strata, n: int):
        inst = _labels(instances, n, "instances")
        strat = np.zeros(n, dtype=str) if strata is None else _labels(strata, n, "strata")
        # clusters are (stratum, instance) pairs, numbered in sorted order: independent of the trials' order
        inst_names, inst_code = np.unique(inst, return_inverse=True)
        strat_names, strat_code = np.unique(strat, return_inverse=True)
        codes, self.index = np.unique(strat_code.ravel() * len(inst_names) + inst_code.ravel(), return_inverse=True)
        self.index = self.index.ravel()
        self.count = len(codes)
        cluster_stratum = codes // len(inst_names)
        self.strata = [np.flatnonzero(cluster_stratum == s) for s in range(len(strat_names))]
        self.strata = [m for m in self.strata if len(m)]

    def sums(self, values: np.ndarray) -> np.ndarray:
        """Per-cluster integer sums of a per-trial 0/1 (or count) vector."""
        return np.bincount(self.index, weights=None if values is None else values.astype(np.int64),
                           minlength=self.count).astype(np.int64)

    def weights(self, n_boot: int, seed: int) -> np.ndarray:
        """``(n_boot, clusters)`` integer counts: how often each cluster is drawn in each resample."""
        rng = np.random.default_rng(seed)
        w = np.zeros((n_boot, self.count), dtype=np.int64)
        rows = np.arange(n_boot)[:, None]
        for members in self.strata:  # strata in sorted order; each keeps its number of instances
            draws = rng.integers(0, len(members), size=(n_boot, len(members)))
            counts = np.zeros((n_boot, len(members)), dtype=np.int64)
            np.add.at(counts, (rows, draws), 1)
            w[:, members] = counts
        return w

    @property
    def degenerate(self) -> bool:
        return all(len(m) == 1 for m in self.strata)


def _interval(values: np.ndarray, level: float) -> tuple[float, float]:
    alpha = (1.0 - float(level)) / 2.0
    lo, hi = np.quantile(values, [alpha, 1.0 - alpha])
    return float(lo), float(hi)


# ----------------------------------------------------------------------------- rates
def bootstrap_rate(instances, successes, *, strata=None, n_boot: int = N_BOOT, seed: int = SEED,
                   level: float = LEVEL) -> tuple[float, float, float]:
    """``(rate, low, high)``: pooled success rate with an instance-level percentile bootstrap interval.

    ``instances``: one label per trial (the resampling unit); ``successes``: one
    bool (or 0/1) per trial; ``strata``: optional label per trial, instances are
    then resampled within each stratum (an instance is identified by its
    stratum and its label).
    """
    _check(n_boot, level)
    s = _outcomes(successes, "successes")
    if len(s) == 0:
        return float("nan"), float("nan"), float("nan")
    clusters = _Clusters(instances, strata, len(s))
    k, n = clusters.sums(s), clusters.sums(None)
    rate = float(k.sum() / n.sum())
    if clusters.degenerate or k.sum() in (0, n.sum()):  # every resample is the sample itself / all 0 / all 1
        return rate, rate, rate
    w = clusters.weights(int(n_boot), seed)
    low, high = _interval((w @ k) / (w @ n), level)
    return rate, low, high


@dataclass(frozen=True)
class PairedBootstrap:
    """The result of :func:`paired_bootstrap`: pooled rates of a and b, their difference and its interval."""

    rate_a: float
    rate_b: float
    diff: float
    low: float
    high: float
    frac_le_zero: float  # fraction of the bootstrap draws with diff <= 0 (a one-sided bootstrap "p-value")
    trials: int
    instances: int

    @property
    def excludes_zero(self) -> bool:
        return bool(self.low > 0.0 or self.high < 0.0)


def paired_bootstrap(instances, a, b, *, strata=None, n_boot: int = N_BOOT, seed: int = SEED,
                     level: float = LEVEL) -> PairedBootstrap:
    """Pooled rate of ``a`` minus pooled rate of ``b`` on the same trials, resampling instances.

    ``a`` and ``b`` are the outcomes of two methods on the SAME trials, aligned
    by the caller (:func:`pair_records`): element i of both is the same
    instance, placement, view and physics. The same instance draws are applied
    to both, so the interval reflects the paired design.
    """
    _check(n_boot, level)
    a, b = _outcomes(a, "a"), _outcomes(b, "b")
    if len(a) != len(b):
        raise InputError(f"a and b: expected the same trials, got {len(a)} and {len(b)} outcomes")
    nan = float("nan")
    if len(a) == 0:
        return PairedBootstrap(nan, nan, nan, nan, nan, nan, 0, 0)
    clusters = _Clusters(instances, strata, len(a))
    ka, kb, n = clusters.sums(a), clusters.sums(b), clusters.sums(None)
    total = n.sum()
    diff = float((ka.sum() - kb.sum()) / total)
    if clusters.degenerate or np.array_equal(ka, kb):  # every draw gives the same difference
        frac = 1.0 if diff <= 0 else 0.0
        return PairedBootstrap(float(ka.sum() / total), float(kb.sum() / total), diff, diff, diff, frac,
                               len(a), clusters.count)
    w = clusters.weights(int(n_boot), seed)
    draws = (w @ (ka - kb)) / (w @ n)
    low, high = _interval(draws, level)
    return PairedBootstrap(float(ka.sum() / total), float(kb.sum() / total), diff, low, high,
                           float(np.mean(draws <= 0.0)), len(a), clusters.count)


def paired_bootstrap_difference(instances, a, b, *, strata=None, n_boot: int = N_BOOT, seed: int = SEED,
                                level: float = LEVEL) -> tuple[float, float, float]:
    """``(diff, low, high)`` of :func:`paired_bootstrap` (pooled rate of a minus b; nan when no trials)."""
    r = paired_bootstrap(instances, a, b, strata=strata, n_boot=n_boot, seed=seed, level=level)
    return r.diff, r.low, r.high


# ----------------------------------------------------------------------------- pairing records
@dataclass(frozen=True)
class PairedTrials:
    """Two sets of trial records aligned by key: ``a[i]`` and ``b[i]`` are the same trial (``keys[i]``)."""

    key: tuple[str, ...]
    keys: list[tuple]
    a: list[dict]
    b: list[dict]
    unpaired_a: int  # records of a without a partner in b (dropped)
    unpaired_b: int

    @property
    def unpaired(self) -> int:
        return self.unpaired_a + self.unpaired_b

    def field(self, name: str) -> np.ndarray:
        """A key field per paired trial (e.g. ``"instance"``, ``"category"``) as a string array."""
        i = self.key.index(name)
        return np.array([str(k[i]) for k in self.keys], dtype=str)

    def outcomes(self, name: str = "functional") -> tuple[np.ndarray, np.ndarray]:
        """``(a, b)`` boolean arrays of one outcome field of the paired trials."""
        return (np.array([bool(r[name]) for r in self.a], dtype=bool),
                np.array([bool(r[name]) for r in self.b], dtype=bool))

    def __len__(self) -> int:
        return len(self.keys)


def _key_of(record: dict, key: Sequence[str], side: str) -> tuple:
    try:
        return tuple(record[k] for k in key)
    except KeyError as e:
        raise InputError(f"{side}: a trial record has no {e.args[0]!r} field (pairing key {', '.join(key)})") from None
    except TypeError:
        raise InputError(f"{side}: trial records must be dicts, got {type(record).__name__}") from None


def _index(records: Iterable[dict], key: Sequence[str], side: str) -> dict:
    out: dict = {}
    for r in records:
        k = _key_of(r, key, side)
        if k in out:
            raise InputError(f"{side}: two trial records with the same key {dict(zip(key, k))}")
        out[k] = r
    return out


def pair_records(records_a: Iterable[dict], records_b: Iterable[dict], *,
                 key: Sequence[str] = PAIR_KEY) -> PairedTrials:
    """Align two methods' records by ``key`` (default :data:`PAIR_KEY`); unpaired trials are dropped and counted.

    The pairs are sorted by key, so the result does not depend on the records' order.
    Raises InputError if a record lacks a key field or one side holds the same key twice.
    """
    key = tuple(key)
    ia, ib = _index(records_a, key, "a"), _index(records_b, key, "b")
    common = sorted(set(ia) & set(ib), key=lambda k: json.dumps(k, sort_keys=True, default=str))
    return PairedTrials(key, common, [ia[k] for k in common], [ib[k] for k in common],
                        len(ia) - len(common), len(ib) - len(common))
