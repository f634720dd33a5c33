"""Fuzzing the shape space (core/shape_space.py): fit, PCA-EM, latent <-> W, and its files."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from catgrasp_drake.core.shape_space import ShapeSpace, build_shape_space, pca_em

from .harness import attempt, finite_array
from .strategies import (
    CORRUPTIONS,
    MUST_REJECT,
    choice,
    clouds,
    corrupt_bytes,
    latents,
    number,
    options,
    scaled,
    seeds,
)


def _check_space(K):
    def check(space):
        assert isinstance(space, ShapeSpace)
        assert 1 <= space.q <= K - 1
        for a in (space.canonical, space.W_mean, space.components, space.eigenvalues, space.latent_train):
            finite_array()(a)
        assert np.all(space.eigenvalues > 0)
        finite_array((space.n_points, 3))(space.deform(np.zeros(space.q)))
    return check


@scaled(50)
@given(instances=st.lists(clouds(max_n=25, valid_weight=40), min_size=0, max_size=4),
       opts=options({
           "canonical_index": choice([0, 1, None, "auto"], [("out_of_range", 7), ("negative", -9), ("string", "first"),
                                                             ("nan", float("nan")), ("fraction", 0.5)]),
           "variance": number(st.floats(0.5, 1.0)),
           "max_q": choice([None, 1, 2], [("zero", 0), ("string", "two"), ("negative", -2), ("nan", float("nan"))]),
           "standardize": choice(["global", "feature"], [("string", "none"), ("none", None)]),
           "beta": number(st.floats(0.01, 0.1)),
           "lam": number(st.floats(0.5, 10.0)),
       }))
def test_build_shape_space(instances, opts):
    label = f"instances:[{','.join(i[0] for i in instances)}]" + "".join(
        f" {k}={v[0]}" for k, v in opts.items() if v[0] != "valid")
    expect = "reject" if len(instances) < 2 or any(i[0] in MUST_REJECT for i in instances) else None
    attempt("shape_space.build_shape_space", label, build_shape_space, [i[1] for i in instances], max_iter=10,
            check=_check_space(len(instances)), expect=expect, **{k: v[1] for k, v in opts.items()})


@st.composite
def _data_matrices(draw):
    rng = np.random.default_rng(draw(seeds))
    K, p = draw(st.sampled_from([4, 5, 6, 3, 2, 6, 0, 1])), draw(st.sampled_from([12, 6, 9, 2, 1, 0]))
    kind = draw(st.sampled_from(["valid", "valid", "rank_one", "zeros", "nan", "huge", "wrong_ndim", "string",
                                 "duplicate_rows"]))
    Y = rng.normal(size=(K, p))
    if kind == "rank_one":
        Y = np.outer(rng.normal(size=K), rng.normal(size=p))
    elif kind == "zeros":
        Y = np.zeros((K, p))
    elif kind == "nan" and Y.size:
        Y[0, 0] = np.nan
    elif kind == "huge":
        Y = Y * 1e200
    elif kind == "wrong_ndim":
        Y = Y.reshape(-1)
    elif kind == "string":
        Y = "matrix"
    elif kind == "duplicate_rows" and K:
        Y = np.repeat(Y[:1], K, axis=0)
    return f"{kind}({K}x{p})", Y


@scaled(50)
@given(Y=_data_matrices(), opts=options({"q": number(st.integers(1, 3)), "max_iter": number(st.integers(1, 50)),
                                         "tol": number(st.floats(0.0, 1e-6))}, max_valid=3))
def test_pca_em(Y, opts):
    opts.setdefault("q", ("valid", 1))
    label = f"Y:{Y[0]}" + "".join(f" {k}={v[0]}" for k, v in opts.items() if v[0] != "valid")
    kwargs = {k: v[1] for k, v in opts.items() if k != "q"}

    def check(r):
        finite_array(ndim=2)(r.components)
        finite_array(ndim=1)(r.variances)
        assert np.all(r.variances >= 0)

    attempt("shape_space.pca_em", label, pca_em, Y[1], opts["q"][1], check=check, **kwargs)


@scaled(50)
@given(x=st.data())
def test_latent_decode_encode_deform(small_space, x):
    space = small_space
    label, v = x.draw(latents(space.q))
    attempt("ShapeSpace.decode", f"x:{label}", space.decode, v, check=finite_array())
    attempt("ShapeSpace.deform", f"x:{label}", space.deform, v, check=finite_array((space.n_points, 3)))
    W = np.asarray(v, dtype=float) if label in ("valid", "zero", "large", "int") else v
    if label in ("valid", "zero", "large"):
        W = space.decode(W)
    attempt("ShapeSpace.encode", f"W:{label}", space.encode, W, check=finite_array())


# ----------------------------------------------------------------------------- files

@pytest.fixture(scope="module")
def space_bytes(small_space, tmp_path_factory):
    path = tmp_path_factory.mktemp("space") / "space.npz"
    small_space.save(path)
    return path.read_bytes()


def _forge(space, how, rng):
    """A shape-space file damaged at the array level (checksum recomputed, so only validation can catch it)."""
    from catgrasp_drake.core.fileio import _arrays_checksum

    arrays, meta = space.to_arrays()
    arrays = {k: np.array(v) for k, v in arrays.items()}
    kind, version = "catgrasp.shape_space", 1
    if how == "other_version":
        version = int(rng.choice([0, 2, 99]))
    elif how == "other_kind":
        kind = "catgrasp.category_model"
    elif how == "missing_array":
        arrays.pop(str(rng.choice(sorted(arrays))))
    elif how == "nan_array":
        arrays["components"][0, 0] = np.nan
    elif how == "wrong_shape":
        arrays["canonical"] = arrays["canonical"][:-1]
    elif how == "negative_variance":
        arrays["eigenvalues"][-1] = -1.0
    elif how == "string_meta":
        meta["q"] = "many"
    elif how == "missing_meta":
        meta.pop("beta")
    elif how == "bad_beta":
        meta["beta"] = float(rng.choice([0.0, -1.0, 1e300]))
    elif how == "int_arrays":
        arrays["canonical"] = arrays["canonical"].astype(np.int64)
    elif how == "complex_array":
        arrays["W_mean"] = arrays["W_mean"].astype(np.complex128)
    header = {"format": kind, "format_version": version, "sha256": _arrays_checksum(arrays), "meta": meta}
    from .strategies import npz_with_header

    return npz_with_header(arrays, header)


FORGERIES = ("other_version", "other_kind", "missing_array", "nan_array", "wrong_shape", "negative_variance",
             "string_meta", "missing_meta", "bad_beta", "int_arrays", "complex_array")


@scaled(50)
@given(how=st.sampled_from(CORRUPTIONS + FORGERIES + ("missing", "directory", "valid")), seed=seeds)
def test_shape_space_load(small_space, space_bytes, tmp_path_factory, how, seed):
    rng = np.random.default_rng(seed)
    path = tmp_path_factory.mktemp("load") / "space.npz"
    if how in CORRUPTIONS:
        path.write_bytes(corrupt_bytes(space_bytes, rng, how))
    elif how in FORGERIES:
        path.write_bytes(_forge(small_space, how, rng))
    elif how == "directory":
        path.mkdir()
    elif how == "valid":
        path.write_bytes(space_bytes)

    def check(s):
        assert isinstance(s, ShapeSpace)
        if how == "valid":
            assert s.q == small_space.q and np.array_equal(s.canonical, small_space.canonical)

    expect = "result" if how == "valid" else ("reject" if how not in ("flipped", "zeroed", "int_arrays") else None)
    attempt("ShapeSpace.load", f"file:{how}", ShapeSpace.load, path, check=check, expect=expect)


def test_meta_is_json(small_space):
    """The forged headers above use the same JSON meta as a real file (guards the forgery helper)."""
    _, meta = small_space.to_arrays()
    json.dumps(meta)
