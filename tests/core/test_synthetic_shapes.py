"""Seeded synthetic shapes shared by the core tests (numpy only), and a sanity test of them."""

from __future__ import annotations

import numpy as np


def fibonacci_sphere(n: int) -> np.ndarray:
    """n nearly uniform unit vectors (deterministic)."""
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5**0.5) * i
    return np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=1)


def blob(params, n: int = 300) -> np.ndarray:
    """A drill-sized smooth closed surface: ellipsoid with axes (a, b, c) m, bent by ``bend`` and
    with a bulge ``bulge`` on +y; base near z = 0."""
    a, b, c, bend, bulge = params
    u = fibonacci_sphere(n)
    p = u * np.array([a, b, c])
    p[:, 1] += bend * (p[:, 2] / c) ** 2
    p[:, 1] += bulge * np.exp(-((u[:, 1] - 1.0) ** 2) / 0.3) * np.sign(u[:, 1] + 1e-9)
    p[:, 2] += c
    return p


def family(rng, k: int, n: int = 300):
    """k instances of :func:`blob` with random parameters."""
    out = []
    for _ in range(k):
        params = (
            rng.uniform(0.025, 0.04),
            rng.uniform(0.05, 0.08),
            rng.uniform(0.07, 0.11),
            rng.uniform(-0.02, 0.02),
            rng.uniform(0.0, 0.02),
        )
        out.append(blob(params, n))
    return out


def test_synthetic_shapes_are_deterministic_and_drill_sized():
    a = family(np.random.default_rng(0), 2, n=100)
    b = family(np.random.default_rng(0), 2, n=100)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    ext = a[0].max(0) - a[0].min(0)
    assert np.all(ext > 0.04) and np.all(ext < 0.3)
