"""Hypothesis profiles of the fuzz tests and the optional recording of every generated call.

Profiles (``HYPOTHESIS_PROFILE``):

* ``ci`` (default): deterministic (``derandomize=True``, no example database,
  so no ``.hypothesis`` directory), ~1000+ generated calls over all entry
  points, well under 90 s on a 2-core machine.
* ``nightly``: 10x the examples, randomised (new inputs every run), for a
  manual or scheduled run: ``HYPOTHESIS_PROFILE=nightly pytest tests/reliability``.

The per-example deadline (10 s; a valid inference takes ~0.2 s) is generous
for a loaded machine yet flags anything hang-like; a single call is also
interrupted after ``harness.HANG_S`` (30 s) so a real hang cannot stall CI.

``CATGRASP_FUZZ_RECORD=<path>``: write one JSON line per generated call
(entry point, input class, outcome, seconds) at the end of the session
(used by ``benchmarks/bench_fuzz.py``).
"""

from __future__ import annotations

import json
import os
from datetime import timedelta

from hypothesis import HealthCheck, settings

from .harness import CI_EXAMPLES, NIGHTLY_FACTOR, RECORDS

_common = dict(
    database=None,
    deadline=timedelta(seconds=10),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much,
                           HealthCheck.function_scoped_fixture],
    print_blob=True,
)
settings.register_profile("ci", max_examples=CI_EXAMPLES, derandomize=True, **_common)
settings.register_profile("nightly", max_examples=NIGHTLY_FACTOR * CI_EXAMPLES, derandomize=False, **_common)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def pytest_sessionfinish(session, exitstatus):
    path = os.environ.get("CATGRASP_FUZZ_RECORD")
    if path:
        with open(path, "w") as f:
            for r in RECORDS:
                f.write(json.dumps(r) + "\n")


# ----------------------------------------------------------------------------- shared fixtures
import numpy as np  # noqa: E402
import pytest  # noqa: E402

REPO = __import__("pathlib").Path(__file__).resolve().parents[2]
TRAINED = {c: REPO / "models" / "trained" / f"{c}.npz" for c in ("drill", "spray_bottle", "mug")}


@pytest.fixture(scope="session")
def small_space():
    """A small synthetic shape space (6 blobs of 80 points; q <= 5): fast to fit to."""
    from catgrasp_drake.core.shape_space import build_shape_space

    from ..core.test_synthetic_shapes import family

    return build_shape_space(family(np.random.default_rng(7), 6, n=80), canonical_index=0, beta=0.03, lam=3.0)


@pytest.fixture(scope="session")
def trained_models():
    """The committed trained models (read-only), loaded once."""
    from catgrasp_drake.category_model import CategoryModel

    missing = [str(p) for p in TRAINED.values() if not p.is_file()]
    if missing:
        pytest.skip(f"trained models missing: {missing}")
    return {c: CategoryModel.load(p) for c, p in TRAINED.items()}
