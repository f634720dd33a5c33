"""Results do not depend on the number of cores: CPD and inference, bit for bit, with 1-4 threads.

The E-step is split into column blocks whose partial sums are added; the
block layout depends on the problem size only (``cpd.THREADED_BLOCKS``), never
on ``os.cpu_count()``, so a model trained on a 2-core CI machine equals one
trained on a laptop. (With one block per core, results differed by ~1e-10.)
"""

from __future__ import annotations

import numpy as np
import pytest

from catgrasp_drake.core import cpd, inference
from catgrasp_drake.core.inference import infer_latent_pose
from catgrasp_drake.core.shape_space import build_shape_space
from catgrasp_drake.core.visibility import camera_on_sphere_position, hidden_point_removal
from tests.core.test_synthetic_shapes import family


def _run_with_threads(monkeypatch, n, fn):
    monkeypatch.setattr(cpd, "n_threads", lambda: n)
    monkeypatch.setattr(inference, "n_threads", lambda: n)
    return fn()


def test_nonrigid_cpd_is_identical_for_any_thread_count(monkeypatch):
    rng = np.random.default_rng(7)
    source = rng.normal(size=(600, 3)) * 0.05
    target = source + 0.01 * np.sin(10 * source) + rng.normal(size=source.shape) * 1e-3
    assert len(source) * len(target) >= 200_000  # big enough to be threaded

    def run():
        r = cpd.nonrigid_cpd(source, target, beta=0.05, lam=3.0, max_iter=30)
        return r.W, r.sigma2

    W1, s1 = _run_with_threads(monkeypatch, 1, run)
    for n in (2, 3, 4):
        W, s = _run_with_threads(monkeypatch, n, run)
        assert np.array_equal(W, W1) and s == s1, f"{n} threads differ from 1"


@pytest.mark.parametrize("n_threads", [2, 3, 4])
def test_inference_is_identical_for_any_thread_count(monkeypatch, n_threads):
    space = build_shape_space(family(np.random.default_rng(10), 6, n=250), canonical_index=0, beta=0.02,
                              lam=3.0, variance=0.95)
    T = space.deform(0.5 * space.latent_train[2]) + [0.3, -0.1, 0.0]
    cam = camera_on_sphere_position(T.mean(0), 0.6, np.radians(45), np.radians(30))
    observed = T[hidden_point_removal(T, cam)]

    def run():
        r = infer_latent_pose(space, observed, camera_position=cam, yaw_candidates=4)
        return np.concatenate([np.ravel(r.x), np.ravel(r.R), np.ravel(r.t), [r.s]])

    ref = _run_with_threads(monkeypatch, 1, run)
    assert np.array_equal(_run_with_threads(monkeypatch, n_threads, run), ref)
