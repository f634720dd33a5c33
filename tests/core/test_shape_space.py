"""Shape space: PCA-EM, encode/decode, canonical selection, files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from catgrasp_drake.core.shape_space import ShapeSpace, build_shape_space, pca_em
from catgrasp_drake.errors import InputError, ModelFileError

from .test_synthetic_shapes import family

BETA = 0.02


@pytest.fixture(scope="module")
def instances():
    return family(np.random.default_rng(0), 6, n=150)


@pytest.fixture(scope="module")
def space(instances):
    return build_shape_space(instances, canonical_index=0, beta=BETA, lam=3.0, variance=1.0)


def test_pca_em_matches_svd():
    rng = np.random.default_rng(1)
    # data with a clear spectrum: 4 strong directions in 60 dims, 12 samples
    basis = np.linalg.qr(rng.normal(size=(60, 4)))[0]
    Y = (rng.normal(size=(12, 4)) * [5.0, 3.0, 2.0, 1.0]) @ basis.T + 0.01 * rng.normal(size=(12, 60))
    res = pca_em(Y, 3)
    Yc = Y - Y.mean(0)
    _, S, Vt = np.linalg.svd(Yc, full_matrices=False)
    assert res.converged
    assert np.allclose(res.variances, S[:3] ** 2 / 11, rtol=1e-6)
    for k in range(3):
        assert abs(abs(res.components[k] @ Vt[k]) - 1.0) < 1e-6  # same axes up to sign
    assert np.allclose(res.components @ res.components.T, np.eye(3), atol=1e-10)


def test_encode_decode_round_trip(space, instances):
    K = len(instances)
    assert space.q == K - 1 and space.latent_train.shape == (K, K - 1)
    # training latents are whitened: unit variance per component
    assert np.allclose(space.latent_train.var(axis=0, ddof=1), 1.0)
    # with all the variance kept, every training W is reproduced exactly
    assert np.allclose(space.decode(space.latent_train), space.W_train, atol=1e-12)
    assert np.allclose(space.encode(space.W_train), space.latent_train, atol=1e-9)
    x = np.random.default_rng(2).normal(size=space.q)
    assert np.allclose(space.encode(space.decode(x)), x, atol=1e-10)
    # the canonical instance has W = 0
    assert np.allclose(space.W_train[0], 0.0)


def test_deform_is_linear_and_matches_the_field(space):
    x = np.random.default_rng(3).normal(size=space.q)
    C = space.canonical
    direct = C + space.kernel @ space.decode(x)
    assert np.allclose(space.deform(x), direct, atol=1e-12)
    assert np.allclose(space.deform(x, points=C), direct, atol=1e-12)
    extra = C[:5] + 0.01  # points added after training
    assert space.deform(x, points=extra).shape == (5, 3)


def test_variance_rule_chooses_q(instances):
    s95 = build_shape_space(instances, canonical_index=0, beta=BETA, variance=0.95)
    s50 = build_shape_space(instances, canonical_index=0, beta=BETA, variance=0.5)
    r = s95.explained_variance_ratio
    assert r.sum() >= 0.95 - 1e-9 and (s95.q == 1 or r[:-1].sum() < 0.95)
    assert s50.q <= s95.q
    assert build_shape_space(instances, canonical_index=0, beta=BETA, max_q=1).q == 1


def test_auto_canonical_is_the_lowest_reconstruction_energy(instances):
    sub = instances[:4]
    sp = build_shape_space(sub, canonical_index="auto", beta=BETA, variance=0.6)
    energies = {int(k): v for k, v in sp.meta["canonical_energies"].items()}
    assert set(energies) == {0, 1, 2, 3}
    assert sp.canonical_index == min(energies, key=energies.get)
    assert np.array_equal(sp.canonical, sub[sp.canonical_index])


def test_save_load_round_trip_and_errors(space, tmp_path):
    path = tmp_path / "drill_space.npz"
    space.save(path)
    back = ShapeSpace.load(path)
    for name in ("canonical", "W_mean", "components", "eigenvalues", "latent_train", "W_train", "feature_std"):
        assert np.array_equal(getattr(back, name), getattr(space, name))
    assert back.beta == space.beta and back.lam == space.lam and back.q == space.q
    x = space.latent_train[1]
    assert np.allclose(back.deform(x), space.deform(x))
    # corrupt: flip bytes in the middle of the file
    bad = tmp_path / "bad.npz"
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    bad.write_bytes(bytes(data))
    with pytest.raises(ModelFileError):
        ShapeSpace.load(bad)
    with pytest.raises(ModelFileError, match="not found"):
        ShapeSpace.load(tmp_path / "missing.npz")
    # another kind of file
    from catgrasp_drake.core.fileio import save_arrays

    other = tmp_path / "other.npz"
    save_arrays(other, {"a": np.zeros(3)}, kind="catgrasp.something_else", version=1)
    with pytest.raises(ModelFileError, match="expected 'catgrasp.shape_space'"):
        ShapeSpace.load(other)
    # version mismatch
    save_arrays(other, {"a": np.zeros(3)}, kind="catgrasp.shape_space", version=99)
    with pytest.raises(ModelFileError, match="version"):
        ShapeSpace.load(other)


def test_bad_inputs(instances):
    with pytest.raises(InputError, match="at least 2"):
        build_shape_space(instances[:1])
    with pytest.raises(InputError, match="empty"):
        build_shape_space([instances[0], np.zeros((0, 3))])
    with pytest.raises(InputError, match="NaN"):
        build_shape_space([instances[0], np.full((10, 3), np.nan)])
    with pytest.raises(InputError, match="out of range"):
        build_shape_space(instances[:2], canonical_index=5)
    with pytest.raises(InputError, match="no shape variation"):
        build_shape_space([instances[0], instances[0].copy()], canonical_index=0)
    with pytest.raises(InputError, match="millimetres"):
        build_shape_space([instances[0] * 1000, instances[1] * 1000])
    with pytest.raises(InputError):
        pca_em(np.ones((1, 5)), 1)


def test_to_from_arrays_for_embedding(space):
    arrays, meta = space.to_arrays()
    back = ShapeSpace.from_arrays(arrays, json.loads(json.dumps(meta)))
    assert np.array_equal(back.components, space.components) and back.q == space.q
    bad = dict(arrays, eigenvalues=arrays["eigenvalues"][:-1])
    with pytest.raises(ModelFileError, match="inconsistent"):
        ShapeSpace.from_arrays(bad, meta, source="model.npz")
    with pytest.raises(ModelFileError, match="lacks"):
        ShapeSpace.from_arrays({}, meta)
